"""Sphinx configuration of the femrub documentation.

Build: ``python -m sphinx -W -b html docs docs/_build/html`` (``pip install -e '.[docs]'``).
Generated at build time: the API reference (autosummary over numpydoc docstrings), every scene
key (``_ext/scene_keys.py`` from ``femrub.scene.schema``), the command line
(``_ext/cli_reference.py`` from ``femrub.app.cli``'s parser) and the example gallery
(sphinx-gallery runs ``docs/gallery/*.py``). ``FEMRUB_DOCS_QUICK=1`` runs the gallery on its
quick settings (what the test suite builds).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE / "_ext"))

import paper_numbers  # noqa: E402

import femrub  # noqa: E402

project = "femrub"
author = "the femrub developers"
copyright = "the femrub developers"
version = release = femrub.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "scene_keys",
    "cli_reference",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "**/campbell-rotor37-*",
    # study sections that benchmarks/run_all.py renders into the pages
    "performance/exponential_section.md",
    "performance/cost_3d.md",
    "gallery/README.rst",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "auto_examples/*.zip",
]
suppress_warnings = []
myst_enable_extensions = ["dollarmath", "colon_fence", "substitution"]
# the numbers of paper-reproduction.md: femrub paper's summary.json (_ext/paper_numbers.py)
myst_substitutions = paper_numbers.substitutions(HERE / "paper" / "summary.json")
myst_heading_anchors = 3

# API reference
autosummary_generate = True
templates_path = ["_templates"]
autodoc_default_options = {"members": True}
autodoc_member_order = "groupwise"
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

# the gallery: every example runs at build time (quick settings in the test suite)
QUICK = os.environ.get("FEMRUB_DOCS_QUICK", "") not in ("", "0")
os.environ.setdefault("MPLBACKEND", "Agg")
sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
    "reset_modules_order": "both",
    "matplotlib_animations": False,
    "show_memory": False,
    "capture_repr": (),
}

html_theme = "pydata_sphinx_theme"
html_title = f"femrub {release}"
html_theme_options = {
    "navigation_depth": 2,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_show_sourcelink = False
