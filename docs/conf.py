"""Sphinx configuration of the gsfric documentation site (``make docs``)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

project = "gsfric"
author = "the gsfric authors"
copyright = "the gsfric authors"  # noqa: A001 (Sphinx's name)
release = "0.1.0"

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax served from _static/mathjax: formulas render offline
    "sphinx_click",
    "sphinx_design",
]

exclude_patterns = ["_build", "_generated", "incoming", "**.ipynb_checkpoints"]
suppress_warnings = ["myst.header"]
"""Only that one: MyST's cross-reference warnings (``myst.xref_missing``, ``myst.xref_ambiguous``)
stay on, so that with ``-W`` a link to a page or file that does not exist fails the build."""
nitpicky = True
nitpick_ignore_regex = [("py:class", r"(?!gsfric\.).*")]
"""Type fields of docstrings hold shapes and units ("(N, 6) array, N"), not only class names:
those are shown as written. Every explicit reference to a gsfric object must resolve."""

myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# `make docs` executes the tutorials (results cached between builds); the link-check test builds
# with GSFRIC_DOCS_EXECUTE=off, since tests/test_notebooks.py already runs every notebook.
nb_execution_mode = os.environ.get("GSFRIC_DOCS_EXECUTE", "cache")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
# The kernels inherit this environment: a matplotlib backend chosen in it (MPLBACKEND=Agg) would
# keep every figure off the site; without one, the kernel draws inline.
os.environ.pop("MPLBACKEND", None)

autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
napoleon_use_ivar = True
napoleon_preprocess_types = False

html_theme = "pydata_sphinx_theme"
html_title = "gsfric"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path: list[str] = []


_OUTSIDE_SCRIPT = """
import sys
from pathlib import Path
from gsfric.discovery.outside import markdown_table
Path(sys.argv[1]).write_text(markdown_table(), encoding="utf-8")
"""


def _write_generated(app) -> None:
    """Files the pages include that the code writes: the commented platform template and the
    table of what discovery looks for outside the catalog."""
    out = Path(app.srcdir, "_generated")
    out.mkdir(exist_ok=True)
    subprocess.run([sys.executable, "-m", "gsfric", "platform", "--template",
                    "--out", str(out / "platform-template.toml")],
                   check=True, capture_output=True)
    subprocess.run([sys.executable, "-c", _OUTSIDE_SCRIPT, str(out / "outside-catalog.md")],
                   check=True, capture_output=True)


REFERENCE_VIEW = "reference-motion.html"
"""The 3-D view of the reference motion, written into the built site's _static/ (the page
explanation/reference-platform.md shows it in a frame)."""

_VIEW_SCRIPT = """
import sys
import gsfric
result = gsfric.evaluate(gsfric.reference_platform(), gsfric.models.paper_motion())
result.to_html(sys.argv[1], title="The reference platform on the reference motion (40 steps)")
"""


def _write_reference_view(app, exception) -> None:
    """Write the 3-D view of the reference motion (``Result.to_html``: one page holding
    three.js, it opens offline) into the built site's _static/, after an HTML build."""
    if exception is not None or app.builder.format != "html":
        return
    static = Path(app.outdir, "_static")
    static.mkdir(parents=True, exist_ok=True)
    subprocess.run([sys.executable, "-c", _VIEW_SCRIPT, str(static / REFERENCE_VIEW)],
                   check=True, capture_output=True)


NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
"""The tutorials' home: notebooks/ at the top of the repository, where they run in Jupyter."""


def _copy_notebooks(app) -> None:
    """Put the notebooks of notebooks/ into tutorials/, where the site shows them.

    Their links are written for the repository (``../docs/howto/sizing.md`` from notebooks/);
    in tutorials/ the same pages are ``../howto/sizing.md``. A copy is written only when it
    would change (Sphinx then rebuilds that page alone), and copies whose notebook is gone are
    removed. The copies are not tracked (.gitignore).
    """
    target = Path(app.srcdir, "tutorials")
    wanted = {}
    for source in sorted(NOTEBOOKS.glob("*.ipynb")):
        notebook = json.loads(source.read_text(encoding="utf-8"))
        for cell in notebook["cells"]:
            if cell["cell_type"] == "markdown":
                text = "".join(cell["source"]).replace("](../docs/", "](../")
                cell["source"] = text.splitlines(keepends=True)
        wanted[source.name] = json.dumps(notebook, indent=1, ensure_ascii=False) + "\n"
    for stale in target.glob("*.ipynb"):
        if stale.name not in wanted:
            stale.unlink()
    for name, text in wanted.items():
        copy = target / name
        if not copy.exists() or copy.read_text(encoding="utf-8") != text:
            # written whole, then renamed: two builds at once never read half a notebook
            partial = target / f".{name}.{os.getpid()}.tmp"
            partial.write_text(text, encoding="utf-8")
            os.replace(partial, copy)


def setup(app):
    app.connect("builder-inited", _copy_notebooks)
    app.connect("builder-inited", _write_generated)
    app.connect("build-finished", _write_reference_view)
