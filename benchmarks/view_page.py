"""Size and writing time of the 3-D view page (``gsfric.view``), against its two limits: at
most 3 MB for 10,000 steps, and written in under 2 s for 100,000 steps.

Sizes: ``Result.to_html`` of a record of 10,000 steps at 50 steps a second (every step a
frame) and at 1000 steps a second (frames at 60 a second), with the page's parts (three.js
and the viewer, the data); and a page of the most frames of discover's report.html
(``gsfric.discovery.view.MAX_FRAMES``) with the curves of three named effects (eight).
Times: the median of ``--rounds`` runs of ``Result.to_html`` for
100,000 steps at 1000 steps a second (the evaluation done before, not timed), and of
``gsfric.simulate.view_file`` on the same motion from a CSV file (reading, differentiating and
evaluating included; the Savitzky-Golay windows chosen per sample, as by default, and one
window given), wall and CPU time (on a shared machine the wall time waits for the
others)::

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
from gsfric.discovery.view import MAX_FRAMES
from gsfric.simulate import view_file
from gsfric.view import Curve, FrameCollector, Plot, embedded, page

MB = 1_000_000


def record(steps: int, rate: float):
    """The reference platform on the sinusoidal motion, ``steps`` at ``rate`` a second."""
    t = np.arange(steps) / rate
    return gsfric.evaluate(gsfric.reference_platform(), models.sinusoidal(t))


def timed(call, rounds: int) -> tuple[float, float]:
    """Median wall and CPU time of ``call()``, s."""
    walls, cpus = [], []
    for _ in range(rounds):
        wall, cpu = time.perf_counter(), time.process_time()
        call()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus)


def sizes(folder: Path) -> None:
    for rate in (50.0, 1000.0):
        path = record(10_000, rate).to_html(folder / f"size-{rate:g}.html")
        page = path.read_text(encoding="utf-8")
        data = len(page) - page.index('id="gsfric-data">')
        print(f"10,000 steps at {rate:g}/s: {embedded(page)['frames']} frames, page "
              f"{len(page.encode()) / MB:.3f} MB (data {data / MB:.3f} MB); limit 3 MB")


def discovery_size() -> None:
    result = record(MAX_FRAMES, 50.0)
    frames = FrameCollector(max_frames=MAX_FRAMES).add_result(result).finish()
    rng = np.random.default_rng(0)

    def curves(n):
        return tuple(Curve(str(k), rng.normal(size=(len(frames), 6))) for k in range(n))

    plots = [Plot("force", "N", curves(3)), Plot("residual", "N", curves(2)),
             Plot("contribution", "N", curves(3))]
    text = page(frames, gsfric.reference_platform(), plots=plots)
    print(f"{len(frames)} frames with 8 curves (discover, three effects): "
          f"{len(text.encode()) / MB:.3f} MB; limit 3 MB")


def times(folder: Path, rounds: int) -> None:
    result = record(100_000, 1000.0)
    page = folder / "long.html"
    wall, cpu = timed(lambda: result.to_html(page), rounds)
    print(f"100,000 steps, Result.to_html: {wall:.3f} s, CPU {cpu:.3f} s (median of {rounds}); "
          "limit 2 s")
    csv = folder / "long.csv"
    write_table(result.source[1].to_frame(), csv)
    for window in (None, 21):
        wall, cpu = timed(lambda w=window: view_file(csv, folder / "file.html", window=w),
                          rounds)
        how = "windows chosen per sample" if window is None else f"--window {window}"
        print(f"100,000 steps, gsfric view ({how}; read, differentiate, evaluate, write): "
              f"{wall:.3f} s, CPU {cpu:.3f} s (median of {rounds})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="Runs timed (median).")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        sizes(Path(folder))
        discovery_size()
        times(Path(folder), args.rounds)


if __name__ == "__main__":
    main()
