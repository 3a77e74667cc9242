"""Streamed evaluation of trajectory files of any length, in bounded memory.

``simulate_file`` reads a trajectory file (CSV or Parquet) in chunks of ``chunk`` rows,
differentiates each chunk, evaluates it, and appends its rows to the output, so that memory
stays bounded by the chunk size however long the file is (10 million steps in well under 2 GB,
see docs/robustness.md). It is what ``gsfric simulate`` runs.

Exactness. A file of at most ``chunk`` rows is read and differentiated whole, exactly as
``gsfric.io.read_trajectory`` does. A longer file must be uniformly sampled (every time step
within ``UNIFORM_RTOL`` of the first chunk's mean step) and is differentiated with a
Savitzky-Golay filter of one fixed window per signal (position, quaternion): the ``window``
given, or the one chosen by generalized cross-validation on the first chunk (as
``Motion.from_samples`` chooses it on a whole file). Each chunk is filtered together with its
neighbours' samples within the window (an overlap of half a window on each side, a whole
window at the ends of the file), so every step gets the value that filtering the whole file at
once with that window gives (to rounding). Quaternion signs are made continuous across
chunk boundaries. The sensor's ``time_offset`` (``gsfric.catalog``) interpolates F between
steps that may lie in a neighbouring chunk: it is applied across chunks (``_Delay``), with the
values ``evaluate`` gives over the whole file.

Checks. Every row is checked as ``read_trajectory`` checks it (numbers, finite, increasing
times), with the file's 1-based data row in the message. Euler input is checked for angles
that look like degrees (a warning when first seen) and for jumps of alpha or gamma near
beta = 0 (one warning at the end naming the rows); the angles are never differentiated, the
quaternions are. Step flags (``gsfric.evaluation``) are gathered over the whole file with
their global step indices and reported at the end as one warning, or, with ``strict``, as a
``StepFlagError`` at the first chunk with a flagged step.

Output. Rows are appended to a temporary file in the output's directory (a Parquet row group
or a CSV block per chunk) that is renamed onto the output only when every chunk succeeded;
on any error or a KeyboardInterrupt it is removed and an existing output is left untouched.
The columns are those of the chosen groups (``DEFAULT_COLUMN_GROUPS`` unless told; the
formats are described in docs/formats.md). Reading and differentiating, evaluating, and
building the columns and writing run in three threads, chunk after chunk.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import warnings
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.ndimage import correlate1d
from tqdm import tqdm

from gsfric.errors import GsfricWarning, InputError, StepFlagError
from gsfric.evaluation.columns import (
    DEFAULT_GROUPS as DEFAULT_COLUMN_GROUPS,  # written by default
)
from gsfric.evaluation.columns import (
    GROUPS as COLUMN_GROUPS,  # output groups of --columns
)
from gsfric.evaluation.columns import arrow_table
from gsfric.evaluation.columns import (
    plan as _column_plan,  # the columns from gsfric.columns
)
from gsfric.evaluation.evaluator import (
    FLAG_NAMES,
    FLAG_NONFINITE,
    Evaluator,
    evaluate_outputs,
)
from gsfric.io.files import atomic_write
from gsfric.io.logs import EULER, FORCES, QUATERNION, ColumnReader
from gsfric.io.readers import motion_from_columns
from gsfric.io.tables import (
    check_file,
    check_unique_columns,
    count_rows,
    csv_options,
    field_count_problem,
    table_kind,
)
from gsfric.models import reference_platform
from gsfric.platform.catalog import sensor_parameters
from gsfric.signal.rotations import (
    continuous_quaternions,
    quaternion_conjugate,
    quaternion_from_euler,
    quaternion_multiply,
)
from gsfric.signal.savgol import (
    DEFAULT_POLYORDER,
    gcv_window,
    savgol_derivatives,
    savgol_weights,
)
from gsfric.trajectory import (
    GIMBAL_JUMP,
    GIMBAL_SIN_BETA,
    MIN_SAMPLES,
    UNIFORM_RTOL,
    Motion,
    _check_window,
    is_uniform,
)

DEFAULT_CHUNK = 100_000
"""Steps per chunk of ``simulate_file`` (about 0.5 GB of working memory)."""

MAX_REPORTED = 10_000
"""Flagged step indices kept for the summary (the count is always exact)."""

# -- reading in blocks --------------------------------------------------------------------------


def _csv_blocks(path: Path, rows: int):
    """DataFrames of at most ``rows`` rows; errors as ``read_table`` gives them."""

    def parse_error(error: Exception) -> InputError:
        reason = field_count_problem(path) or str(error)
        return InputError(f"{path}: cannot parse as CSV: {reason}")

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", pd.errors.ParserWarning)
            reader = pd.read_csv(path, chunksize=rows, **csv_options())
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: file is empty (no header line)") from None
    except UnicodeDecodeError as error:
        raise InputError(f"{path}: not UTF-8 text (byte {error.start})") from None
    except (ValueError, OverflowError, pd.errors.ParserError, pd.errors.ParserWarning) as error:
        raise parse_error(error) from None
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    with reader:
        while True:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", pd.errors.ParserWarning)
                    frame = next(reader)
            except StopIteration:
                return
            except UnicodeDecodeError as error:
                raise InputError(f"{path}: not UTF-8 text (byte {error.start})") from None
            except (ValueError, OverflowError, pd.errors.ParserError,
                    pd.errors.ParserWarning) as error:
                raise parse_error(error) from None
            except OSError as error:
                raise InputError(f"{path}: cannot read ({error.strerror})") from None
            names = [str(c) for c in frame.columns]
            check_unique_columns(path, names)
            frame.columns = names
            yield frame


def _parquet_blocks(path: Path, rows: int):
    import pyarrow
    import pyarrow.parquet as pq

    errors = (pyarrow.ArrowException, ValueError, TypeError, OSError, NotImplementedError)
    try:
        # without pre-buffering: pre-buffered row groups stay cached in the reader, so memory
        # would grow by a row group for every row group read
        source = pq.ParquetFile(path, pre_buffer=False)
        names = [str(n) for n in source.schema_arrow.names]
    except errors as error:
        raise InputError(f"{path}: cannot read as Parquet: {error}") from None
    if len(set(names)) != len(names):
        raise InputError(f"{path}: a column name appears more than once")
    if source.metadata.num_rows == 0:

        yield pd.DataFrame({n: [] for n in names})
        return

    batches = source.iter_batches(batch_size=rows)
    while True:
        try:
            batch = next(batches)
            frame = pd.DataFrame({name: _numpy(batch.column(i)) for i, name in enumerate(names)},
                                 copy=False)
        except StopIteration:
            return
        except errors as error:
            raise InputError(f"{path}: cannot read as Parquet: {error}") from None
        yield frame


def _numpy(array):
    """A column of a record batch as NumPy: floats without nulls as a view of the Arrow buffer
    (no copy), anything else as pandas converts it (nulls, strings, timestamps...)."""
    import pyarrow as pa

    if array.null_count == 0 and (pa.types.is_floating(array.type)
                                  or pa.types.is_integer(array.type)):
        return array.to_numpy(zero_copy_only=True)
    return array.to_pandas()


@dataclass
class _Block:
    """Validated samples of consecutive data rows starting at global row ``start`` (0-based)."""

    start: int
    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray       # normalized, not yet sign-continuous
    euler: np.ndarray | None     # when the orientation is given as ZXZ angles
    columns: dict[str, np.ndarray]


def _blocks(path: Path, rows: int, log_format=None, carry=None) -> Iterator[_Block]:
    """Validated blocks of the trajectory file; messages name 1-based data rows.

    ``carry``: a list to which each block's carried columns (F1..F6 of a measured-data file
    and ``keep:NAME`` columns) are appended as a dict, in order.
    """
    kind = check_file(path)
    reader = ColumnReader(path, log_format)
    frames = _csv_blocks(path, rows) if kind == "csv" else _parquet_blocks(path, rows)
    start = 0
    last_t = None
    orientation = None
    for frame in frames:
        names = [name.strip() for name in frame.columns]
        if orientation is None:
            if len(set(names)) != len(names):
                duplicate = next(n for n in names if names.count(n) > 1)
                raise InputError(f"{path}: column {duplicate!r} appears more than once")
            orientation = reader.check(names)
        if len(frame) == 0:
            continue
        frame.columns = names
        columns = reader.read(frame, first_row=start)
        if carry is not None and (reader.forces or reader.keep):
            carry.append({k: v for k, v in columns.items()
                          if k in FORCES or k.startswith("keep:")})
        t = columns["t"]
        with np.errstate(over="ignore", invalid="ignore"):
            steps = np.diff(t if last_t is None else np.concatenate([[last_t], t]))
        bad = np.flatnonzero(steps <= 0)
        if len(bad):
            local = int(bad[0]) + (1 if last_t is None else 0)   # index in t of the bad row
            previous = t[local - 1] if local > 0 else last_t
            row = start + local + 1
            if steps[bad[0]] == 0:
                raise InputError(f"{path}: row {row}: duplicate time t = {float(t[local])!r} "
                                 f"(same as row {row - 1})")
            raise InputError(f"{path}: row {row}: t = {float(t[local])!r} is less than "
                             f"t = {float(previous)!r} in row {row - 1}; t must increase")
        position = np.stack([columns[n] for n in ("x", "y", "z")], axis=1)
        angles = np.stack([columns[n] for n in orientation], axis=1)
        if orientation == QUATERNION:
            norms = np.linalg.norm(angles, axis=1)
            zero = np.flatnonzero(norms < 1e-12)
            if len(zero):
                raise InputError(f"{path}: row {start + int(zero[0]) + 1}: quaternion of "
                                 "zero length")
            q, euler = angles / norms[:, None], None
        else:
            q, euler = quaternion_from_euler(*angles.T), angles
        yield _Block(start, t, position, q, euler, columns)
        start += len(t)
        last_t = t[-1]
    if orientation is None or start == 0:
        raise InputError(f"{path}: no data rows")


# -- Euler checks across blocks -----------------------------------------------------------------


class _EulerWatch:
    """The checks of ``Motion.from_samples`` on ZXZ angles, gathered over blocks."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.warned_degrees = False
        self.previous: np.ndarray | None = None
        self.jumps: list[int] = []
        self.jump_count = 0

    def add(self, block: _Block) -> None:
        euler = block.euler
        if euler is None:
            return
        largest = np.abs(euler).max(axis=0)
        if not self.warned_degrees and (largest > 2 * np.pi).any():
            self.warned_degrees = True
            big = [f"|{name}| up to {value:.4g}"
                   for name, value in zip(("alpha", "beta", "gamma"), largest)
                   if value > 2 * np.pi]
            warnings.warn(f"{self.path}: angles look like degrees ({', '.join(big)} > 2*pi, "
                          f"first seen in rows {block.start + 1}-{block.start + len(euler)}); "
                          "angles must be in radians", GsfricWarning, stacklevel=2)
        joined = euler if self.previous is None else np.vstack([self.previous, euler])
        offset = block.start - (0 if self.previous is None else 1)
        near = np.abs(np.sin(joined[:, 1])) < GIMBAL_SIN_BETA
        near = near[1:] | near[:-1]
        steps = np.abs((np.diff(joined[:, [0, 2]], axis=0) + np.pi) % (2 * np.pi) - np.pi)
        jumps = np.flatnonzero(near & (steps.max(axis=1) > GIMBAL_JUMP)) + 1 + offset
        self.jump_count += len(jumps)
        self.jumps.extend(int(j) for j in jumps[:max(0, 10 - len(self.jumps))])
        self.previous = euler[-1:].copy()

    def finish(self) -> None:
        if self.jump_count:
            rows = ", ".join(str(j + 1) for j in self.jumps)
            more = f" and {self.jump_count - len(self.jumps)} more" \
                if self.jump_count > len(self.jumps) else ""
            word = "rows" if self.jump_count > 1 else "row"
            warnings.warn(f"{self.path}: ZXZ angles near beta = 0 (where alpha and gamma are "
                          f"ill-defined) jump by more than {GIMBAL_JUMP} rad in alpha or gamma "
                          f"at {word} {rows}{more}; give the orientation as a quaternion "
                          "(qw, qx, qy, qz) instead", GsfricWarning, stacklevel=2)


