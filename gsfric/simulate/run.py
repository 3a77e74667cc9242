"""``simulate_file``: a trajectory file of any length evaluated chunk by chunk and written, in bounded memory.

``simulate_file`` reads a trajectory file (CSV or Parquet) in chunks of ``chunk`` rows,
differentiates each chunk (``gsfric.simulate.differentiate``), evaluates it, and appends its
rows to the output, so that memory stays bounded by the chunk size however long the file is
(10 million steps in well under 2 GB, see docs/explanation/robustness.md). It is what ``gsfric simulate``
runs.

The sensor's ``time_offset`` (``gsfric.platform.catalog``) interpolates F between steps that may
lie in a neighbouring chunk: it is applied across chunks (``SensorDelay``), with the values
``evaluate`` gives over the whole file. Step flags (``gsfric.evaluation``) are gathered over the
whole file with their global step indices and reported at the end as one warning, or, with
``strict``, as a ``StepFlagError`` at the first chunk with a flagged step.

Output. Rows are appended to a temporary file in the output's directory (a Parquet row group
or a CSV block per chunk) that is renamed onto the output only when every chunk succeeded;
on any error or a KeyboardInterrupt it is removed and an existing output is left untouched.
Reading and differentiating, evaluating, and building the columns and writing run in three
threads, chunk after chunk.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import warnings
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from gsfric._checks import as_count, as_flag, as_path
from gsfric._threads import one_blas_thread
from gsfric.errors import GsfricWarning, StepFlagError
from gsfric.evaluation.columns import plan as column_plan
from gsfric.evaluation.evaluator import MAX_THREADS, Evaluator, evaluate_outputs
from gsfric.evaluation.flags import FLAG_NAMES, FLAG_NONFINITE, check_flagged, flag_counts
from gsfric.evaluation.peaks import PEAK_ARRAYS, Peaks
from gsfric.io.files import (
    atomic_write,
    check_output_place,
    check_outputs,
    is_stream,
    output_group,
)
from gsfric.io.tables import check_file, count_rows, table_kind
from gsfric.models import check_measured_forces, platform_from
from gsfric.platform.catalog import sensor_parameters
from gsfric.platform.usable import check_flagged_share, check_gaps, check_poses
from gsfric.signal.savgol import DEFAULT_POLYORDER
from gsfric.simulate.delay import SensorDelay
from gsfric.simulate.differentiate import DEFAULT_CHUNK, MotionChunk, iter_motions
from gsfric.simulate.figure import SERIES, Trace, check_figure, write_figure
from gsfric.simulate.outputs import (
    ChunkOutputs,
    delayed_columns,
    parse_columns,
    result_columns,
    with_carried,
)
from gsfric.simulate.rates import RateComparison, compare_rates
from gsfric.simulate.writer import Writer

SIGMA_SHARE = 0.05
"""``simulate`` warns when a leg's sigma_F (the differentiation's uncertainty of F; its root
mean square over the steps where every leg slides: at a rest it is the friction's sign, which
the ``rest`` column reports) exceeds this share of its largest |F|: beyond, the forces depend on
how the motion was differentiated (window, time base, the log's own rates) by more than a
sizing margin hides."""

MAX_REPORTED = 10_000
"""Flagged step indices kept for the summary (the count is always exact)."""

MAX_RANGES = 10_000
"""Time ranges of consecutive flagged steps kept for the summary (their count is exact)."""

SHOWN_RANGES = 5
"""Time ranges of flagged steps named in a message: the longest ones."""

EVALUATE_STEPS = 50_000
"""Steps evaluated and written at a time (a Parquet row group): a chunk read and
differentiated whole is evaluated in pieces of at most this many steps, so the outputs and
columns in flight (two pieces' worth of each) stay small whatever the chunk."""


@dataclass
class Summary:
    """What ``simulate_file`` did.

    Attributes
    ----------
    out : Path
    steps : int
        Steps evaluated (= data rows of the trajectory = rows written).
    chunks : int
    windows : tuple (position, quaternion) of int, "whole" or None
        Savitzky-Golay windows of a streamed file; "whole" for a file read in one piece with a
        Savitzky-Golay filter, None for a non-uniform file (smoothing spline).
    flagged : int
        Number of flagged steps.
    flag_counts : dict of str -> int
        Flagged steps per kind (``FLAG_NAMES``).
    flagged_steps : ndarray
        0-based indices of flagged steps (the first ``MAX_REPORTED``).
    differentiation : str
        How velocities and accelerations were obtained (``describe_differentiation``).
    flagged_ranges : list of (float, float, int)
        Runs of consecutive flagged steps: first and last time from the record's start, s,
        and the steps in the run (the first ``MAX_RANGES`` runs).
    runs : int
        Number of runs of consecutive flagged steps.
    peaks : Peaks
        The per-leg peaks over the sound steps (``gsfric.evaluation.peaks``).
    trace : Trace or None
        The forces and friction over the record for ``plot`` (``gsfric.simulate.figure``).
    sliding_sigma_F : ndarray, shape (6,)
        Root mean square of sigma_F of each leg over the steps where no leg is possibly at
        rest, N (NaN: not computed; with the ``uncertainty`` group only).
    rest_steps : int
        Steps with a leg possibly at rest (``rest`` != 0).
    rates : RateComparison or None
        The log's own rates against its poses differentiated, for a log with rate columns.
    """

    out: Path
    steps: int = 0
    chunks: int = 0
    windows: Any = None
    flagged: int = 0
    flag_counts: dict[str, int] = field(default_factory=dict)
    flagged_steps: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    differentiation: str = ""
    flagged_ranges: list = field(default_factory=list)
    runs: int = 0
    peaks: Peaks = field(default_factory=Peaks)
    trace: Trace | None = None
    sliding_sigma_F: np.ndarray = field(default_factory=lambda: np.full(6, np.nan))
    rest_steps: int = 0
    rates: RateComparison | None = None

    def uncertainty_message(self, trajectory: Path) -> str | None:
        """One line when a leg's typical sigma_F (``sliding_sigma_F``) exceeds
        ``SIGMA_SHARE`` of its largest |F|, else None."""
        peak = self.peaks.values.get("F", np.full(6, np.nan))
        with np.errstate(invalid="ignore", divide="ignore"):
            share = self.sliding_sigma_F / peak
        if not np.any(share > SIGMA_SHARE):
            return None
        leg = int(np.nanargmax(share))
        return (f"{trajectory}: the forces hinge on the differentiation: sigma_F is "
                f"{self.sliding_sigma_F[leg]:.4g} N on leg {leg + 1} (root mean square where "
                f"the legs slide), {100 * share[leg]:.3g} % of its peak |F| of "
                f"{peak[leg]:.4g} N (more than "
                f"{100 * SIGMA_SHARE:g} %); see the sigma_F columns, give a --window, or map "
                "the log's own rate columns")

    def flag_message(self, trajectory: Path) -> str:
        kinds = "; ".join(f"{name}: {count}" for name, count in self.flag_counts.items()
                          if count)
        share = 100.0 * self.flagged / max(self.steps, 1)
        return (f"{trajectory}: {self.flagged} of {self.steps} steps flagged ({kinds}; "
                f"{share:.3g} % of the steps) in {self.ranges_text()}: "
                f"{_steps_text(self.flagged_steps, self.flagged)}")

    def ranges_text(self) -> str:
        """Where the flagged steps lie: the number of runs of consecutive flagged steps and
        the longest ``SHOWN_RANGES`` of them, as times from the record's start."""
        longest = sorted(self.flagged_ranges, key=lambda r: (-r[2], r[0]))[:SHOWN_RANGES]
        spans = ", ".join(f"{a:.3f}-{b:.3f} s ({n} steps)" if n > 1 else f"{a:.3f} s"
                          for a, b, n in sorted(longest))
        word = "stretch" if self.runs == 1 else "stretches"
        which = "" if self.runs <= len(longest) else f", the {len(longest)} longest"
        return f"{self.runs} {word} (t from the record's start{which}: {spans})"


def describe_differentiation(part: MotionChunk) -> str:
    """One line on how a chunk's velocities and accelerations were obtained: the motion's
    own ``Motion.differentiation`` for a file read whole, the fixed windows of a streamed
    one."""
    how = part.motion.differentiation()
    if how is not None:
        return how.describe()
    position, orientation = part.windows
    return (f"savgol (windows {position} for the position, {orientation} for the "
            "orientation, the same over every chunk)")


def _steps_text(indices: np.ndarray, total: int, limit: int = 10) -> str:
    shown = indices[:limit]
    more = f", ... ({total - len(shown)} more)" if total > len(shown) else ""
    steps = ", ".join(str(int(i)) for i in shown)
    rows = ", ".join(str(int(i) + 1) for i in shown)
    return f"steps {steps}{more} (data rows {rows})"


def _pieces(parts: Iterable[MotionChunk], size: int) -> Iterator[MotionChunk]:
    """The chunks cut into consecutive pieces of at most ``size`` steps (views, no copies)."""
    for part in parts:
        n = len(part.motion)
        if n <= size:
            yield part
            continue
        for s in range(0, n, size):
            e = min(n, s + size)
            yield MotionChunk(part.start + s, part.motion.slice(s, e), part.windows,
                              {name: v[s:e] for name, v in part.carried.items()})


@one_blas_thread
def simulate_file(trajectory: str | os.PathLike[str], out: str | os.PathLike[str], platform=None,
                  *, mode: str = "kinematic", strict: bool = False, chunk: int = DEFAULT_CHUNK,
                  window: int | None = None, polyorder: int = DEFAULT_POLYORDER,
                  n_threads: int = 1, progress: bool | None = None, log_format=None,
                  columns=None, float32: bool = False, keep_flagged: bool = False,
                  plot: str | os.PathLike[str] | None = None, uncertainty: bool = True) -> Summary:
    """Evaluate a trajectory file chunk by chunk and write every step's outputs.

    Parameters
    ----------
    trajectory : path-like
        CSV or Parquet trajectory file (see ``gsfric.io.read_trajectory``).
    out : path-like
        Output file, CSV or Parquet by extension; columns of ``Result.to_frame``.
    platform : Platform or path-like, optional
        As ``gsfric.models.platform_from``; default: the reference platform.
    mode : {"kinematic", "paper"}
    strict : bool
        ``StepFlagError`` at the first flagged step. Without it, at the end when more than
        ``FLAGGED_LIMIT`` (``gsfric.platform.usable``) of the steps are flagged, unless
        ``keep_flagged``; either way no output is written.
    chunk : int
        Steps read and differentiated at a time; memory grows with it (about 1.3 kB per
        step). They are evaluated and written ``EVALUATE_STEPS`` at a time.
    window, polyorder, n_threads :
        Smoothing of the differentiation (``iter_motions``); threads of the evaluation.
    progress : bool or None
        Progress bar on stderr (tqdm); None: only when stderr is a terminal.
    log_format : gsfric.io.LogFormat, optional
        Column map, units, angle convention and carried columns of the file. Measured F1..F6
        add ``F*_measured`` and ``F*_residual`` (measured minus model) to the output.
    columns : iterable of str, optional
        Output groups (``COLUMN_GROUPS``); default ``DEFAULT_COLUMN_GROUPS``. ``t`` and
        ``flag`` always.
    float32 : bool
        Outputs (not ``t``) as float32: relative error up to ``FLOAT32_RTOL``, half the file.
    keep_flagged : bool
        Write the output, with a warning, when up to half the steps are flagged.
    plot : path-like, optional
        Also a figure (PNG, SVG or PDF by the extension) of every leg's actuator force and
        prismatic friction over the record (``gsfric.simulate.figure``).
    uncertainty : bool
        The ``uncertainty`` group (sigma_F1..6, rest; kinematic mode), its warning above
        ``SIGMA_SHARE`` of a leg's peak force and a log's own rates against its differentiated
        poses (``Summary.rates``); False leaves them out.

    Returns
    -------
    Summary
        (Flags also as one ``GsfricWarning`` when not strict.)

    Raises
    ------
    InputTypeError, InputError
        An argument of the wrong type or value (``n_threads`` in 1..``MAX_THREADS``), a bad
        trajectory (row and column named) or output path (an input, a directory).
    OutputError
        The output could not be written (a full disk); an earlier file is unchanged.
    StepFlagError
        See ``strict``.
    """
    trajectory, out = as_path(trajectory, "trajectory"), as_path(out, "out")
    n_threads = as_count(n_threads, "n_threads", minimum=1, maximum=MAX_THREADS)
    strict = as_flag(strict, "strict")
    kind = _check_paths(trajectory, out, platform)
    platform = platform_from(platform)
    uncertainty = as_flag(uncertainty, "uncertainty") and mode == "kinematic"
    plan = _column_plan(columns, uncertainty)
    motions = iter_motions(trajectory, chunk=chunk, window=window, polyorder=polyorder,
                           log_format=log_format)
    plot = _checked_plot(plot, {"trajectory": trajectory, "platform": platform, "out": out})
    keep_flagged = as_flag(keep_flagged, "keep_flagged")
    smoothing = (window, polyorder) if uncertainty else None
    run = _Run(trajectory, out, platform, plan, mode=mode, strict=strict, n_threads=n_threads,
               float32=float32, progress=progress, keep_flagged=keep_flagged,
               trace=plot is not None, smoothing=smoothing)
    summary = _write_outputs(run, motions, kind, plot)
    _warn(summary, trajectory, uncertainty)
    return summary


def _column_plan(columns: Iterable[str] | None, uncertainty: bool) -> list:
    """The output columns (``evaluation.columns.plan``) of the groups ``columns`` (default
    ``DEFAULT_COLUMN_GROUPS``), the ``uncertainty`` group only when asked for."""
    groups = parse_columns(None) if columns is None else parse_columns(",".join(columns))
    if not uncertainty:                 # the paper mode's accelerations are its constants
        groups = tuple(g for g in groups if g != "uncertainty")
    return column_plan(groups)


def _checked_plot(plot: str | os.PathLike[str] | None, inputs: dict) -> Path | None:
    """The figure's path, checked before any work: not one of the ``inputs`` (name -> path or
    object), a known format, a writable place."""
    if plot is None:
        return None
    plot = as_path(plot, "plot")
    check_outputs([plot], inputs)
    check_figure(plot)
    check_output_place(plot)
    return plot


def _write_outputs(run: _Run, motions: Iterable[MotionChunk], kind: str,
                   plot: Path | None) -> Summary:
    """Evaluate and write every chunk of ``motions`` to the output of kind ``kind``, then the
    figure ``plot``: both or neither."""
    Writer.load(kind)
    with output_group():                # the table and the figure, both or neither
        try:
            run.write(motions, kind)
        finally:
            run.bar.close()
        summary = run.finish()
        if plot is not None and summary.trace is not None and summary.steps:
            write_figure(plot, summary.trace, summary.peaks.t0,
                         title=f"{run.trajectory.name}: {summary.steps} steps, "
                               f"{summary.flagged} flagged")
    return summary


def _warn(summary: Summary, trajectory: Path, uncertainty: bool) -> None:
    """The run's warnings on ``trajectory`` (``GsfricWarning``, pointing where
    ``simulate_file`` was called): a force that hinges on the differentiation (with
    ``uncertainty``), the flagged steps."""
    message = summary.uncertainty_message(trajectory) if uncertainty else None
    if message:
        warnings.warn(message, GsfricWarning, stacklevel=3)
    if summary.flagged:
        warnings.warn(summary.flag_message(trajectory) + f"; see the flag column of "
                      f"{summary.out}", GsfricWarning, stacklevel=3)


def check_chunk(platform, part: MotionChunk, trajectory: Path) -> None:
    """A chunk read from ``trajectory`` checked against the platform before any physics, by
    every command that evaluates a file (``gsfric.platform.usable``): its recorded poses
    (``check_poses``), its time gaps (``check_gaps``), and a measured-data file's forces
    F1..F6 (``models.check_measured_forces``: their unit and sign)."""
    motion = part.motion
    recorded = motion.recorded_poses()
    position, rotation = recorded if recorded is not None else (motion.position,
                                                                motion.rotation)
    check_poses(platform, position, rotation, motion.t, str(trajectory))
    check_gaps(motion.t, str(trajectory))
    if "F1" in part.carried:
        check_measured_forces(platform, motion, np.stack([part.carried[f"F{i}"] for i in range(1, 7)], axis=1),
                     str(trajectory))


def _check_paths(trajectory: Path, out: Path, platform) -> str:
    """The output's kind ("csv" or "parquet"; CSV for a device or FIFO without an extension,
    such as /dev/null or /dev/stdout), after checking the paths: ``out`` must not be the
    trajectory, nor the platform's file when ``platform`` is one."""
    check_outputs([out], {"trajectory": trajectory, "platform": platform})
    check_output_place(out)
    kind = "csv" if not out.suffix and is_stream(out) else table_kind(out)
    check_file(trajectory)
    return kind


@dataclass
class _Flags:
    """The flagged steps counted so far: their number, the count per kind (bit -> n), the
    first ``MAX_REPORTED`` global indices, in arrays of chunk after chunk, and the runs of
    consecutive flagged steps ([first time, last time, steps, last global index], times from
    ``t0``; the first ``MAX_RANGES`` of ``runs``)."""

    flagged: int = 0
    counts: dict[int, int] = field(default_factory=lambda: dict.fromkeys(FLAG_NAMES, 0))
    kept: list[np.ndarray] = field(default_factory=list)
    ranges: list[list] = field(default_factory=list)
    runs: int = 0
    t0: float | None = None

    def add(self, flag: np.ndarray, start: int, t: np.ndarray) -> bool:
        """Count a chunk's flags (N,) (its first step at global index ``start``, its times
        ``t`` (N,), s); whether any step is flagged."""
        if self.t0 is None and len(t):
            self.t0 = float(t[0])
        bad = np.flatnonzero(flag)
        if not bad.size:
            return False
        self.flagged += int(bad.size)
        for bit, n in flag_counts(flag).items():
            self.counts[bit] += n
        room = MAX_REPORTED - sum(len(k) for k in self.kept)
        if room > 0:
            self.kept.append(bad[:room] + start)
        self._add_runs(bad, start, np.asarray(t, dtype=np.float64) - self.t0)
        return True

    def _add_runs(self, bad: np.ndarray, start: int, t: np.ndarray) -> None:
        breaks = np.flatnonzero(np.diff(bad) > 1)
        firsts, lasts = np.r_[bad[0], bad[breaks + 1]], np.r_[bad[breaks], bad[-1]]
        for first, last in zip(firsts, lasts):
            if self.ranges and self.ranges[-1][3] == start + first - 1:   # across pieces
                run = self.ranges[-1]
                run[1], run[2], run[3] = float(t[last]), run[2] + int(last - first) + 1, \
                    start + int(last)
                continue
            self.runs += 1
            if len(self.ranges) < MAX_RANGES:
                self.ranges.append([float(t[first]), float(t[last]), int(last - first) + 1,
                                    start + int(last)])

    def fill(self, summary: Summary) -> None:
        summary.flagged = self.flagged
        summary.flagged_steps = np.concatenate(self.kept) if self.kept \
            else np.zeros(0, dtype=np.int64)
        summary.flag_counts = {FLAG_NAMES[bit]: n for bit, n in self.counts.items()}
        summary.flagged_ranges = [(a, b, n) for a, b, n, _ in self.ranges]
        summary.runs = self.runs


class _Writes:
    """The writes in flight in the writing thread, oldest first (at most two wait), and the
    last write from each of the two sets of evaluation outputs."""

    def __init__(self, pool: ThreadPoolExecutor, write_one: Callable[[Any], None]) -> None:
        self.pool, self.write_one = pool, write_one
        self.futures: list[Future] = []
        self.by_set: list[Future | None] = [None, None]

    def submit(self, ready: list, which: int | None) -> None:
        """Queue what is ready to be written, from the set ``which`` (None: no set to free)."""
        for item in ready:
            while len(self.futures) >= 2:
                self.futures.pop(0).result()
            self.futures.append(self.pool.submit(self.write_one, item))
            if which is not None:
                self.by_set[which] = self.futures[-1]

    def wait(self) -> None:
        for done in self.futures:
            done.result()


class _Run:
    """One ``simulate_file`` call: its options, the state shared by its three threads (the
    flags counted, the summary, the reused output buffers), and its stages.

    Three stages overlap, each in its own thread: reading and differentiating the next chunk
    (the calling thread, which queues at most two pieces of ``EVALUATE_STEPS`` ahead),
    evaluating piece k + 1 and queuing its write, building the columns of piece k and
    writing them (the compiled code, NumPy's copies and the Parquet writer run without the
    GIL). The evaluation's outputs and the columns' arrays are reused from piece to piece
    within the call (two sets of each, one being written while the other is filled)."""

    def __init__(self, trajectory: Path, out: Path, platform, plan, *, mode: str,
                 strict: bool, n_threads: int, float32: bool, progress: bool | None,
                 keep_flagged: bool = False, trace: bool = False,
                 smoothing: tuple[int | None, int] | None = None) -> None:
        self.trajectory, self.platform, self.plan = trajectory, platform, plan
        self.mode, self.strict, self.n_threads, self.float32 = mode, strict, n_threads, float32
        self.keep_flagged = keep_flagged
        self.summary = Summary(out=out, trace=Trace() if trace else None)
        self.flags = _Flags()
        self.evaluator: Evaluator | None = None
        show = sys.stderr.isatty() if progress is None else bool(progress)
        self.bar = tqdm(total=count_rows(trajectory) if show else None, unit="step",
                        unit_scale=True, desc="simulate", file=sys.stderr, disable=not show,
                        dynamic_ncols=True, leave=False)
        self.stopped = False                      # a stage failed: evaluate no more
        self.smoothing = smoothing                # (window, polyorder): compare own rates
        self.own_rates = None                     # a motion with the log's own rates
        self.sigma_squares, self.sigma_steps = np.zeros(6), 0   # sigma_F^2 summed, sliding
        self.sets: tuple[dict, dict] = ({}, {})   # the evaluation's outputs of even, odd chunks
        self.column_arrays: dict = {}             # the columns' arrays (of the writing thread)
        gains, delay = sensor_parameters(platform.effects)
        # a delay reaches across chunks: applied here, over the record, not per chunk
        self.shift = SensorDelay(gains, delay) if delay != 0.0 else None
        # the columns' arrays, those of the table of peaks and the figure (F among them, which
        # a sensor delay shifts)
        self.names = list(dict.fromkeys([*(key for _, key, _, _ in plan), *PEAK_ARRAYS,
                                         *(key for key, _ in SERIES)]))

    def write(self, motions: Iterable[MotionChunk], kind: str) -> None:
        """Evaluate every chunk and write it to the output, atomically."""
        mode_text = "wb" if kind == "parquet" else "w"
        options = {"newline": ""} if kind == "csv" else {}
        with atomic_write(self.summary.out, mode_text, inputs={"trajectory": self.trajectory},
                          **options) as handle, \
                ThreadPoolExecutor(1, thread_name_prefix="gsfric-evaluate") as evaluation, \
                ThreadPoolExecutor(1, thread_name_prefix="gsfric-write") as output:
            writer = Writer(handle, kind)
            writes = _Writes(output, functools.partial(self._write_one, writer))
            pending: deque[Future] = deque()     # the evaluations queued or running
            try:
                for k, part in enumerate(_pieces(self._checked(motions), EVALUATE_STEPS)):
                    if self.evaluator is None:
                        self.evaluator = Evaluator(self.platform, mode=self.mode,
                                                   n_threads=self.n_threads)
                    while len(pending) >= 2:
                        pending.popleft().result()
                    pending.append(evaluation.submit(self._evaluate, part, k % 2, writes))
                    del part
                self._drain(pending, writes)
                check_flagged(self.platform, self.flags.counts, self.flags.flagged,
                              self.summary.steps, str(self.trajectory))
                if not self.keep_flagged:
                    self.flags.fill(self.summary)
                    check_flagged_share(self.flags.flagged, self.summary.steps,
                                        str(self.trajectory), self.summary.ranges_text())
            except BaseException:
                self.stopped = True         # the evaluations queued return at once
                for future in [*pending, *list(writes.futures)]:
                    with contextlib.suppress(BaseException):
                        future.result()
                for future in list(writes.futures):  # any the last evaluations queued
                    with contextlib.suppress(BaseException):
                        future.result()
                writer.abandon()
                raise
            writer.close()

    def _checked(self, motions: Iterable[MotionChunk]) -> Iterator[MotionChunk]:
        """The chunks, each checked (``_check_usable``) and counted as it is read."""
        for part in motions:
            self.summary.windows = part.windows
            self._check_usable(part)
            self.summary.chunks += 1
            yield part

    def _check_usable(self, part: MotionChunk) -> None:
        """The chunk's poses (and measured forces) checked against the platform before any
        physics (``gsfric.platform.usable``); the differentiation noted in the summary."""
        motion = part.motion
        check_chunk(self.platform, part, self.trajectory)
        if not self.summary.differentiation:
            self.summary.differentiation = describe_differentiation(part)
            how = motion.differentiation()
            if how is not None and how.rates:
                self.own_rates = motion

    def _drain(self, pending: deque[Future], writes: _Writes) -> None:
        """Wait for the evaluations left and their writes, and write what waits for the
        sensor delay."""
        while pending:
            pending.popleft().result()
        if self.shift is not None:
            writes.submit(self.shift.finish(), None)
        writes.wait()

    def _evaluate(self, part: MotionChunk, which: int, writes: _Writes) -> None:
        """Evaluate a piece into the output set ``which`` (0 or 1) and count its flags, then
        queue its writing (in the evaluation thread, one piece after the other; no warnings
        issued): (outputs, carried columns) that the writing thread makes columns of, or,
        with a sensor delay, the column dicts that are ready. The set's last write is waited
        for before its arrays are overwritten."""
        if self.stopped:
            return
        try:
            self._evaluate_piece(part, which, writes)
        except BaseException:
            self.stopped = True             # the pieces queued after this one are not run
            raise

    def _evaluate_piece(self, part: MotionChunk, which: int, writes: _Writes) -> None:
        buffers_free = writes.by_set[which]
        if buffers_free is not None:
            buffers_free.result()
        start, motion = part.start, part.motion
        arrays, flag = evaluate_outputs(self.evaluator, motion, self.names,
                                        buffers=self.sets[which], sensor=self.shift is None,
                                        start=start)
        self.summary.peaks.add(motion.t, arrays, flag)
        if self.summary.trace is not None:
            self.summary.trace.add(motion.t, arrays, flag)
        if self.flags.add(flag, start, motion.t) and self.strict:
            self.summary.steps = start + len(motion)
            self.flags.fill(self.summary)
            raise StepFlagError(
                self.summary.flag_message(self.trajectory)
                + " (--strict: stopped at the first chunk with flagged steps; "
                "no output written)")
        self._uncertainty(arrays)
        outputs = ChunkOutputs(np.asarray(motion.t, dtype=np.float64), arrays, flag)
        if self.shift is None:
            writes.submit([(outputs, part.carried)], which)
        else:
            good = (flag & FLAG_NONFINITE) == 0
            writes.submit(self.shift.add(outputs.t, arrays["F"], good, functools.partial(
                delayed_columns, result_columns(outputs, self.plan, self.float32), self.plan,
                self.float32, part.carried)), None)
        self.summary.steps = start + len(motion)
        self.bar.update(len(motion))

    def _uncertainty(self, arrays: dict) -> None:
        """Count a piece's sigma_F per leg where the legs slide and its steps with a leg
        possibly at rest into the summary."""
        summary = self.summary
        if "sigma_F" not in arrays or "rest" not in arrays:
            return
        resting = np.nan_to_num(arrays["rest"]).reshape(-1) != 0
        summary.rest_steps += int(np.count_nonzero(resting))
        sliding = arrays["sigma_F"][~resting]
        self.sigma_squares += np.nansum(sliding ** 2, axis=0)
        self.sigma_steps += len(sliding)
        if self.sigma_steps:
            summary.sliding_sigma_F = np.sqrt(self.sigma_squares / self.sigma_steps)

    def _write_one(self, writer: Writer, item) -> None:
        """Write one chunk (in the writing thread): its columns first, from ``ChunkOutputs``."""
        if isinstance(item, tuple):
            outputs, carried = item
            item = with_carried(result_columns(outputs, self.plan, self.float32,
                                               reuse=self.column_arrays), carried)
        writer.write(item)

    def finish(self) -> Summary:
        """The summary, its flags and the comparison of the log's own rates filled in."""
        self.flags.fill(self.summary)
        if self.own_rates is not None and self.smoothing is not None \
                and self.evaluator is not None:
            self.summary.rates = compare_rates(self.evaluator, self.own_rates, *self.smoothing)
        return self.summary
