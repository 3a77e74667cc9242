"""The streamed motion estimate: a trajectory file as consecutive Motions of at most a chunk
of steps.

Exactness. A file of at most ``chunk`` rows is read and differentiated whole, exactly as
``gsfric.io.read_trajectory`` does. A longer file must be uniformly sampled (every time step
within ``UNIFORM_RTOL`` of the first chunk's mean step) and is differentiated with a
Savitzky-Golay filter of one fixed window per signal (position, quaternion): the ``window``
given, or the one chosen by generalized cross-validation on the first chunk (as
``Motion.from_samples`` chooses it on a whole file). Each chunk is filtered together with its
neighbours' samples within the window (an overlap of half a window on each side, a whole
window at the ends of the file), so every step gets the value that filtering the whole file at
once with that window gives (to rounding). Quaternion signs are made continuous across
chunk boundaries.

Checks. Every row is checked as ``read_trajectory`` checks it (``gsfric.simulate.blocks``);
the angles are never differentiated, the quaternions are.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gsfric._threads import in_parallel
from gsfric.errors import InputError
from gsfric.io.logs import EULER, QUATERNION, RATES
from gsfric.io.readers import motion_from_columns
from gsfric.signal.noise import white_noise_std
from gsfric.signal.rotations import angular_rates, continuous_quaternions, rotation_from_quaternion
from gsfric.signal.savgol import (
    DEFAULT_POLYORDER,
    check_polyorder,
    check_window,
    savgol_core,
    savgol_derivatives,
    savgol_gains,
)
from gsfric.signal.windows import gcv_window
from gsfric.simulate.blocks import Block, EulerWatch, read_blocks
from gsfric.trajectory import MIN_SAMPLES, UNIFORM_RTOL, Motion, RateUncertainty

DEFAULT_CHUNK = 100_000
"""Steps per chunk of ``simulate_file`` (about 0.5 GB of working memory)."""

NOISE_ROWS = 20_000
"""Rows at the start of a streamed file whose white pose noise stands for the whole file's in
the rates' standard deviations (``RateUncertainty``): a robust scale from 20,000 samples is
within about 1 % of the noise level, at a fifth of the cost of a whole chunk's."""


@dataclass(frozen=True)
class MotionChunk:
    """One Motion of a trajectory file read by ``iter_motions``.

    Attributes
    ----------
    start : int
        0-based index of the Motion's first step in the file (= its data row minus 1).
    motion : Motion
        The differentiated steps ``start .. start + len(motion) - 1``.
    windows : tuple (position, quaternion) of int, "whole" or None
        Savitzky-Golay windows of a streamed file; "whole" for a file read in one piece with
        a Savitzky-Golay filter (windows as ``Motion.from_samples`` chose them), None for one
        read in one piece with a smoothing spline (non-uniform sampling).
    carried : dict of str -> ndarray (len(motion),)
        The columns carried to the output for these steps: F1..F6 of a measured-data file,
        ``keep:NAME`` columns; empty when the file has none.
    """

    start: int
    motion: Motion
    windows: Any
    carried: dict[str, np.ndarray]


