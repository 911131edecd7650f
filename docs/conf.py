"""The documentation site (Sphinx with MyST Markdown, the Furo theme): `make docs` builds it from the
checkout root with warnings as errors into build/docs/html/ (open build/docs/html/index.html).

The source tree is the checkout itself, limited to README.md, docs/ and reports/, so every relative
link in them (docs/config.md, ../reports/paper/fig14.md, a figure) works on the site as it does in the
repository. The API reference is autodoc over the docstrings of sim, models and experiments.
"""
from __future__ import annotations

import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import experiments  # noqa: E402

project = "rast5d"
author = "The rast5d authors"
release = version = experiments.__version__
copyright = "the rast5d authors, MIT licence"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.viewcode"]
root_doc = "docs/index"
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
include_patterns = ["README.md", "CHANGELOG.md", "models/assets/README.md", "docs/**", "reports/**"]
exclude_patterns = ["docs/_extra/**", "reports/quick/**", "reports/**/cache/**", "**/configs/**"]
html_extra_path = ["_extra"]  # index.html at the site's root, forwarding to docs/index.html

myst_enable_extensions = ["colon_fence", "deflist", "html_image"]
myst_heading_anchors = 4
myst_url_schemes = ["http", "https", "mailto"]
# A link to a file of the checkout that is not a page (a config, a module, a CSV) is a link to the
# file itself (copied into the site by MyST as a download), not a missing cross-reference.
suppress_warnings = ["myst.header"]

html_theme = "furo"
html_title = f"rast5d {release}"
html_static_path = []
html_show_sourcelink = False

autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_typehints = "description"
autodoc_mock_imports = []
napoleon_google_docstring = False
napoleon_numpy_docstring = True
nitpicky = False


def _bibliography_if_present(app, docname, source):
    """The bibliography page (docs/references.md) joins the site's table of contents, and the README's
    link to it works, once it exists; until then both name it as text."""
    if (ROOT / "docs" / "references.md").exists():
        return
    if docname == "docs/index":
        source[0] = re.sub(r"^references\n", "", source[0], flags=re.M)
    if docname == "README":
        source[0] = source[0].replace("[bibliography](docs/references.md)", "bibliography (`docs/references.md`)")


def setup(app):
    app.connect("source-read", _bibliography_if_present)
