"""Sphinx configuration of campar's documentation site.

Sphinx with MyST-Parser reads the Markdown pages as they are on GitHub; numpydoc renders
the docstrings' Parameters/Returns/Raises/Examples sections and checks them
(``numpydoc_validation_checks``); pydata-sphinx-theme is the theme of NumPy, SciPy and
xarray. Built with warnings as errors by the test suite (tests/test_docs.py).
"""

import campar

project = "campar"
author = "the campar engineers"
copyright = "campar engineers, MIT licence"
release = version = campar.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "numpydoc",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "**/*.yaml"]
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

autodoc_typehints = "none"  # the Parameters sections give every type
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
# Every documented public object has its parameters, returns and examples.
numpydoc_validation_checks = {"PR01", "PR02", "PR03", "RT01", "EX01", "SS01"}
numpydoc_validation_exclude = {r"\.to_dict$", r"\.to_npz$"}

html_theme = "pydata_sphinx_theme"
html_title = "campar"
html_theme_options = {"navigation_with_keys": False}
