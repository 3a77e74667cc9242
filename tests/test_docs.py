"""The documentation site builds with warnings as errors: every page is in the table of
contents, and every internal link, cross-reference and API reference resolves."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NOTEBOOKS = ROOT / "notebooks"
MAX_PAGE_LINES = 400


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built as ``make docs`` builds it (notebooks not executed: tests/test_notebooks.py
    runs them), into a temporary folder; the build's log is checked by the first test."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "GSFRIC_DOCS_EXECUTE": "off"}
    run = subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "-n", "-q",
                          "--keep-going", "-d", str(out / "doctrees"), str(DOCS),
                          str(out / "html")], capture_output=True, text=True, env=env,
                         cwd=ROOT)
    return run, out / "html"


def test_site_builds_without_warnings(site):
    run, html = site
    assert run.returncode == 0, run.stderr[-4000:]
    assert (html / "index.html").is_file()
    assert (html / "reference" / "api.html").read_text().count("gsfric.evaluate")


def test_every_notebook_is_a_tutorial_page(site):
    _, html = site
    notebooks = sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb"))
    assert notebooks
    missing = [n for n in notebooks if not (html / "tutorials" / f"{n}.html").is_file()]
    assert not missing, f"notebooks/ without a page under tutorials/: {missing}"


def _pages():
    return sorted(p for p in DOCS.rglob("*.md")
                  if "_build" not in p.parts and "_generated" not in p.parts)


HISTORY = re.compile(r"\b(?:source|commit|against) `[0-9a-f]{7,40}`|as measured on")


@pytest.mark.parametrize("page", _pages(), ids=lambda p: str(p.relative_to(DOCS)))
def test_page_is_short_and_speaks_of_the_product(page):
    text = page.read_text()
    assert len(text.splitlines()) <= MAX_PAGE_LINES, f"{page.name}: split it into pages"
    history = HISTORY.findall(text)
    assert not history, f"{page.name}: run records belong in benchmarks/results/: {history[:3]}"


@pytest.mark.parametrize("notebook", sorted(NOTEBOOKS.glob("*.ipynb")), ids=lambda p: p.name)
def test_notebook_speaks_of_the_product(notebook):
    nbformat = pytest.importorskip("nbformat")
    cells = nbformat.read(notebook, as_version=4).cells
    text = "\n".join(c.source for c in cells if c.cell_type == "markdown")
    history = HISTORY.findall(text)
    assert not history, f"{notebook.name}: run records belong in benchmarks/results/: {history}"
