"""Trajectories and measured data read from files (CSV or Parquet), or from a DataFrame.

The format follows the extension: ``.csv`` or ``.parquet`` / ``.pq`` (case-insensitive). Every
problem with an input file raises an ``InputError`` with a one-line message naming the file and,
where it applies, the row and the column, e.g. ``trajectory.csv: row 17: column 'x' is NaN``.
Rows are data rows counted from 1 (the CSV header is not counted). Of an index that pandas
stored in a Parquet file, a named one (``df.set_index("t")``) is read as a column, an unnamed
one is ignored.

Trajectory files hold ``t, x, y, z`` (s, m; platform frame origin in the base frame) and either
the ZXZ angles ``alpha, beta, gamma`` (rad) or a unit quaternion ``qw, qx, qy, qz`` (platform
frame to base frame) or roll, pitch, yaw angles ``roll, pitch, yaw`` (see ``LogFormat`` for
their convention). When several sets are present the quaternion is used, then the ZXZ angles.
Measured-data files add ``F1..F6`` (actuator forces, N, all six required) and optionally
``D1..D6`` (leg lengths, m, all six or none). Other columns are ignored, with one warning naming
them.

A log written by another program (a controller's names and units, a wrapping microsecond
counter, roll/pitch/yaw) is read with a ``LogFormat``: a column map, units per column, the
angle convention and the columns to carry through; see docs/howto/read-a-log.md.

Writes are atomic (``atomic_write``): a reader never sees a partly written file.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gsfric._checks import as_path
from gsfric.errors import InputError
from gsfric.io.logs import FORCES, LENGTHS, QUATERNION, RATES, ColumnReader, LogFormat
from gsfric.io.tables import read_columns
from gsfric.signal.savgol import DEFAULT_POLYORDER
from gsfric.trajectory import MIN_SAMPLES, Motion

if TYPE_CHECKING:
    import pandas as pd

MAX_FORCE = 1e8
"""Measured actuator forces beyond this magnitude, N (100 MN, far above any hexapod's), are
refused: a wrong unit or a corrupt file."""


def _read_samples(path: str | os.PathLike[str], measured: bool,
                  log_format: LogFormat | None = None
                  ) -> tuple[Path, dict[str, np.ndarray], tuple[str, ...]]:
    path = as_path(path, "path")
    return _samples(path, *read_columns(path), measured, log_format)


def _samples(path, names: list, values: list, measured: bool, log_format: LogFormat | None
             ) -> tuple[Path, dict[str, np.ndarray], tuple[str, ...]]:
    """The checked columns of a whole table (its column ``names`` and ``values``, NumPy arrays
    or Series); ``path`` names it in messages."""
    names = [str(name).strip() for name in names]
    if len(set(names)) != len(names):
        duplicate = next(n for n in names if names.count(n) > 1)
        raise InputError(f"{path}: column {duplicate!r} appears more than once")
    reader = ColumnReader(path, log_format, measured)
    orientation = reader.check(names)
    if len(values[0]) == 0:
        raise InputError(f"{path}: no data rows")

    columns = reader.read(dict(zip(names, values)))
    t = columns["t"]
    with np.errstate(over="ignore", invalid="ignore"):
        steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if len(bad):
        i = int(bad[0]) + 1
        row, before = reader.file_row(i) + 1, reader.file_row(i - 1) + 1
        if steps[i - 1] == 0:
            raise InputError(f"{path}: row {row}: duplicate time t = {float(t[i])!r} "
                             f"(same as row {before})")
        raise InputError(f"{path}: row {row}: t = {float(t[i])!r} is less than "
                         f"t = {float(t[i - 1])!r} in row {before}; t must increase")
    if len(t) < MIN_SAMPLES:
        raise InputError(f"{path}: {len(t)} data rows; at least {MIN_SAMPLES} are needed "
                         "to differentiate the motion")
    if measured:
        check_force_range(np.stack([columns[n] for n in FORCES], axis=1), str(path),
                          lambda i: reader.file_row(i) + 1)
    if measured and "D1" in columns:
        lengths = np.stack([columns[n] for n in LENGTHS], axis=1)
        bad_rows, bad_legs = np.nonzero(lengths <= 0)
        if len(bad_rows):
            raise InputError(f"{path}: row {reader.file_row(bad_rows[0]) + 1}: column "
                             f"'D{bad_legs[0] + 1}' must be positive (a leg length)")
    return path, columns, orientation


def check_force_range(forces: np.ndarray, where: str, row=lambda i: i + 1) -> None:
    """``InputError`` naming the first force (N, 6), N, beyond ``MAX_FORCE``: ``where`` starts
    the message, ``row`` maps a sample's index to the row the user sees."""
    bad_rows, bad_legs = np.nonzero(np.abs(forces) > MAX_FORCE)
    if len(bad_rows):
        value = forces[bad_rows[0], bad_legs[0]]
        raise InputError(f"{where}: row {row(bad_rows[0])}: column 'F{bad_legs[0] + 1}' = "
                         f"{value:.4g} N is not a plausible actuator force (|F| > "
                         f"{MAX_FORCE:g} N); forces must be in N")


def motion_from_columns(path: Path, columns: dict[str, np.ndarray], orientation: tuple[str, ...],
                        window: int | None, polyorder: int) -> Motion:
    """The columns read (``ColumnReader.read``, SI) differentiated into a ``Motion``; the log's
    own rates (``RATES``) where it has them."""
    position = np.stack([columns[n] for n in ("x", "y", "z")], axis=1)
    angles = np.stack([columns[n] for n in orientation], axis=1)
    key = "quaternion" if orientation == QUATERNION else "euler"
    rates = {name: np.stack([columns[n] for n in group], axis=1)
             for name, group in RATES.items() if group[0] in columns}
    return Motion.from_samples(columns["t"], position, window=window, polyorder=polyorder,
                               source=str(path), rates=rates or None, **{key: angles})


def motion_from_frame(frame: pd.DataFrame, *, window: int | None = None,
                      polyorder: int = DEFAULT_POLYORDER, log_format: LogFormat | None = None,
                      name: str = "DataFrame") -> Motion:
    """A ``Motion`` from a DataFrame with trajectory columns, as ``read_trajectory`` reads a file.

    Parameters
    ----------
    frame : pandas.DataFrame
        Columns ``t, x, y, z`` (s, m) and ``alpha, beta, gamma`` (rad), ``qw, qx, qy, qz`` or
        ``roll, pitch, yaw``, or other names and units given by ``log_format``; one row per
        sample, N >= ``MIN_SAMPLES`` rows. The index is not used.
    window, polyorder, log_format :
        As for ``read_trajectory``.
    name : str
        How messages name the frame (``"DataFrame: row 3: column 'x' is NaN"``).

    Returns
    -------
    Motion
        N steps.
    """
    frame = frame.reset_index(drop=True)
    path, columns, orientation = _samples(
        name, list(frame.columns), [frame.iloc[:, k] for k in range(frame.shape[1])], False,
        log_format)
    return motion_from_columns(path, columns, orientation, window, polyorder)


def read_trajectory(path: str | os.PathLike[str], *, window: int | None = None,
                    polyorder: int = DEFAULT_POLYORDER,
                    log_format: LogFormat | None = None) -> Motion:
    """Read a trajectory file and differentiate it into a ``Motion``.

    Parameters
    ----------
    path : path-like
        CSV or Parquet with ``t, x, y, z`` and ``alpha, beta, gamma`` or ``qw, qx, qy, qz``.
    window, polyorder :
        Smoothing of the differentiation, see ``Motion.from_samples``.
    log_format : LogFormat, optional
        Column map, units, angle convention of a log written by another program.

    Returns
    -------
    Motion
        N steps, N the number of data rows (at least ``MIN_SAMPLES``).

    Raises
    ------
    InputError
        Unknown or missing columns, values that are not numbers, NaN or infinite values, times
        that do not increase, too few rows. Warnings (``GsfricWarning``) flag angles that look
        like degrees and jumps of the ZXZ angles near beta = 0.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np, gsfric
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "motion.csv"
    >>> gsfric.io.write_table(gsfric.models.sinusoidal(np.linspace(0, 2, 401)).to_frame(), path)
    >>> gsfric.read_trajectory(path).position.shape
    (401, 3)
    """
    path, columns, orientation = _read_samples(path, False, log_format)
    return motion_from_columns(path, columns, orientation, window, polyorder)


def read_measured(path: str | os.PathLike[str], *, window: int | None = None,
                  polyorder: int = DEFAULT_POLYORDER, log_format: LogFormat | None = None
                  ) -> tuple[Motion, np.ndarray, np.ndarray | None]:
    """Read a measured-data file: the trajectory columns plus ``F1..F6`` and optional ``D1..D6``.

    Parameters
    ----------
    path : str or path-like
        A CSV or Parquet file with the columns of a trajectory and ``F1..F6`` (N).
    window, polyorder, log_format
        As for ``read_trajectory``.

    Returns
    -------
    motion : Motion
        The differentiated trajectory, N steps.
    forces : ndarray, shape (N, 6)
        Actuator forces F1..F6 as read (not smoothed), N, positive pushing the platform away
        from the base.
    lengths : ndarray, shape (N, 6), or None
        Leg lengths D1..D6, m, when the file has them.

    Raises
    ------
    InputError
        As ``read_trajectory``, and for missing F columns, an incomplete D1..D6 set or a
        non-positive leg length.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import gsfric
    >>> from gsfric.synth import synthesize
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "measured.csv"
    >>> gsfric.io.write_table(synthesize(samples=400, seed=1).frame, path)
    >>> motion, forces, lengths = gsfric.read_measured(path)
    >>> forces.shape[1]
    6
    """
    return read_measured_columns(path, window, polyorder, log_format)[:3]


def read_measured_columns(path, window, polyorder, log_format):
    """``read_measured`` and the file's columns as read (SI), for callers that also need the
    recorded poses (discovery's rest detection)."""
    path, columns, orientation = _read_samples(path, True, log_format)
    motion = motion_from_columns(path, columns, orientation, window, polyorder)
    forces = np.stack([columns[n] for n in FORCES], axis=1)
    lengths = np.stack([columns[n] for n in LENGTHS], axis=1) if "D1" in columns else None
    return motion, forces, lengths, columns
