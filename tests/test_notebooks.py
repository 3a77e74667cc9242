"""Every tutorial notebook (notebooks/) executes headless, top to bottom, without an error, and
every cell that draws shows its figure (the site shows the outputs as they come out here)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

NOTEBOOK_DIR = Path(__file__).resolve().parents[1] / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
CELL_TIMEOUT = None  # no deadline of its own: pytest-timeout guards against a hang

DRAWS = re.compile(r"\bplt\.|\bplot\(|\bImage\(")
"""A code cell that draws: pyplot, gsfric's plot helpers or a PNG shown with IPython's Image."""


def _code_cells(notebook):
    return [cell for cell in notebook.cells if cell.cell_type == "code"]


@pytest.mark.parametrize(
    "path",
    NOTEBOOKS or [pytest.param(None, marks=pytest.mark.skip(reason="no notebooks in notebooks/"))],
    ids=lambda p: p.name if isinstance(p, Path) else "none",
)
def test_notebook_executes_and_shows_its_figures(path: Path, monkeypatch) -> None:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    # the kernel takes this environment: a backend chosen here (Agg) would hide every figure
    monkeypatch.delenv("MPLBACKEND", raising=False)
    notebook = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(notebook, timeout=CELL_TIMEOUT, kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    errors = [out for cell in _code_cells(notebook) for out in cell.get("outputs", [])
              if out.get("output_type") == "error"]
    assert not errors, f"{path.name}: {errors[0].get('ename')}: {errors[0].get('evalue')}"
    blank = [cell.source.splitlines()[0] for cell in _code_cells(notebook)
             if DRAWS.search(cell.source)
             and not any("image/png" in out.get("data", {}) for out in cell.outputs)]
    assert not blank, f"{path.name}: cells that draw show no figure: {blank}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_keeps_the_inline_backend(path: Path) -> None:
    """A notebook that picks a matplotlib backend (``matplotlib.use('Agg')``) draws nothing on
    the site; the kernel's inline backend shows every figure."""
    text = path.read_text(encoding="utf-8")
    assert not re.search(r"matplotlib\.use\(|%matplotlib\s+(?!inline)", text), path.name
