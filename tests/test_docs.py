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
MAX_PAGE_LINES = 400


def test_site_builds_without_warnings(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    env = {**os.environ, "GSFRIC_DOCS_EXECUTE": "off"}
    run = subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "-n", "-q",
                          "--keep-going", "-d", str(tmp_path / "doctrees"), str(DOCS),
                          str(tmp_path / "html")], capture_output=True, text=True, env=env,
                         cwd=ROOT)
    assert run.returncode == 0, run.stderr[-4000:]
    assert (tmp_path / "html" / "index.html").is_file()
    assert (tmp_path / "html" / "reference" / "api.html").read_text().count("gsfric.evaluate")


def _pages():
    return sorted(p for p in DOCS.rglob("*.md")
                  if "_build" not in p.parts and "_generated" not in p.parts)


@pytest.mark.parametrize("page", _pages(), ids=lambda p: str(p.relative_to(DOCS)))
def test_page_is_short_and_speaks_of_the_product(page):
    text = page.read_text()
    assert len(text.splitlines()) <= MAX_PAGE_LINES, f"{page.name}: split it into pages"
    history = re.findall(r"\b(?:source|commit|against) `[0-9a-f]{7,40}`|as measured on", text)
    assert not history, f"{page.name}: run records belong in benchmarks/results/: {history[:3]}"
