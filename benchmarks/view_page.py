"""Size and writing time of the 3-D view page (``gsfric.view``), against its two limits: at
most 3 MB for 10,000 steps, and written in under 2 s for 100,000 steps.

Sizes: ``Result.to_html`` of a record of 10,000 steps at 50 steps a second (every step a
frame) and at 1000 steps a second (frames at 60 a second), with the page's parts (three.js
and the viewer, the data). Times: the median of ``--rounds`` runs of ``Result.to_html`` for
100,000 steps at 1000 steps a second (the evaluation done before, not timed), and of
``gsfric.simulate.view_file`` on the same motion from a CSV file (reading, differentiating and
evaluating included)::

    .venv/bin/python benchmarks/view_page.py
    .venv/bin/python benchmarks/view_page.py --rounds 5
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import gsfric
from gsfric import models
from gsfric.io.tables import write_table
from gsfric.simulate import view_file
from gsfric.view import embedded

MB = 1_000_000


def record(steps: int, rate: float):
    """The reference platform on the sinusoidal motion, ``steps`` at ``rate`` a second."""
    t = np.arange(steps) / rate
    return gsfric.evaluate(gsfric.reference_platform(), models.sinusoidal(t))


def timed(call, rounds: int) -> float:
    """Median wall time of ``call()``, s."""
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def sizes(folder: Path) -> None:
    for rate in (50.0, 1000.0):
        path = record(10_000, rate).to_html(folder / f"size-{rate:g}.html")
        page = path.read_text(encoding="utf-8")
        data = len(page) - page.index('id="gsfric-data">')
        print(f"10,000 steps at {rate:g}/s: {embedded(page)['frames']} frames, page "
              f"{len(page.encode()) / MB:.3f} MB (data {data / MB:.3f} MB); limit 3 MB")


def times(folder: Path, rounds: int) -> None:
    result = record(100_000, 1000.0)
    page = folder / "long.html"
    seconds = timed(lambda: result.to_html(page), rounds)
    print(f"100,000 steps, Result.to_html: {seconds:.3f} s (median of {rounds}); limit 2 s")
    csv = folder / "long.csv"
    write_table(result.source[1].to_frame(), csv)
    seconds = timed(lambda: view_file(csv, folder / "file.html"), rounds)
    print(f"100,000 steps, gsfric view (read, differentiate, evaluate, write): {seconds:.3f} s "
          f"(median of {rounds})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="Runs timed (median).")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        sizes(Path(folder))
        times(Path(folder), args.rounds)


if __name__ == "__main__":
    main()
