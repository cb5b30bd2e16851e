"""Sphinx configuration of the documentation site: the specification pages (Markdown, through MyST) and the API
reference (autodoc from the package's docstrings).  Built by `make docs`, warnings as errors."""

from impact import __version__

project = "impact-dampers"
author = "impact-dampers maintainers"
release = version = __version__
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax",
              "sphinx.ext.viewcode"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
# the docstrings name their arguments in prose; only a "Returns"/"Parameters" section is read as such
napoleon_google_docstring = False
napoleon_numpy_docstring = True
html_theme = "alabaster"
html_title = f"impact-dampers {__version__}"
nitpicky = False
