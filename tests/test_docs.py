"""The documentation site builds with warnings as errors: every page is in the table of
contents, and every internal link, cross-reference and API reference resolves. The built site
works offline: no page loads a script, stylesheet, font or image from outside the site."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest

from gsfric.view import embedded

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NOTEBOOKS = ROOT / "notebooks"
MAX_PAGE_LINES = 400
EXTERNAL = re.compile(r"^\s*(?:[a-z][a-z0-9+.-]*:)?//", re.I)
"""A URL that leaves the site: ``http://``, ``https://``, ``//host`` (any scheme with a host)."""


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


class _Resources(HTMLParser):
    """The URLs a page loads by itself (not the links a reader may follow)."""

    LOADS = {"script": ("src",), "img": ("src", "srcset"), "iframe": ("src",),
             "source": ("src", "srcset"), "audio": ("src",), "video": ("src", "poster"),
             "embed": ("src",), "object": ("data",)}
    LINK_RELS = {"stylesheet", "preload", "modulepreload", "prefetch", "icon", "shortcut",
                 "apple-touch-icon", "manifest"}

    def __init__(self) -> None:
        super().__init__()
        self.urls: list[str] = []
        self.styles: list[str] = []
        self._in_style = False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for name in self.LOADS.get(tag, ()):
            if attrs.get(name):
                self.urls += [part.split()[0] for part in attrs[name].split(",") if part.strip()]
        if tag == "link" and set((attrs.get("rel") or "").lower().split()) & self.LINK_RELS:
            self.urls.append(attrs.get("href") or "")
        if attrs.get("style"):
            self.styles.append(attrs["style"])
        self._in_style = tag == "style"

    def handle_endtag(self, tag):
        if tag == "style":
            self._in_style = False

    def handle_data(self, data):
        if self._in_style:
            self.styles.append(data)


def _css_urls(text: str) -> list[str]:
    """``url(...)`` and ``@import "..."`` of a stylesheet."""
    return (re.findall(r"url\(\s*['\"]?([^'\")]+)", text)
            + re.findall(r"@import\s+['\"]([^'\"]+)", text))


def test_pages_load_nothing_from_outside_the_site(site):
    """MathJax, fonts, scripts and stylesheets are served from the site, so that it renders
    with no network (a page that loaded MathJax from a CDN would show raw LaTeX offline)."""
    run, html = site
    assert run.returncode == 0, run.stderr[-4000:]
    found = []
    pages = sorted(html.rglob("*.html"))
    assert len(pages) > 20
    for page in pages:
        parser = _Resources()
        parser.feed(page.read_text(encoding="utf-8", errors="replace"))
        urls = parser.urls + [u for style in parser.styles for u in _css_urls(style)]
        found += [f"{page.relative_to(html)}: {u}" for u in urls if EXTERNAL.match(u)]
    for sheet in sorted(html.rglob("*.css")):
        urls = _css_urls(sheet.read_text(encoding="utf-8", errors="replace"))
        found += [f"{sheet.relative_to(html)}: {u}" for u in urls if EXTERNAL.match(u)]
    assert not found, "loaded from outside the site:\n" + "\n".join(found[:20])


def test_math_is_rendered_by_the_sites_own_mathjax(site):
    _, html = site
    with_math = 0
    for page in sorted(html.rglob("*.html")):
        text = page.read_text(encoding="utf-8", errors="replace")
        if 'class="math' not in text:
            continue
        with_math += 1
        scripts = re.findall(r"<script[^>]*\ssrc=\"([^\"]*mathjax[^\"]*)\"", text, re.I)
        assert scripts, f"{page.relative_to(html)} has formulas but loads no MathJax"
        for src in scripts:
            assert (page.parent / src.split("?")[0]).resolve().is_file(), (page, src)
    assert with_math


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


def test_the_reference_motion_is_shown_in_3d_from_the_site(site):
    """The page that describes the reference motion shows its 3-D view, a page of the site's
    own _static/ written at build time (self-contained: tests/test_view.py)."""
    run, html = site
    assert run.returncode == 0, run.stderr[-4000:]
    page = html / "explanation" / "reference-platform.html"
    parser = _Resources()
    parser.feed(page.read_text(encoding="utf-8"))
    frames = [u for u in parser.urls if u.endswith("reference-motion.html")]
    assert len(frames) == 1
    view = (page.parent / frames[0]).resolve()
    assert view.is_file() and view.parent == (html / "_static").resolve()
    data = embedded(view.read_text(encoding="utf-8"))
    assert data["steps"] == data["frames"] == 40