def iter_motions(path: str | os.PathLike[str], *, chunk: int = DEFAULT_CHUNK,
                 window: int | None = None, polyorder: int = DEFAULT_POLYORDER,
                 log_format=None) -> Iterator[MotionChunk]:
    """The trajectory file as consecutive Motions of at most ``chunk`` steps.

    Parameters
    ----------
    path : path-like
        Trajectory file, CSV or Parquet (columns as for ``gsfric.io.read_trajectory``).
    chunk : int
        Steps per Motion (>= ``MIN_SAMPLES``); memory is proportional to it.
    window, polyorder :
        Savitzky-Golay window (odd, samples; None: chosen on the first chunk) and order.
    log_format : gsfric.io.LogFormat, optional
        Column map, units and angle convention of the file.

    Yields
    ------
    MotionChunk
        In file order; concatenated, the Motions are the whole file's differentiation (see
        the module's docstring).

    Raises
    ------
    InputError
        As ``read_trajectory``, with the file's rows; also a non-uniform time step in a file
        longer than one chunk, or a window longer than the chunk.
    """
    path = Path(path)
    chunk = _checked_chunk(chunk, window)
    blocks = read_blocks(path, chunk, log_format)
    carry = _Carry()
    first: list[Block] = []
    count = 0
    for block in blocks:
        first.append(block)
        carry.add(block)
        count += len(block.t)
        if count > chunk:
            break
    if count <= chunk:
        motion = _whole(path, first, window, polyorder)
        how = motion.differentiation()
        windows = "whole" if how is not None and how.even else None
        yield MotionChunk(0, motion, windows, carry.take(len(motion)))
        return
    if any(group[0] in first[0].columns for group in RATES.values()):
        raise InputError(f"{path}: the log's own rates (velocity or acceleration columns) "
                         f"are read with the file whole: give a --chunk above its {count}+ "
                         "rows, or leave the rate columns out of the column map")
    watch = EulerWatch(path)
    for block in first:
        watch.add(block)
    samples = _Samples.first_chunk(path, first, chunk, window, polyorder)
    del first
    while True:
        while samples.chunk_ready():
            yield samples.next_chunk(carry, end_of_file=False)
        block = next(blocks, None)
        if block is None:
            break
        carry.add(block)
        watch.add(block)
        samples.add(block)
    watch.finish()
    if samples.done < samples.total:
        yield samples.next_chunk(carry, end_of_file=True)


def _checked_chunk(chunk: object, window: object) -> int:
    if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) \
            or chunk < MIN_SAMPLES:
        raise InputError(f"chunk: must be an integer >= {MIN_SAMPLES}, got {chunk!r}")
    chunk = int(chunk)
    if window is not None and isinstance(window, (int, np.integer)) \
            and not isinstance(window, bool) and window > chunk:
        raise InputError(f"window = {window} is longer than the chunk of {chunk} steps; "
                         "use a larger chunk")
    return chunk


def _whole(path: Path, blocks: list[Block], window, polyorder) -> Motion:
    """The file as ``read_trajectory`` reads it (it fits in one chunk)."""
    n = sum(len(b.t) for b in blocks)
    if n < MIN_SAMPLES:
        raise InputError(f"{path}: {n} data rows; at least {MIN_SAMPLES} are needed "
                         "to differentiate the motion")
    names = blocks[0].columns.keys()
    columns = {name: np.concatenate([b.columns[name] for b in blocks]) for name in names}
    orientation = QUATERNION if "qw" in columns else EULER
    return motion_from_columns(path, columns, orientation, window, polyorder)


class _Carry:
    """The carried columns of the blocks read, handed out row by row in file order."""

    def __init__(self) -> None:
        self.parts: list[dict[str, np.ndarray]] = []

    def add(self, block: Block) -> None:
        if block.carried:
            self.parts.append(block.carried)

    def take(self, n: int) -> dict[str, np.ndarray]:
        """The next ``n`` rows of the carried columns (removed from the queue)."""
        taken: list[dict] = []
        got = 0
        while got < n and self.parts:
            head = self.parts[0]
            size = len(next(iter(head.values())))
            if got + size <= n:
                taken.append(self.parts.pop(0))
                got += size
            else:
                k = n - got
                taken.append({key: v[:k] for key, v in head.items()})
                self.parts[0] = {key: v[k:] for key, v in head.items()}
                got = n
        if not taken:
            return {}
        return {key: np.concatenate([p[key] for p in taken]) for key in taken[0]}


# -- the streamed file --------------------------------------------------------------------------