# -- chunked differentiation --------------------------------------------------------------------


def _whole(path: Path, blocks: list[_Block], window, polyorder) -> Motion:
    """The file as ``read_trajectory`` reads it (it fits in one chunk)."""
    n = sum(len(b.t) for b in blocks)
    if n < MIN_SAMPLES:
        raise InputError(f"{path}: {n} data rows; at least {MIN_SAMPLES} are needed "
                         "to differentiate the motion")
    names = blocks[0].columns.keys()
    columns = {name: np.concatenate([b.columns[name] for b in blocks]) for name in names}
    orientation = QUATERNION if "qw" in columns else EULER
    return motion_from_columns(path, columns, orientation, window, polyorder)


@functools.lru_cache(maxsize=16)
def _savgol_coefficients(window: int, polyorder: int) -> np.ndarray:
    """(3, window) Savitzky-Golay weights of the value and the first two derivatives (unit
    sample step), applied as ``sum_j c[k, j] y[i - window // 2 + j]``: those of
    ``trajectory.savgol_filter`` away from the ends of the signal. Read-only."""
    c = np.stack([savgol_weights(window, polyorder, k) for k in (0, 1, 2)])
    c.flags.writeable = False
    return c


def _savgol_core(y: np.ndarray, window: int, polyorder: int, step: float,
                 lo: int, hi: int) -> list[np.ndarray]:
    """The value and first two derivatives (``savgol_derivatives``) of y (N, k) at rows lo..hi-1, which
    have ``window // 2`` samples on each side: contiguous (hi - lo, k) arrays, equal to the
    last bit to ``trajectory.savgol_filter``'s there (the same ``scipy.ndimage.correlate1d``
    with the same weights, run on the rows it needs only)."""

    c = _savgol_coefficients(window, polyorder)
    h = window // 2
    block = y[lo - h:hi + h]
    out = []
    for k in (0, 1, 2):
        value = correlate1d(block, c[k], axis=0)[h:h + hi - lo]
        if k:
            value /= step ** k
        out.append(value)
    return out




