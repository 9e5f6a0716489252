"""``python -m femrub``: the command line (same as the ``femrub`` script)."""

from .app.cli import main

raise SystemExit(main())