class _Samples:
    """The samples of a streamed file still needed, and where the next chunk starts.

    ``t``, ``position``, ``q`` (sign-continuous) hold the file's samples from global index
    ``start``; ``done`` is the global index of the next chunk's first step. A chunk's steps are
    filtered with half the longest window of samples on each side (a whole window at an end of
    the file); samples no chunk needs any more are dropped."""

    def __init__(self, path: Path, t: np.ndarray, position: np.ndarray, q: np.ndarray,
                 step: float, windows: tuple[int, int], polyorder: int, chunk: int) -> None:
        self.path, self.step, self.windows = path, step, windows
        self.polyorder, self.chunk = polyorder, chunk
        self.width = max(windows)          # samples the filter needs at an end of the file
        self.half = self.width // 2        # overlap on each side of an interior chunk
        self.t, self.position, self.q = t, position, q
        self.start = 0
        self.done = 0
        # the pose noise of the first rows stands for the file's (``RateUncertainty``)
        rows = min(chunk, NOISE_ROWS)
        self.noise = (white_noise_std(position[:rows]),
                      np.full(3, 2.0 * np.sqrt(np.mean(white_noise_std(q[:rows]) ** 2))))

    @classmethod
    def first_chunk(cls, path: Path, blocks: list[Block], chunk: int, window, polyorder
                    ) -> _Samples:
        """The samples of the first blocks (more than ``chunk`` rows), with the time step and
        the windows they give."""
        t = np.concatenate([b.t for b in blocks])
        position = np.concatenate([b.position for b in blocks])
        q = continuous_quaternions(np.concatenate([b.quaternion for b in blocks]))
        step = (t[chunk - 1] - t[0]) / (chunk - 1)
        if not np.isfinite(step) or step <= 0:
            raise InputError(f"{path}: t spans too large a range")
        _check_uniform(path, t, step, 0, chunk)
        windows = _windows(path, position[:chunk], q[:chunk], chunk, window, polyorder)
        return cls(path, t, position, q, step, windows, polyorder, chunk)

    @property
    def total(self) -> int:
        """Samples read so far."""
        return self.start + len(self.t)

    def add(self, block: Block) -> None:
        """Append a block, checking its time steps and continuing the quaternions' signs."""
        _check_uniform(self.path, np.concatenate([self.t[-1:], block.t]), self.step,
                       block.start - 1, self.chunk)
        q_new = continuous_quaternions(np.vstack([self.q[-1:], block.quaternion]))[1:]
        self.t = np.concatenate([self.t, block.t])
        self.position = np.concatenate([self.position, block.position])
        self.q = np.concatenate([self.q, q_new])

    def chunk_ready(self) -> bool:
        """Whether a whole chunk and the samples after it that its filter needs are read."""
        return self.done + self.chunk + self.half <= self.total

    def next_chunk(self, carry: _Carry, end_of_file: bool) -> MotionChunk:
        """The next chunk's Motion: ``chunk`` steps, or every step left at the end of the file."""
        stop = self.total if end_of_file else self.done + self.chunk
        lo = max(0, self.done - self.half)
        if end_of_file:
            lo = max(0, min(lo, self.total - self.width))
        hi = self.total if end_of_file else min(self.total, max(stop + self.half, self.width))
        a, b = lo - self.start, hi - self.start
        core = slice(self.done - lo, stop - lo)
        with np.errstate(all="ignore"):
            motion = _differentiate(self.t[a:b], self.position[a:b], self.q[a:b], self.windows,
                                    self.polyorder, self.step, core, (self.path, self.done))
        object.__setattr__(motion, "_uncertainty", _uncertainty(
            b - a, core, self.windows, self.polyorder, self.step, self.noise))
        start, self.done = self.done, stop
        self._drop(max(0, self.done - self.width) - self.start)
        return MotionChunk(start, motion, self.windows, carry.take(len(motion)))

    def _drop(self, n: int) -> None:
        if n > 0:
            self.t, self.position, self.q = self.t[n:], self.position[n:], self.q[n:]
            self.start += n