def _cross_into(out: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``out[:] = a x b`` row by row, (N, 3)."""
    for i, (j, k) in enumerate(((1, 2), (2, 0), (0, 1))):
        np.subtract(a[:, j] * b[:, k], a[:, k] * b[:, j], out=out[:, i])
    return out


def _rates(q0: np.ndarray, q1: np.ndarray, q2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angular velocity and acceleration (N, 3), base frame, from a quaternion signal and its
    first two derivatives (N, 4), not necessarily of unit length: ``omega = 2 vec(q1 q0*) /
    |q0|^2``, ``alpha = 2 vec(q2 q0*) / |q0|^2 - omega 2 (q0 . q1) / |q0|^2`` (as
    ``_differentiate``'s quaternion products), with ``vec(p q0*) = w0 vp - wp v0 + v0 x vp``."""
    w0, v0 = q0[:, :1], q0[:, 1:]
    squared = np.einsum("ij,ij->i", q0, q0)[:, None]
    dot01 = np.einsum("ij,ij->i", q0, q1)[:, None]
    cross = np.empty((len(q0), 3))
    omega = w0 * q1[:, 1:]
    omega -= q1[:, :1] * v0
    omega += _cross_into(cross, v0, q1[:, 1:])
    omega *= 2
    omega /= squared
    alpha = w0 * q2[:, 1:]
    alpha -= q2[:, :1] * v0
    alpha += _cross_into(cross, v0, q2[:, 1:])
    alpha *= 2
    alpha /= squared
    alpha -= omega * (2 * dot01 / squared)
    return omega, alpha


def _rotation(q: np.ndarray) -> np.ndarray:
    """``rotation_from_quaternion`` (N, 4) -> (N, 3, 3), written in place of its stacks."""
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q.T
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    r = np.empty((len(q), 3, 3))
    r[:, 0, 0] = 1 - 2 * (yy + zz)
    r[:, 0, 1] = 2 * (xy - wz)
    r[:, 0, 2] = 2 * (xz + wy)
    r[:, 1, 0] = 2 * (xy + wz)
    r[:, 1, 1] = 1 - 2 * (xx + zz)
    r[:, 1, 2] = 2 * (yz - wx)
    r[:, 2, 0] = 2 * (xz - wy)
    r[:, 2, 1] = 2 * (yz + wx)
    r[:, 2, 2] = 1 - 2 * (xx + yy)
    return r


def _differentiate(t, position, q, windows, polyorder, step, core: slice,
                   where: tuple[Path, int]) -> Motion:
    """Savitzky-Golay smoothing and derivatives as ``Motion.from_samples``; the core steps.

    Where the core has half a window of samples on each side (every chunk but those at the
    ends of the file), the filter is applied to the core only (``_savgol_core``); at the ends
    of the file, ``trajectory.savgol_filter`` fits the edges."""
    wp, wq = windows
    lo, hi = core.start, core.stop
    if lo >= max(windows) // 2 and len(t) - hi >= max(windows) // 2:
        p0, p1, p2 = _savgol_core(position, wp, polyorder, step, lo, hi)
        q0, q1, q2 = _savgol_core(q, wq, polyorder, step, lo, hi)
        omega, alpha = _rates(q0, q1, q2)
    else:
        p0, p1, p2 = (a[core] for a in savgol_derivatives(position, wp, polyorder, step))
        q0, q1, q2 = (a[core] for a in savgol_derivatives(q, wq, polyorder, step))
        squared = np.sum(q0 * q0, axis=1, keepdims=True)
        omega = 2 * quaternion_multiply(q1, quaternion_conjugate(q0))[:, 1:] / squared
        alpha = (2 * quaternion_multiply(q2, quaternion_conjugate(q0))[:, 1:] / squared
                 - omega * 2 * np.sum(q0 * q1, axis=1, keepdims=True) / squared)
    parts = (p0, p1, p2, q0, omega, alpha)
    if not all(np.isfinite(a).all() for a in parts):
        finite = np.ones(len(q0), dtype=bool)
        for a in parts:
            finite &= np.isfinite(a).all(axis=1)
        bad = np.flatnonzero(~finite)
        raise InputError(f"{where[0]}: rows {where[1] + bad[0] + 1}-{where[1] + bad[-1] + 1}: "
                         "differentiation gave non-finite values (values or time steps out "
                         "of range)")
    # every value checked above (t by the reader): no second validation pass
    return Motion._trusted(t[core], p0, _rotation(q0), p1, omega, p2, alpha)


def iter_motions(path: str | os.PathLike[str], *, chunk: int = DEFAULT_CHUNK,
                 window: int | None = None, polyorder: int = DEFAULT_POLYORDER,
                 info: dict | None = None, log_format=None,
                 carry: list | None = None) -> Iterator[tuple[int, Motion]]:
    """The trajectory file as consecutive Motions of at most ``chunk`` steps.

    Parameters
    ----------
    path : path-like
        Trajectory file, CSV or Parquet (columns as for ``gsfric.io.read_trajectory``).
    chunk : int
        Steps per Motion (>= ``MIN_SAMPLES``); memory is proportional to it.
    window, polyorder :
        Savitzky-Golay window (odd, samples; None: chosen on the first chunk) and order.
    info : dict, optional
        Filled with ``"rows"`` (data rows read so far) and ``"windows"``: the position and
        quaternion windows of a streamed file; ``"whole"`` for a file read in one piece with a
        Savitzky-Golay filter (windows as ``Motion.from_samples`` chose them), None for one
        read in one piece with a smoothing spline (non-uniform sampling).
    log_format : gsfric.io.LogFormat, optional
        Column map, units and angle convention of the file.
    carry : list, optional
        Receives, block by block in file order, the columns carried to the output (F1..F6,
        ``keep:NAME``) as dicts of arrays.

    Yields
    ------
    (start, Motion)
        ``start`` is the 0-based index of the Motion's first step in the file (= its data row
        minus 1). Concatenated, the Motions are the whole file's differentiation (see the
        module's docstring).

    Raises
    ------
    InputError
        As ``read_trajectory``, with the file's rows; also a non-uniform time step in a file
        longer than one chunk, or a window longer than the chunk.
    """
    path = Path(path)
    info = {} if info is None else info
    if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) \
            or chunk < MIN_SAMPLES:
        raise InputError(f"chunk: must be an integer >= {MIN_SAMPLES}, got {chunk!r}")
    chunk = int(chunk)
    if window is not None and isinstance(window, (int, np.integer)) \
            and not isinstance(window, bool) and window > chunk:
        raise InputError(f"window = {window} is longer than the chunk of {chunk} steps; "
                         "use a larger chunk")
    blocks = _blocks(path, chunk, log_format, carry)

    # the first chunk, and whether there is more
    first: list[_Block] = []
    count = 0
    for block in blocks:
        first.append(block)
        count += len(block.t)
        if count > chunk:
            break
    info["rows"] = count
    if count <= chunk:
        motion = _whole(path, first, window, polyorder)
        info["windows"] = "whole" if is_uniform(motion.t) else None
        yield 0, motion
        return

    # streamed: fixed step and windows from the first chunk
    watch = _EulerWatch(path)
    for block in first:
        watch.add(block)
    t = np.concatenate([b.t for b in first])
    position = np.concatenate([b.position for b in first])
    q = continuous_quaternions(np.concatenate([b.quaternion for b in first]))
    step = (t[chunk - 1] - t[0]) / (chunk - 1)
    if not np.isfinite(step) or step <= 0:
        raise InputError(f"{path}: t spans too large a range")
    _check_uniform(path, t, step, 0, chunk)
    if isinstance(polyorder, bool) or not isinstance(polyorder, (int, np.integer)) \
            or polyorder < 2:
        raise InputError(f"polyorder must be an integer >= 2, got {polyorder!r}")
    if polyorder + 1 >= chunk:
        raise InputError(f"polyorder = {polyorder} needs a chunk of more than "
                         f"{polyorder + 1} steps")
    if window is None:
        with np.errstate(all="ignore"):
            windows = (gcv_window(position[:chunk], polyorder),
                       gcv_window(q[:chunk], polyorder))
    else:
        try:
            _check_window(window, polyorder, chunk)
        except InputError as error:
            raise InputError(f"{path}: {error}") from None
        windows = (int(window), int(window))
    info["windows"] = windows
    width = max(windows)          # samples the filter needs at an end of the file
    half = width // 2             # overlap on each side of an interior chunk

    buf_start = 0                 # global index of buf_t[0]
    done = 0                      # global index of the next core's first step

    def emit(stop: int, end_of_file: bool):
        nonlocal buf_t, buf_p, buf_q, buf_start, done
        total = buf_start + len(buf_t)
        lo = max(0, done - half)
        if end_of_file:
            lo = max(0, min(lo, total - width))
        hi = min(total, max(stop + half, width)) if not end_of_file else total
        a, b = lo - buf_start, hi - buf_start
        core = slice(done - lo, stop - lo)
        with np.errstate(all="ignore"):
            motion = _differentiate(buf_t[a:b], buf_p[a:b], buf_q[a:b], windows, polyorder,
                                    step, core, (path, done))
        start = done
        done = stop
        keep = max(0, done - width) - buf_start
        if keep > 0:
            buf_t, buf_p, buf_q = buf_t[keep:], buf_p[keep:], buf_q[keep:]
            buf_start += keep
        return start, motion

    buf_t, buf_p, buf_q = t, position, q
    del t, position, q, first
    while True:
        while done + chunk + half <= buf_start + len(buf_t):
            yield emit(done + chunk, False)
        block = next(blocks, None)
        if block is None:
            break
        watch.add(block)
        _check_uniform(path, np.concatenate([buf_t[-1:], block.t]), step, block.start - 1,
                       chunk)
        q_new = continuous_quaternions(np.vstack([buf_q[-1:], block.quaternion]))[1:]
        buf_t = np.concatenate([buf_t, block.t])
        buf_p = np.concatenate([buf_p, block.position])
        buf_q = np.concatenate([buf_q, q_new])
        info["rows"] = buf_start + len(buf_t)
    total = buf_start + len(buf_t)
    watch.finish()
    if done < total:
        yield emit(total, True)


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


