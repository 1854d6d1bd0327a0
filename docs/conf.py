"""Sphinx configuration of the rc3r documentation.

Build (warnings are errors, as in CI)::

    .venv/bin/pip install -e ".[docs]"
    .venv/bin/python -m sphinx -W --keep-going -b html docs docs/_build/html

``docs/docs-build.md`` says why each extension is used.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# The installed package is what gets documented (pip install -e .); fall back to src/ so a
# checkout without an editable install still builds.
try:
    import rc3r  # noqa: F401
except ImportError:  # pragma: no cover
    sys.path.insert(0, str(ROOT / "src"))
    import rc3r  # noqa: F401

project = "rc3r"
author = "rc3r contributors"
copyright = "rc3r contributors"
version = release = rc3r.__version__

extensions = [
    "sphinx.ext.autodoc",      # API reference from the docstrings
    "sphinx.ext.autosummary",  # summary tables of the public API
    "sphinx.ext.mathjax",      # :math: in docstrings
    "sphinx.ext.viewcode",     # [source] links
    "numpydoc",                # the docstrings are numpydoc style
    "myst_nb",                 # the Markdown pages (myst-parser) and the executed notebook
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "README.md"]

# --- autodoc / autosummary / numpydoc ------------------------------------------------------
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_default_options = {"members": True, "show-inheritance": True}
autosummary_generate = False          # the API pages are written by hand (docs/api/*.rst)
numpydoc_show_class_members = False   # members are listed by autodoc, not by numpydoc
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False

# --- MyST ----------------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3              # the pages link to each other's sections (page.md#a-title)

# --- notebooks (myst-nb): executed at every build, an error fails the build ---------------
nb_execution_mode = "force"
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

# --- HTML ----------------------------------------------------------------------------------
html_theme = "alabaster"
html_title = f"rc3r {release}"
html_static_path: list[str] = []