def _windows(path: Path, position: np.ndarray, q: np.ndarray, chunk: int, window,
             polyorder) -> tuple[int, int]:
    """The Savitzky-Golay windows (position, quaternion) of a streamed file: ``window``, or
    chosen by cross-validation on the first chunk's samples."""
    check_polyorder(polyorder, chunk, "steps in a chunk")
    if window is None:
        with np.errstate(all="ignore"):
            windows = in_parallel(lambda: gcv_window(position, polyorder),
                                  lambda: gcv_window(q, polyorder))
        return windows[0], windows[1]
    try:
        check_window(window, polyorder, chunk)
    except InputError as error:
        raise type(error)(f"{path}: {error}") from None
    return int(window), int(window)


def _check_uniform(path: Path, t: np.ndarray, step: float, start: int, chunk: int) -> None:
    """Every step of ``t`` (first sample at global index ``start``) within tolerance of ``step``."""
    steps = np.diff(t)
    bad = np.flatnonzero(~(np.abs(steps - step) <= UNIFORM_RTOL * step))
    if len(bad):
        i = int(bad[0])
        raise InputError(f"{path}: row {start + i + 2}: time step {steps[i]:.6g} s differs from "
                         f"the first {chunk} rows' mean step {step:.6g} s; a file longer than "
                         "one chunk must be uniformly sampled: resample it, or give a chunk "
                         "larger than the file to evaluate it whole")


def _differentiate(t, position, q, windows, polyorder, step, core: slice,
                   where: tuple[Path, int]) -> Motion:
    """Savitzky-Golay smoothing and derivatives as ``Motion.from_samples``; the core steps.

    Where the core has half a window of samples on each side (every chunk but those at the
    ends of the file), the filter is applied to the core only (``savgol_core``); at the ends
    of the file, ``savgol_derivatives`` fits the edges."""
    wp, wq = windows
    lo, hi = core.start, core.stop
    if lo >= max(windows) // 2 and len(t) - hi >= max(windows) // 2:
        p0, p1, p2 = savgol_core(position, wp, polyorder, step, lo, hi)
        q0, q1, q2 = savgol_core(q, wq, polyorder, step, lo, hi)
    else:
        p0, p1, p2 = (a[core] for a in savgol_derivatives(position, wp, polyorder, step))
        q0, q1, q2 = (a[core] for a in savgol_derivatives(q, wq, polyorder, step))
    omega, alpha = angular_rates(q0, q1, q2)
    _check_finite((p0, p1, p2, q0, omega, alpha), where)
    # every value checked above (t by the reader): no second validation pass
    return Motion._trusted(t[core], p0, rotation_from_quaternion(q0), p1, omega, p2, alpha)


def _uncertainty(n: int, core: slice, windows: tuple[int, int], polyorder: int, step: float,
                 noise: tuple[np.ndarray, np.ndarray]) -> RateUncertainty:
    """The rates' standard deviations of a chunk's core steps (``RateUncertainty``): the fixed
    filters' noise gains on its n samples times the first chunk's pose noise (position (3,),
    m; the angular rates' (3,), twice the quaternion's)."""
    sigma = []
    rows = core.stop - core.start
    for k in (1, 2):
        for window, level in zip(windows, noise):
            half = window // 2
            if core.start >= half and n - core.stop >= half:       # centred filters only
                centre = savgol_gains(window, window, polyorder, k)[half] / step ** k
                sigma.append(np.broadcast_to(centre * level, (rows, 3)))
            else:
                gain = savgol_gains(n, window, polyorder, k)[core] / step ** k
                sigma.append(gain[:, None] * level[None, :])
    return RateUncertainty(*sigma)


def _check_finite(parts: tuple[np.ndarray, ...], where: tuple[Path, int]) -> None:
    """Raise ``InputError`` naming the rows (the core's first at 0-based ``where[1]``) where
    a differentiated array (N, k) is not finite."""
    if all(np.isfinite(a).all() for a in parts):
        return
    finite = np.ones(len(parts[0]), dtype=bool)
    for a in parts:
        finite &= np.isfinite(a).all(axis=1)
    bad = np.flatnonzero(~finite)
    raise InputError(f"{where[0]}: rows {where[1] + bad[0] + 1}-{where[1] + bad[-1] + 1}: "
                     "differentiation gave non-finite values (values or time steps out "
                     "of range)")
