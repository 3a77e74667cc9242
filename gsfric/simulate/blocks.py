"""Reading a trajectory file in validated blocks of rows, with the checks of ``read_trajectory``.

Every row is checked as ``gsfric.io.read_trajectory`` checks it (numbers, finite, increasing
times), with the file's 1-based data row in the message. Euler input is checked for angles
that look like degrees (a warning when first seen) and for jumps of alpha or gamma near
beta = 0 (one warning at the end naming the rows, ``EulerWatch``).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gsfric._optional import optional
from gsfric.errors import GsfricWarning, InputError
from gsfric.io.arrow import column_from_arrow, data_columns
from gsfric.io.logs import FORCES, QUATERNION, ColumnReader
from gsfric.io.tables import check_csv_header, check_file, csv_errors, csv_options
from gsfric.signal.rotations import (
    MIN_QUATERNION_LENGTH,
    quaternion_from_euler,
    unit_quaternions,
)
from gsfric.trajectory import GIMBAL_JUMP, GIMBAL_SIN_BETA


@dataclass
class Block:
    """Validated samples of consecutive data rows starting at global row ``start`` (0-based).

    Attributes
    ----------
    start : int
    t : ndarray, shape (n,)
        Times, s, increasing (also across blocks).
    position : ndarray, shape (n, 3)
        m.
    quaternion : ndarray, shape (n, 4)
        Normalized, not yet sign-continuous.
    euler : ndarray, shape (n, 3), or None
        The ZXZ angles, rad, when the orientation is given as such.
    columns : dict of str -> ndarray (n,)
        Every column read (gsfric names, SI units).
    carried : dict of str -> ndarray (n,)
        The columns carried to the output: F1..F6 of a measured-data file and ``keep:NAME``
        columns; empty when there are none.
    """

    start: int
    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    euler: np.ndarray | None
    columns: dict[str, np.ndarray]
    carried: dict[str, np.ndarray]


def read_blocks(path: Path, rows: int, log_format=None) -> Iterator[Block]:
    """Validated blocks of at most ``rows`` rows of the trajectory file; messages name
    1-based data rows. ``log_format``: a ``gsfric.io.LogFormat`` (column map, units, angle
    convention, kept columns), or None."""
    kind = check_file(path)
    reader = ColumnReader(path, log_format)
    frames = _csv_frames(path, rows) if kind == "csv" else _parquet_frames(path, rows)
    start = 0
    last_t = None
    orientation = None
    for names, values in frames:
        names = [name.strip() for name in names]
        if orientation is None:
            orientation = _check_header(path, reader, names)
        if len(values[0]) == 0:
            continue
        columns = reader.read(dict(zip(names, values)), first_row=start)
        carried = {k: v for k, v in columns.items() if k in FORCES or k.startswith("keep:")} \
            if reader.forces or reader.keep else {}
        t = columns["t"]
        if len(t) == 0:                    # only dropout rows
            continue
        _check_increasing(path, t, last_t, start, reader.file_row)
        position = np.stack([columns[n] for n in ("x", "y", "z")], axis=1)
        q, euler = _quaternions(path, np.stack([columns[n] for n in orientation], axis=1),
                                orientation, start, reader.file_row)
        yield Block(start, t, position, q, euler, columns, carried)
        start += len(t)
        last_t = t[-1]
    if orientation is None or start == 0:
        raise InputError(f"{path}: no data rows")


def _check_header(path: Path, reader: ColumnReader, names: list[str]) -> tuple[str, ...]:
    """The orientation columns the file gives, after checking its column names."""
    if len(set(names)) != len(names):
        duplicate = next(n for n in names if names.count(n) > 1)
        raise InputError(f"{path}: column {duplicate!r} appears more than once")
    return reader.check(names)


def _check_increasing(path: Path, t: np.ndarray, last_t: float | None, start: int,
                      file_row=int) -> None:
    """Raise ``InputError`` naming the first row of ``t`` (first row ``start``, 0-based; the
    previous block's last time ``last_t``) whose time does not increase; ``file_row`` maps an
    index of the rows read to the file's 0-based data row (``ColumnReader.file_row``)."""
    with np.errstate(over="ignore", invalid="ignore"):
        steps = np.diff(t if last_t is None else np.concatenate([[last_t], t]))
    bad = np.flatnonzero(steps <= 0)
    if not len(bad):
        return
    local = int(bad[0]) + (1 if last_t is None else 0)   # index in t of the bad row
    previous = t[local - 1] if local > 0 else last_t
    row, before = file_row(start + local) + 1, file_row(start + local - 1) + 1
    if steps[bad[0]] == 0:
        raise InputError(f"{path}: row {row}: duplicate time t = {float(t[local])!r} "
                         f"(same as row {before})")
    raise InputError(f"{path}: row {row}: t = {float(t[local])!r} is less than "
                     f"t = {float(previous)!r} in row {before}; t must increase")


def _quaternions(path: Path, angles: np.ndarray, orientation: tuple[str, ...], start: int,
                 file_row=int) -> tuple[np.ndarray, np.ndarray | None]:
    """Unit quaternions (n, 4) of the orientation columns (n, 3 or 4), and the ZXZ angles
    themselves when they are given (else None)."""
    if orientation != QUATERNION:
        return quaternion_from_euler(*angles.T), angles
    unit, norms = unit_quaternions(angles)
    zero = np.flatnonzero(norms < MIN_QUATERNION_LENGTH)
    if len(zero):
        raise InputError(f"{path}: row {file_row(start + int(zero[0])) + 1}: quaternion of "
                         "zero length")
    return unit, None


# -- CSV and Parquet frames ---------------------------------------------------------------------


Frame = tuple[list[str], list]
"""A block of rows as read: the column names and the columns (NumPy arrays or Series)."""


def _csv_frames(path: Path, rows: int) -> Iterator[Frame]:
    """Blocks of at most ``rows`` rows; errors as ``read_table`` gives them."""
    pd = optional("pandas")
    with csv_errors(path):
        reader = pd.read_csv(path, chunksize=rows, **csv_options())
    with reader:
        while True:
            with csv_errors(path):
                frame = next(reader, None)
            if frame is None:
                return
            names = [str(c) for c in frame.columns]
            check_csv_header(path, names)
            yield names, [column for _, column in frame.items()]


def _parquet_frames(path: Path, rows: int) -> Iterator[Frame]:
    """The file's record batches of at most ``rows`` rows."""
    pyarrow = optional("pyarrow")
    pq = optional("pyarrow.parquet")
    errors = (pyarrow.ArrowException, ValueError, TypeError, OSError, NotImplementedError)
    try:
        # without pre-buffering: pre-buffered row groups stay cached in the reader, so memory
        # would grow by a row group for every row group read
        source = pq.ParquetFile(path, pre_buffer=False)
        keep = data_columns(source.schema_arrow)
        names = [str(source.schema_arrow.names[k]) for k in keep]
    except errors as error:
        raise InputError(f"{path}: cannot read as Parquet: {error}") from None
    if len(set(names)) != len(names):
        raise InputError(f"{path}: a column name appears more than once")
    if source.metadata.num_rows == 0:
        yield names, [np.empty(0) for _ in names]
        return
    batches = source.iter_batches(batch_size=rows, columns=names)
    while True:
        try:
            batch = next(batches)
            values = [column_from_arrow(column) for column in batch.columns]
        except StopIteration:
            return
        except errors as error:
            raise InputError(f"{path}: cannot read as Parquet: {error}") from None
        yield names, values


# -- Euler checks across blocks -----------------------------------------------------------------


class EulerWatch:
    """The checks of ``Motion.from_samples`` on ZXZ angles, gathered over blocks."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.warned_degrees = False
        self.previous: np.ndarray | None = None
        self.jumps: list[int] = []
        self.jump_count = 0

    def add(self, block: Block) -> None:
        """Check one block (a warning when its angles first look like degrees)."""
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
        """One warning naming the rows where alpha or gamma jumped near beta = 0."""
        if self.jump_count:
            rows = ", ".join(str(j + 1) for j in self.jumps)
            more = f" and {self.jump_count - len(self.jumps)} more" \
                if self.jump_count > len(self.jumps) else ""
            word = "rows" if self.jump_count > 1 else "row"
            warnings.warn(f"{self.path}: ZXZ angles near beta = 0 (where alpha and gamma are "
                          f"ill-defined) jump by more than {GIMBAL_JUMP} rad in alpha or gamma "
                          f"at {word} {rows}{more}; give the orientation as a quaternion "
                          "(qw, qx, qy, qz) instead", GsfricWarning, stacklevel=2)