# -- the streamed evaluation --------------------------------------------------------------------


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
    """

    out: Path
    steps: int = 0
    chunks: int = 0
    windows: Any = None
    flagged: int = 0
    flag_counts: dict[str, int] = field(default_factory=dict)
    flagged_steps: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    def flag_message(self, trajectory: Path) -> str:
        kinds = "; ".join(f"{name}: {count}" for name, count in self.flag_counts.items()
                          if count)
        return (f"{trajectory}: {self.flagged} of {self.steps} steps flagged ({kinds}): "
                f"{_steps_text(self.flagged_steps, self.flagged)}")


def _steps_text(indices: np.ndarray, total: int, limit: int = 10) -> str:
    shown = indices[:limit]
    more = f", ... ({total - len(shown)} more)" if total > len(shown) else ""
    steps = ", ".join(str(int(i)) for i in shown)
    rows = ", ".join(str(int(i) + 1) for i in shown)
    return f"steps {steps}{more} (data rows {rows})"


# -- output columns -----------------------------------------------------------------------------

FLOAT32_RTOL = 2.0 ** -24
"""Relative rounding error of an output written as float32 (``--float32``): half an ulp."""

def parse_columns(text: str | None) -> tuple[str, ...]:
    """Output groups from ``--columns`` ("forces,friction"; None: ``DEFAULT_COLUMN_GROUPS``,
    "all": every group)."""
    if text is None:
        return tuple(DEFAULT_COLUMN_GROUPS)
    if text.strip() == "all":
        return tuple(COLUMN_GROUPS)
    chosen = tuple(dict.fromkeys(g.strip() for g in text.split(",") if g.strip()))
    unknown = [g for g in chosen if g not in COLUMN_GROUPS]
    if unknown or not chosen:
        raise InputError(f"--columns: unknown group {unknown[0] if unknown else text!r}; "
                         f"choose from {', '.join(COLUMN_GROUPS)} (comma-separated) or all")
    return chosen


TRANSPOSE_BLOCK = 2048
"""Steps per block of the row-major to column-major copies of ``result_columns``: a block of a
Result array stays in the cache while its columns are written (twice as fast as one strided
copy of the whole array)."""

def _transpose_into(out: np.ndarray, rows: np.ndarray) -> None:
    """``out[:] = rows.T`` for rows (N, k) and out (k, N), block by block of steps."""
    n = rows.shape[0]
    for s in range(0, n, TRANSPOSE_BLOCK):
        np.copyto(out[:, s:s + TRANSPOSE_BLOCK], rows[s:s + TRANSPOSE_BLOCK].T,
                  casting="same_kind")


@dataclass
class _Chunk:
    """What ``result_columns`` reads of a Result: times (N,), outputs by name, flags (N,)."""

    t: np.ndarray
    arrays: dict[str, np.ndarray]
    flag: np.ndarray


def result_columns(result, plan, float32: bool = False, reuse: dict | None = None
                   ) -> dict[str, np.ndarray]:
    """The output columns of one Result (or ``_Chunk``), each a contiguous 1-D array (one
    transposed copy per output array; nothing refers to the Result's buffers). ``reuse`` (a
    dict, filled on first use) lends the arrays of the columns from call to call: the columns
    are then valid until the next call with it."""
    n = len(result.t)
    dtype = np.float32 if float32 else np.float64
    keys = list(dict.fromkeys(key for _, key, _, _ in plan))
    blocks: dict[str, np.ndarray] = {}
    for key in keys:
        values = result.arrays[key].reshape(n, -1)
        buf = None if reuse is None else reuse.get(key)
        if buf is None or buf.shape[1] < n or buf.dtype != dtype:
            buf = np.empty((values.shape[1], n), dtype=dtype)
            if reuse is not None:
                reuse[key] = buf
        blocks[key] = buf[:, :n]
        _transpose_into(blocks[key], values)
    cols = {"t": np.array(result.t, dtype=np.float64)}
    cols.update((column, blocks[key][index]) for column, key, index, _ in plan)
    cols["flag"] = np.array(result.flag, dtype=np.int64)
    return cols


class _Delay:
    """The sensor's ``time_offset`` applied across chunks exactly as over the whole record.

    ``F(t - delay)`` interpolates between the finite steps around ``t - delay``, which may lie
    in an earlier chunk (delay > 0) or a later one (delay < 0): the finite steps' times and
    forces are carried from chunk to chunk (back to the last one at or before the earliest
    time still needed), and a chunk waits, its columns built, until the samples after its last
    ``t - delay`` have been evaluated (or the file has ended). The interpolation brackets are
    those of the whole record, so the values are the same, bit for bit, as
    ``gsfric.catalog.apply_sensor`` over the whole record (``Evaluator.evaluate``)."""

    def __init__(self, gains: np.ndarray, delay: float) -> None:
        self.gains, self.delay = gains, delay
        self.t = np.empty(0)
        self.F = np.empty((0, 6))
        self.pending: list[tuple] = []

    def add(self, t: np.ndarray, F: np.ndarray, good: np.ndarray, build) -> list:
        """Take one chunk: its times, mechanism forces F (N, 6), finite steps, and
        ``build(F_sensor)`` giving what to write. Returns what is ready, in order."""
        self.t = np.concatenate([self.t, t[good]])
        self.F = np.concatenate([self.F, F[good]])
        self.pending.append((t, good, build))
        return self._ready(final=False)

    def finish(self) -> list:
        """Everything still waiting (the file has ended)."""
        return self._ready(final=True)

    def _ready(self, final: bool) -> list:
        done = []
        while self.pending:
            t, good, build = self.pending[0]
            if not final and not (len(self.t) and self.t[-1] >= t[-1] - self.delay):
                break
            self.pending.pop(0)
            shifted = np.full((len(t), 6), np.nan)
            if len(self.t):
                x = t[good] - self.delay
                part = np.empty((len(x), 6))
                for i in range(6):
                    part[:, i] = np.interp(x, self.t, self.F[:, i])
                shifted[good] = part * (1.0 + self.gains)
            done.append(build(shifted))
            earliest = (self.pending[0][0][0] if self.pending else t[-1]) - self.delay
            first = int(np.searchsorted(self.t, earliest, side="right")) - 1
            if first > 0:
                self.t, self.F = self.t[first:], self.F[first:]
        return done


PARQUET_COMPRESSION = "lz4"
"""Compression of ``simulate``'s Parquet output (docs/formats.md gives the measured choices:
the outputs' float64 mantissas are close to random bytes, so general-purpose compression
saves little unless the bytes are split by significance first, ``PARQUET_SPLIT_FLOATS``)."""

PARQUET_SPLIT_FLOATS = True
"""Write the float columns with Parquet's BYTE_STREAM_SPLIT encoding (pays only with a
compression)."""

FLUSH_BYTES = 256 * 2**20
"""Bytes written between two requests to the disk (``_Flusher``)."""

class _Flusher:
    """Hands the written part of a file to the disk while more is being written.

    Every ``FLUSH_BYTES`` (when the previous flush has finished), ``os.fdatasync`` runs in a
    thread of its own (it waits for the disk, not the processor): the disk writes during the
    run instead of after it, so that the final ``fsync`` of ``atomic_write`` finds little
    left. Without it, the kernel holds back up to a tenth of the memory before writing."""

    def __init__(self, handle) -> None:

        self.handle = handle
        self.fileno = handle.fileno()
        self.sync = getattr(os, "fdatasync", os.fsync)
        self.pool = ThreadPoolExecutor(1, thread_name_prefix="gsfric-flush")
        self.pending = None
        self.flushed = 0

    def written(self) -> None:
        """Called after each write, from the writing thread."""
        if self.pending is not None and not self.pending.done():
            return
        if self.pending is not None:
            self.pending.result()
        position = self.handle.tell()
        if position - self.flushed >= FLUSH_BYTES:
            self.handle.flush()
            self.flushed = position
            self.pending = self.pool.submit(self.sync, self.fileno)

    def close(self) -> None:
        self.pool.shutdown(wait=True)
        pending, self.pending = self.pending, None
        if pending is not None:
            pending.result()


class _Writer:
    """Appends column dicts to an open binary (Parquet) or text (CSV) handle.

    Parquet: floats BYTE_STREAM_SPLIT (no dictionary: they almost never repeat), compression
    ``PARQUET_COMPRESSION``, the flag column dictionary-encoded; one row group per chunk.
    The Arrow arrays are the column arrays themselves (no copy); the schema, with each field's
    ``unit`` and ``description``, is built once, from the first chunk."""

    def __init__(self, handle, kind: str) -> None:
        self.handle, self.kind = handle, kind
        self.parquet = None
        self.schema = None
        self.header = True
        self.flusher = _Flusher(handle)

    @staticmethod
    def load(kind: str) -> None:
        """Import what writing ``kind`` needs, before the temporary output exists: a stop
        signal that lands inside an import comes out as whatever error the import makes of it
        (or is swallowed in an import's callback), not as the stop."""
        if kind == "csv":
            import pandas  # noqa: F401
        else:
            import pyarrow.parquet  # noqa: F401

            import gsfric.evaluation.columns  # noqa: F401

    def write(self, columns: dict[str, np.ndarray]) -> None:
        if self.kind == "csv":

            pd.DataFrame(columns, copy=False).to_csv(self.handle, index=False,
                                                     header=self.header)
            self.header = False
        else:
            self._write_parquet(columns)
        self.flusher.written()

    def _write_parquet(self, columns: dict[str, np.ndarray]) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        arrays = [pa.array(values) for values in columns.values()]
        if self.parquet is None:

            self.schema = arrow_table(dict(zip(columns, arrays))).schema
            floats = [f.name for f in self.schema if pa.types.is_floating(f.type)]
            self.parquet = pq.ParquetWriter(
                self.handle, self.schema, use_dictionary=["flag"],
                compression=PARQUET_COMPRESSION,
                use_byte_stream_split=floats if PARQUET_SPLIT_FLOATS else False)
        self.parquet.write_table(pa.Table.from_arrays(arrays, schema=self.schema))

    def close(self) -> None:
        try:
            if self.parquet is not None:
                writer, self.parquet = self.parquet, None
                writer.close()
        finally:
            self.flusher.close()

    def abandon(self) -> None:
        with contextlib.suppress(BaseException):
            self.close()


def simulate_file(trajectory: str | os.PathLike[str], out: str | os.PathLike[str],
                  platform=None, *, mode: str = "kinematic", strict: bool = False,
                  chunk: int = DEFAULT_CHUNK, window: int | None = None,
                  polyorder: int = DEFAULT_POLYORDER, n_threads: int = 1,
                  progress: bool | None = None, log_format=None, columns=None,
                  float32: bool = False) -> Summary:
    """Evaluate a trajectory file chunk by chunk and write every step's outputs.

    Parameters
    ----------
    trajectory : path-like
        CSV or Parquet trajectory file (see ``gsfric.io.read_trajectory``).
    out : path-like
        Output file, CSV or Parquet by extension; columns of ``Result.to_frame``.
    platform : Platform, optional
        Default: the reference platform.
    mode : {"kinematic", "paper"}
    strict : bool
        Raise ``StepFlagError`` at the first chunk with a flagged step (no output is written).
    chunk : int
        Steps per chunk; memory grows with it (about 5 kB per step).
    window, polyorder :
        Smoothing of the differentiation, see ``iter_motions``.
    n_threads : int
        Threads of the compiled evaluation.
    progress : bool or None
        Progress bar on stderr (tqdm); None: only when stderr is a terminal.
    log_format : gsfric.io.LogFormat, optional
        Column map, units, angle convention and carried columns of the file. A file with
        F1..F6 (measured data) also gets ``F1_measured..F6_measured`` and the residuals
        ``F1_residual..F6_residual`` (measured minus model) in the output.
    columns : iterable of str, optional
        Output groups (``COLUMN_GROUPS``); default ``DEFAULT_COLUMN_GROUPS`` (forces, the
        paper's friction scalars, reactions: 68 values a step). ``t`` and ``flag`` always.
    float32 : bool
        Write the outputs (not ``t``) as float32: relative error up to ``FLOAT32_RTOL``
        (6e-8) of each value, half the file.

    Three stages overlap, each in its own thread: reading and differentiating chunk k + 2
    (the calling thread), evaluating chunk k + 1 and building its columns, writing chunk k
    (the compiled code, NumPy's copies and the Parquet writer run without the GIL). The
    evaluation's outputs and the columns' arrays are reused from chunk to chunk within the
    call (two sets of columns, one being written while the other is filled).

    Returns
    -------
    Summary
        Flags are also reported as one warning (``GsfricWarning``) when not strict.

    Raises
    ------
    InputError
        Bad trajectory (naming the row and column), bad output path.
    StepFlagError
        ``strict`` and a flagged step.
    """

    trajectory, out = Path(trajectory), Path(out)
    kind = table_kind(out)
    check_file(trajectory)
    if out.exists() and out.is_dir():
        raise InputError(f"{out}: is a directory; give a file name")
    if not out.parent.is_dir():
        raise InputError(f"{out}: directory {str(out.parent)!r} does not exist")
    with contextlib.suppress(OSError):
        if out.exists() and os.path.samefile(out, trajectory):
            raise InputError(f"{out}: is the trajectory file itself; choose another output")
    if platform is None:

        platform = reference_platform()

    plan = _column_plan(parse_columns(None) if columns is None else
                        parse_columns(",".join(columns)))
    summary = Summary(out=out)
    info: dict = {}
    carry: list[dict] = []
    motions = iter_motions(trajectory, chunk=chunk, window=window, polyorder=polyorder,
                           info=info, log_format=log_format, carry=carry)
    kept: list[np.ndarray] = []
    counts = dict.fromkeys(FLAG_NAMES, 0)
    evaluator = None
    show = sys.stderr.isatty() if progress is None else bool(progress)
    bar = tqdm(total=count_rows(trajectory) if show else None, unit="step",
               unit_scale=True, desc="simulate", file=sys.stderr, disable=not show,
               dynamic_ncols=True, leave=False)
    mode_text = "wb" if kind == "parquet" else "w"
    options = {"newline": ""} if kind == "csv" else {}

    sets: tuple[dict, dict] = ({}, {})   # the evaluation's outputs of even and odd chunks
    column_arrays: dict = {}             # the columns' arrays (filled by the writing thread)

    gains, delay = sensor_parameters(platform.effects)
    # a delay reaches across chunks: applied here, over the record, not per chunk
    shift = _Delay(gains, delay) if delay != 0.0 else None
    names = list(dict.fromkeys(key for _, key, _, _ in plan))
    if shift is not None and "F" not in names:
        names.append("F")

    def process(start: int, motion, carried: dict[str, np.ndarray], buffers: dict,
                buffers_free) -> list:
        """Evaluate, count the flags (in the evaluation thread; no warnings issued); what to
        write: (chunk, carried columns) to be made columns by the writing thread, or, with a
        sensor delay, the column dicts that are ready. ``buffers_free``: the write of the
        chunk that last used ``buffers``, waited for before they are overwritten."""
        if buffers_free is not None:
            buffers_free.result()
        arrays, flag = evaluate_outputs(evaluator, motion, names, buffers=buffers,
                                        sensor=shift is None)
        bad = np.flatnonzero(flag)
        if bad.size:
            summary.flagged += int(bad.size)
            for bit in FLAG_NAMES:
                counts[bit] += int(np.count_nonzero(flag & bit))
            room = MAX_REPORTED - sum(len(k) for k in kept)
            if room > 0:
                kept.append(bad[:room] + start)
            if strict:
                summary.steps = start + len(motion)
                _finish(summary, kept, counts)
                raise StepFlagError(
                    summary.flag_message(trajectory)
                    + " (--strict: stopped at the first chunk with flagged steps; "
                    "no output written)")
        chunk_ = _Chunk(np.asarray(motion.t, dtype=np.float64), arrays, flag)
        if shift is None:
            ready = [(chunk_, carried)]
        else:
            good = (flag & FLAG_NONFINITE) == 0
            ready = shift.add(chunk_.t, arrays["F"], good, functools.partial(
                _delayed_columns, result_columns(chunk_, plan, float32), plan, float32,
                carried))
        summary.steps = start + len(motion)
        summary.chunks += 1
        bar.update(len(motion))
        return ready

    def write_one(item) -> None:
        """Write one chunk (in the writing thread): its columns first, from a ``_Chunk``."""
        if isinstance(item, tuple):
            chunk_, carried = item
            item = _with_carried(result_columns(chunk_, plan, float32, reuse=column_arrays),
                                 carried)
        writer.write(item)

    # three stages in three threads: reading and differentiating chunk k + 2 (this thread),
    # evaluating chunk k + 1, building the columns of chunk k and writing them (the compiled
    # code, NumPy's copies and the Parquet writer run without the GIL)
    _Writer.load(kind)
    try:
        with atomic_write(out, mode_text, **options) as handle, \
                ThreadPoolExecutor(1, thread_name_prefix="gsfric-evaluate") as evaluation, \
                ThreadPoolExecutor(1, thread_name_prefix="gsfric-write") as output:
            writer = _Writer(handle, kind)
            pending = None                  # the evaluation in flight
            writes: list = []               # the writes in flight, oldest first
            set_writes: list = [None, None]   # the last write from each set of outputs

            def write(ready: list, which: int | None) -> None:
                for item in ready:
                    while len(writes) >= 2:     # bounded: at most two chunks wait to be written
                        writes.pop(0).result()
                    writes.append(output.submit(write_one, item))
                    if which is not None:
                        set_writes[which] = writes[-1]

            try:
                k = 0
                for start, motion in motions:
                    if evaluator is None:
                        evaluator = Evaluator(platform, mode=mode, n_threads=n_threads)
                    if pending is not None:
                        write(pending.result(), (k - 1) % 2 if shift is None else None)
                    pending = evaluation.submit(process, start, motion,
                                                _take(carry, len(motion)), sets[k % 2],
                                                set_writes[k % 2])
                    k += 1
                    del motion
                if pending is not None:
                    write(pending.result(), None)
                    pending = None
                if shift is not None:
                    write(shift.finish(), None)
                for done in writes:
                    done.result()
            except BaseException:
                for future in [pending, *writes]:
                    if future is not None:
                        with contextlib.suppress(BaseException):
                            future.result()
                writer.abandon()
                raise
            writer.close()
    finally:
        bar.close()
    summary.windows = info.get("windows")
    _finish(summary, kept, counts)
    if summary.flagged:
        warnings.warn(summary.flag_message(trajectory) + f"; see the flag column of {out}",
                      GsfricWarning, stacklevel=2)
    return summary


def _take(carry: list[dict], n: int) -> dict[str, np.ndarray]:
    """The next ``n`` rows of the carried columns (removed from ``carry``)."""
    parts: list[dict] = []
    got = 0
    while got < n and carry:
        head = carry[0]
        size = len(next(iter(head.values()))) if head else n - got
        if got + size <= n:
            parts.append(carry.pop(0))
            got += size
        else:
            k = n - got
            parts.append({key: v[:k] for key, v in head.items()})
            carry[0] = {key: v[k:] for key, v in head.items()}
            got = n
    if not parts or not parts[0]:
        return {}
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}


