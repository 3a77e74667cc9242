"""report.html of ``gsfric discover``: the 3-D view (``gsfric.view``) of the final model along
the measured motion, with the measured and model forces, the residuals and the named effects'
contributions per leg (``gsfric.view.comparison``)."""

from __future__ import annotations

import os
from pathlib import Path

from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.flags import FLAG_NAMES
from gsfric.view import DEFAULT_FPS, FrameCollector, page, write_page
from gsfric.view.comparison import discovery_plots

CHUNK = 20_000
"""Samples evaluated at a time for the view: only its frames are kept (bounded memory)."""

MAX_FRAMES = 6_000
"""The most frames of the view: its plots add 16 bytes a frame per curve (six curves and one per
further named effect) to the 190 of a frame, and 6,000 frames keep the page under 3 MB."""


def write_view(d, path: str | os.PathLike[str], *, fps: float = DEFAULT_FPS) -> Path:
    """Write the 3-D view of discovery ``d`` (a ``Discovery`` with its ``motion``) to ``path``.

    The final model (``d.platform``) is evaluated along the used samples of the measured
    motion, chunk by chunk, keeping the frames of the view (``FrameCollector``; a frame's step
    is its sample's index in the data); the page draws its loads and plots
    ``discovery_plots``; written as ``write_page`` writes (a temporary file renamed).
    Returns ``path``.
    """
    motion = d.motion.slice(d.used.start, d.used.stop)
    evaluator = Evaluator(d.platform)
    collector = FrameCollector(fps=fps, max_frames=MAX_FRAMES)
    n = len(motion)
    if n > 1:
        collector.fps = min(fps, (collector.max_frames - 1) / float(motion.t[-1] - motion.t[0]))
    for start in range(0, n, CHUNK):
        stop = n if n - start < CHUNK + 8 else start + CHUNK     # no piece too short alone
        collector.add_result(evaluator.evaluate_quiet(motion.slice(start, stop)),
                             d.used.start + start)
        if stop == n:
            break
    frames = collector.finish()
    name = Path(d.source).name if d.source else "measured data"
    effects = ", ".join(d.names) or "no effect named"
    title = f"{name}: the final model ({effects}) against the measurement"
    text = page(frames, d.platform, title=title, flag_names=FLAG_NAMES, steps=n,
                plots=discovery_plots(d, frames))
    return write_page(path, text)
