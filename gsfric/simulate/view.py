"""``view_file``: a trajectory file evaluated as ``simulate_file`` evaluates it, and written as a
3-D view (``gsfric view``).

The file is read and differentiated chunk by chunk (``iter_motions``, the same reading,
checks and differentiation as ``gsfric simulate``), each chunk is evaluated and only the
frames of the view are kept (``gsfric.view.FrameCollector``, with a measured-data file's
forces), so that memory stays bounded however long the file is. The page is written to a
temporary file and renamed when complete.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gsfric._checks import as_count, as_flag, as_path
from gsfric._threads import one_blas_thread
from gsfric.errors import GsfricWarning, InputError
from gsfric.evaluation.evaluator import MAX_THREADS, Evaluator
from gsfric.evaluation.flags import FLAG_NAMES
from gsfric.io.files import check_output_place, check_outputs, is_stream
from gsfric.io.tables import check_file
from gsfric.models import platform_from
from gsfric.signal.savgol import DEFAULT_POLYORDER
from gsfric.simulate.differentiate import DEFAULT_CHUNK, iter_motions
from gsfric.simulate.run import Summary, _Flags, check_chunk, describe_differentiation
from gsfric.view import DEFAULT_FPS, FrameCollector, Frames, page, write_page
from gsfric.view.comparison import measured_plots

HTML_SUFFIXES = (".html", ".htm")


@dataclass
class ViewSummary(Summary):
    """What ``view_file`` did: ``simulate_file``'s ``Summary`` (``out`` is the page) and

    Attributes
    ----------
    frames : int
        Frames in the page (``gsfric.view.frames``).
    size : int
        The page's size, bytes.
    """

    frames: int = 0
    size: int = 0


def check_view_paths(trajectory: Path, out: Path, platform) -> None:
    """``InputError`` before any work: ``out`` not an .html file in an existing directory (a
    character device or FIFO is written into), or one of the inputs; ``trajectory`` missing,
    empty or of an unknown kind."""
    check_outputs([out], {"trajectory": trajectory, "platform": platform})
    stream = is_stream(out)
    if not stream and out.suffix.lower() not in HTML_SUFFIXES:
        raise InputError(f"{out}: unknown extension {out.suffix or '(none)'!r}; use .html")
    check_output_place(out)
    check_file(trajectory)


@one_blas_thread
def view_file(trajectory: str | os.PathLike[str], out: str | os.PathLike[str], platform=None,
              *, mode: str = "kinematic", chunk: int = DEFAULT_CHUNK, window: int | None = None,
              polyorder: int = DEFAULT_POLYORDER, n_threads: int = 1, log_format=None,
              fps: float = DEFAULT_FPS, title: str | None = None,
              measured: bool = False) -> ViewSummary:
    """Evaluate a trajectory file and write its 3-D view (``gsfric.view``) to ``out``.

    Parameters
    ----------
    trajectory : path-like
        CSV or Parquet trajectory or measured-data file (``gsfric.io.read_trajectory``); the
        page of a measured-data file plots its forces F1..F6 against the model's and the
        residual (``gsfric.view.comparison.measured_plots``).
    out : path-like
        The ``.html`` page.
    platform : Platform or path-like, optional
        As ``gsfric.models.platform_from``; default: the reference platform.
    mode, chunk, window, polyorder, n_threads, log_format :
        As for ``gsfric.simulate.simulate_file``.
    fps : float
        Frames per second of motion time in the page (at most ``gsfric.view.MAX_FRAMES``).
    title : str, optional
        The page's title (default: the trajectory's file name).
    measured : bool
        The file must be a measured-data file: an ``InputError`` naming the first of
        F1..F6 it lacks.

    Returns
    -------
    ViewSummary
        Flagged steps are also reported as one warning (``GsfricWarning``).

    Raises
    ------
    InputError
        Bad trajectory (naming the row and column), platform or output path, as
        ``simulate_file``; ``fps`` not a positive number.
    OutputError
        The page could not be written; an earlier file of that name is unchanged.
    """
    trajectory, out = as_path(trajectory, "trajectory"), as_path(out, "out")
    n_threads = as_count(n_threads, "n_threads", minimum=1, maximum=MAX_THREADS)
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not np.isfinite(fps) \
            or fps <= 0:
        raise InputError(f"fps: must be a positive number, got {fps!r}")
    measured = as_flag(measured, "measured")
    check_view_paths(trajectory, out, platform)
    platform = platform_from(platform)
    summary = ViewSummary(out=out)
    motions = iter_motions(trajectory, chunk=chunk, window=window, polyorder=polyorder,
                           log_format=log_format)
    frames = _frames(trajectory, motions, Evaluator(platform, mode=mode, n_threads=n_threads),
                     FrameCollector(fps=fps), summary, measured)
    text = page(frames, platform, title=title if title is not None else
                f"{trajectory.name}: {mode} mode", flag_names=FLAG_NAMES, steps=summary.steps,
                plots=measured_plots(frames))
    write_page(out, text, inputs={"trajectory": trajectory, "platform": platform})
    summary.frames, summary.size = len(frames), len(text.encode("utf-8"))
    if summary.flagged:
        warnings.warn(summary.flag_message(trajectory) + f"; they are marked in {out}",
                      GsfricWarning, stacklevel=2)
    return summary


def _frames(trajectory: Path, motions, evaluator: Evaluator, collector: FrameCollector,
            summary: ViewSummary, measured: bool = False) -> Frames:
    """Evaluate each chunk of ``motions`` (checked as ``simulate_file`` checks them:
    ``check_chunk``) and keep
    its frames; the steps, chunks, differentiation and flags counted into ``summary``.
    ``measured``: F1..F6 must be among the carried columns."""
    flags = _Flags()
    for part in motions:
        motion = part.motion
        check_chunk(evaluator.platform, part, trajectory)
        missing = [f"F{i}" for i in range(1, 7) if f"F{i}" not in part.carried]
        if measured and missing:
            raise InputError(f"{trajectory}: a measured-data file needs the force columns "
                             f"F1..F6; {missing[0]} is missing")
        result = evaluator.evaluate_quiet(motion)
        forces = (np.column_stack([part.carried[f"F{i}"] for i in range(1, 7)])
                    if "F1" in part.carried else None)       # a measured-data file's
        collector.add_result(result, part.start, forces)
        flags.add(np.asarray(result.flag, np.int64), part.start, motion.t)
        summary.steps = part.start + len(motion)
        summary.chunks += 1
        summary.windows = part.windows
        summary.differentiation = summary.differentiation or describe_differentiation(part)
    flags.fill(summary)
    return collector.finish()
