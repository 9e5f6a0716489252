"""Reading a run's results back: a results folder or a saved ``.npz`` as :class:`Results`."""

from __future__ import annotations

from pathlib import Path

from .results import Results

#: the history file of a results folder (``femrub run``, :func:`femrub.app.run_scene`)
HISTORY = "history.npz"


def load_results(path) -> Results:
    """The :class:`~femrub.output.results.Results` of a run, read back from disk.

    Parameters
    ----------
    path : str or pathlib.Path
        A results folder (``femrub run SCENE -o DIR``, :func:`femrub.app.run_scene`,
        :func:`femrub.output.run_folder.run_to_folder`: its ``history.npz`` is read) or an
        ``.npz`` file written by :meth:`Results.save_npz`.

    Returns
    -------
    Results
        Every stored step: ``t`` (s), ``signals`` (SI units, ``Results.units()``),
        ``impulse`` (N s per contact; ``force = impulse / h`` in N, the paper's λ of
        Eq. 8), the energy and heat balances (J) and the run's ``status`` and ``message``.

    Raises
    ------
    FileNotFoundError
        ``path`` is neither an ``.npz`` file nor a folder holding ``history.npz``.
    """
    path = Path(path)
    file = path / HISTORY if path.is_dir() else path
    if not file.is_file():
        where = f"folder {path} has no {HISTORY}" if path.is_dir() else f"{path} does not exist"
        raise FileNotFoundError(
            f"load_results: {where}; give a results folder of `femrub run` or a saved .npz "
            "file (a run with outputs.history_npz = false writes none: run it again with it)"
        )
    return Results.load_npz(file)