def _delayed_columns(columns: dict[str, np.ndarray], plan, float32: bool,
                     carried: dict[str, np.ndarray], F: np.ndarray) -> dict[str, np.ndarray]:
    """A chunk's columns with the sensor's F (N, 6) in place of the mechanism's."""
    dtype = np.float32 if float32 else np.float64
    columns = dict(columns)
    for column, key, index, _ in plan:
        if key == "F":
            columns[column] = np.array(F[:, index], dtype=dtype)
    return _with_carried(columns, carried)


def _with_carried(columns: dict[str, np.ndarray],
                  carried: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The output columns with measured forces, residuals (where the forces are written) and
    kept input columns appended."""
    extra = {}
    if "F1" in carried:
        for i in range(1, 7):
            extra[f"F{i}_measured"] = carried[f"F{i}"]
        if "F1" in columns:
            for i in range(1, 7):
                extra[f"F{i}_residual"] = carried[f"F{i}"] - columns[f"F{i}"]
    for key, values in carried.items():
        if key.startswith("keep:"):
            name = key[5:]
            if name in columns or name in extra:
                name = f"{name}_input"
            extra[name] = values
    return {**columns, **extra} if extra else columns


def _finish(summary: Summary, kept: list[np.ndarray], counts: dict[int, int]) -> None:
    summary.flagged_steps = np.concatenate(kept) if kept else np.zeros(0, dtype=np.int64)
    summary.flag_counts = {FLAG_NAMES[bit]: n for bit, n in counts.items()}
