"""Reading and writing files: tables (CSV or Parquet), trajectories, measured data.

The format follows the extension: ``.csv`` or ``.parquet`` / ``.pq`` (case-insensitive). Every
problem with an input file raises an ``InputError`` with a one-line message naming the file and,
where it applies, the row and the column, e.g. ``trajectory.csv: row 17: column 'x' is NaN``.
Rows are data rows counted from 1 (the CSV header is not counted).

Trajectory files hold ``t, x, y, z`` (s, m; platform frame origin in the base frame) and either
the ZXZ angles ``alpha, beta, gamma`` (rad) or a unit quaternion ``qw, qx, qy, qz`` (platform
frame to base frame). When both sets are present the quaternion is used. Measured-data files add
``F1..F6`` (actuator forces, N, all six required) and optionally ``D1..D6`` (leg lengths, m, all
six or none). No other columns are accepted.

Writes are atomic (``atomic_write``): a reader never sees a partly written file.
"""

from __future__ import annotations

import contextlib
import csv
import errno
import os
import re
import stat
import tempfile
import warnings
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from gsfric._checks import short, suggest
from gsfric.errors import GsfricError, InputError, OutputError
from gsfric.trajectory import DEFAULT_POLYORDER, MIN_SAMPLES, Motion

if TYPE_CHECKING:
    import pandas as pd

TIME_POSITION = ("t", "x", "y", "z")
EULER = ("alpha", "beta", "gamma")
QUATERNION = ("qw", "qx", "qy", "qz")
FORCES = tuple(f"F{i}" for i in range(1, 7))
LENGTHS = tuple(f"D{i}" for i in range(1, 7))

MAX_FORCE = 1e8
"""Measured actuator forces beyond this magnitude, N (100 MN, far above any hexapod's), are
refused: a wrong unit or a corrupt file."""

_NAN_WORDS = ("nan", "-nan", "+nan")
_CSV = (".csv",)
_PARQUET = (".parquet", ".pq")


# -- atomic writes ------------------------------------------------------------------------------

_TEMP_TAG = ".gsfric-"
"""Temporary outputs are named ``.{name}.gsfric-{pid}-{random}.tmp`` beside the output, so that a
later run can recognise (and remove) those of its own that a killed process (SIGKILL, a power
cut) left behind."""

_WRITE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO}


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True
    return True


def remove_stale_temporaries(path: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files or folders of ``path`` that dead gsfric processes left.

    Only names ``.{name}.gsfric-{pid}-*.tmp`` in ``path``'s directory whose process no longer
    runs are removed (a run still writing is never disturbed). Returns what was removed.
    """
    import glob
    import shutil

    path = Path(path)
    removed = []
    pattern = f".{glob.escape(path.name)}{_TEMP_TAG}*.tmp"
    for stale in path.parent.glob(pattern):
        pid_text = stale.name[len(path.name) + 1 + len(_TEMP_TAG):].split("-", 1)[0]
        if not pid_text.isdigit() or _pid_alive(int(pid_text)):
            continue
        with contextlib.suppress(OSError):
            if stale.is_dir() and not stale.is_symlink():
                shutil.rmtree(stale)
            else:
                stale.unlink()
            removed.append(stale)
    return removed


def _temp_prefix(path: Path) -> str:
    return f".{path.name}{_TEMP_TAG}{os.getpid()}-"


def resolve_output(path: str | os.PathLike[str]) -> Path:
    """The file an output path stands for: a symbolic link's target (the link is kept).

    Raises
    ------
    InputError
        A symbolic link loop.
    """
    path = Path(path)
    try:
        os.stat(path)
    except FileNotFoundError:
        pass
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise InputError(f"{path}: symbolic link loop (too many levels of symbolic "
                             "links)") from None
    if path.is_symlink():
        return Path(os.path.realpath(path))
    return path


def _write_failure(path: Path, error: OSError, what: str = "file") -> OutputError:
    reason = error.strerror or str(error) or type(error).__name__
    return OutputError(f"{path}: cannot write ({reason}); nothing was written, an earlier "
                       f"{what} of that name is unchanged")


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "w", *,
                 encoding: str = "utf-8", newline: str | None = None) -> Iterator[IO[Any]]:
    """Open a temporary file next to ``path`` and move it onto ``path`` when the block ends.

    The temporary file lives in the same directory (so ``os.replace`` is atomic), is named
    ``.{name}.gsfric-{pid}-{random}.tmp`` (those of dead processes are removed on the next
    write of the same output, see ``remove_stale_temporaries``), is flushed and fsync'ed before
    the move, and is removed if the block raises or a signal interrupts it; ``path`` is then
    left as it was. A symbolic link ``path`` is followed: its target is written, the link kept.
    A new file gets the usual permissions (0666 less the umask), a replaced file keeps its own.

    Parameters
    ----------
    path : path-like
        The file to write.
    mode : {"w", "wt", "wb"}
        Text or binary.
    encoding, newline :
        As for ``open``, text mode only.

    Yields
    ------
    file object

    Raises
    ------
    InputError
        The directory is missing or not writable, ``path`` is a directory or a link loop.
    OutputError
        Writing failed part way (a full disk, an I/O error); nothing was left.
    """
    if mode not in ("w", "wt", "wb"):
        raise ValueError(f"atomic_write: mode must be 'w', 'wt' or 'wb', got {mode!r}")
    given = Path(path)
    path = resolve_output(given)
    directory = path.parent
    if path.is_dir():
        raise InputError(f"{given}: is a directory; give a file name")
    with contextlib.suppress(OSError):
        remove_stale_temporaries(path)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=_temp_prefix(path), suffix=".tmp", dir=directory)
    except FileNotFoundError as error:
        if directory.is_dir():
            raise InputError(f"{given}: cannot write ({error.strerror})") from None
        raise InputError(f"{given}: directory {str(directory)!r} does not exist") from None
    except NotADirectoryError:
        raise InputError(f"{given}: {str(directory)!r} is not a directory") from None
    except OSError as error:
        raise InputError(f"{given}: cannot write ({error.strerror})") from None
    try:
        text_options = {} if "b" in mode else {"encoding": encoding, "newline": newline}
        try:
            with os.fdopen(fd, mode, **text_options) as handle:
                yield handle
                handle.flush()
                os.fsync(handle.fileno())
            try:
                permissions = path.stat().st_mode & 0o7777
            except FileNotFoundError:
                permissions = 0o666 & ~_current_umask()
            os.chmod(tmp_name, permissions)
            os.replace(tmp_name, path)
        except OSError as error:
            if isinstance(error, (GsfricError, BrokenPipeError)):
                raise
            raise _write_failure(given, error) from None
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp_name)
        raise
    _sync_directory(directory)


def _sync_directory(directory: Path) -> None:
    with contextlib.suppress(OSError):
        dir_fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)


@contextlib.contextmanager
def output_folder(path: str | os.PathLike[str], *,
                  inputs: Iterable[str | os.PathLike[str] | None] = ()) -> Iterator[Path]:
    """Write a set of outputs into a temporary folder and move them into ``path`` as a whole.

    Yields a new empty folder beside ``path`` (``.{name}.gsfric-{pid}-{random}.tmp``). When the
    block ends without an error, the folder itself is renamed to ``path`` if ``path`` does not
    exist or is empty; otherwise each file is renamed into ``path`` (other files there are
    left alone). Only renames happen then, which need no disk space: either every output of
    the run is in place or, if the block raises or a signal interrupts it, none is and the
    temporary folder is removed (earlier outputs stay as they were). Files of ``inputs`` are
    never replaced: an output of the same name raises ``InputError`` before anything moves.

    Parameters
    ----------
    path : path-like
        The output directory (created with its parents if missing).
    inputs : iterable of path-like
        Files the run reads (``None`` entries are ignored).

    Yields
    ------
    Path
        The temporary folder to write into (plain files only).

    Raises
    ------
    InputError
        ``path`` exists and is not a directory, cannot be created or written, or an output
        would replace one of ``inputs``.
    OutputError
        A write failed (a full disk); nothing was left.
    """
    import shutil

    given = Path(path)
    path = resolve_output(given)
    if path.exists() and not path.is_dir():
        raise InputError(f"{given}: exists and is not a directory")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise InputError(f"{given}: {str(path.parent)!r} is not a directory") from None
    except OSError as error:
        raise InputError(f"{given}: cannot create the directory ({error.strerror})") from None
    with contextlib.suppress(OSError):
        remove_stale_temporaries(path)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(path), suffix=".tmp", dir=path.parent))
    except OSError as error:
        raise InputError(f"{given}: cannot write in {str(path.parent)!r} "
                         f"({error.strerror})") from None
    try:
        try:
            yield tmp
            names = sorted(p.name for p in tmp.iterdir())
            protected = [Path(p) for p in inputs if p is not None]
            for name in names:
                target = path / name
                for source in protected:
                    with contextlib.suppress(OSError):
                        if target.exists() and os.path.samefile(target, source):
                            raise InputError(f"{given}: writing {name} would replace the input "
                                             f"file {source}; choose another output directory")
            if not path.exists() or (path.is_dir() and not any(path.iterdir())):
                os.chmod(tmp, 0o777 & ~_current_umask())
                if path.exists():
                    path.rmdir()
                os.replace(tmp, path)
            else:
                if not os.access(path, os.W_OK | os.X_OK):
                    raise InputError(f"{given}: directory is not writable")
                for name in names:
                    os.replace(tmp / name, path / name)
                tmp.rmdir()
            _sync_directory(path.parent)
        except OSError as error:
            if isinstance(error, (GsfricError, BrokenPipeError)):
                raise
            raise _write_failure(given, error, "output") from None
        except OutputError as error:   # name the final path, not the temporary folder
            raise OutputError(str(error).replace(str(tmp), str(given))) from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


# -- tables -------------------------------------------------------------------------------------


def _table_kind(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix in _CSV:
        return "csv"
    if suffix in _PARQUET:
        return "parquet"
    raise InputError(f"{path}: unknown extension {suffix or '(none)'!r}; "
                     "use .csv, .parquet or .pq")


def _field_count_problem(path: Path) -> str | None:
    """'row N has K fields but the header has M' for the first such data row, or None."""
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            lines = (line for line in csv.reader(handle, skipinitialspace=True) if line)
            header = next(lines, None)
            if header is None:
                return None
            for row, fields in enumerate(lines, start=1):
                if len(fields) > len(header):
                    return (f"row {row} has {len(fields)} fields but the header has "
                            f"{len(header)}")
    except (OSError, ValueError, csv.Error):
        return None
    return None


def check_file(path: Path) -> str:
    """The table kind ("csv" or "parquet") of an existing, non-empty file; InputError if not."""
    kind = _table_kind(path)
    try:
        status = os.stat(path)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise InputError(f"{path}: symbolic link loop (too many levels of symbolic "
                             "links)") from None
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    if stat.S_ISDIR(status.st_mode):
        raise InputError(f"{path}: is a directory, not a file")
    size = status.st_size
    if size == 0:
        raise InputError(f"{path}: file is empty")
    return kind


def csv_options() -> dict[str, Any]:
    """pandas.read_csv options: only an empty cell is missing; floats read back exactly."""
    import pandas as pd

    options: dict[str, Any] = {"index_col": False, "skipinitialspace": True,
                               "keep_default_na": False, "na_values": [""]}
    if int(pd.__version__.split(".")[0]) < 3:
        options["float_precision"] = "round_trip"
    return options


def check_unique_columns(path: Path, names: list[str]) -> None:
    """InputError when pandas renamed a repeated CSV column ``x`` to ``x.1``."""
    for name in names:
        match = re.fullmatch(r"(.*)\.[0-9]+", name)
        if match and match.group(1) in names:
            raise InputError(f"{path}: column {match.group(1)!r} appears more than once")


def numeric_columns(path: Path, frame, names: list[str], first_row: int = 0) -> dict:
    """The frame's columns as float arrays under ``names``; InputError naming the first bad row.

    ``first_row`` is the 0-based data row of the frame's first row in the file (for blocks).
    """
    columns: dict[str, np.ndarray] = {}
    problems = []
    for original, name in zip(frame.columns, names):
        values, problem = _column_values(frame[original], name)
        columns[name] = values
        if problem is not None:
            problems.append(problem)
    if problems:
        row, message = min(problems, key=lambda p: p[0])
        raise InputError(f"{path}: row {first_row + row + 1}: {message}")
    return columns


def read_table(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a CSV or Parquet file (chosen by extension) into a DataFrame.

    CSV floats are read back exactly as ``write_table`` wrote them. Column names are strings;
    a CSV column name that appears twice is an error.

    Raises
    ------
    InputError
        Missing file, unknown extension, empty file, unparsable content, duplicate columns.
    """
    import pandas as pd

    path = Path(path)
    kind = check_file(path)
    if kind == "csv":
        options = csv_options()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", pd.errors.ParserWarning)
                frame = pd.read_csv(path, **options)
        except pd.errors.EmptyDataError:
            raise InputError(f"{path}: file is empty (no header line)") from None
        except UnicodeDecodeError as error:
            raise InputError(f"{path}: not UTF-8 text (byte {error.start})") from None
        except (ValueError, OverflowError, pd.errors.ParserError,
                pd.errors.ParserWarning) as error:
            reason = _field_count_problem(path) or str(error)
            raise InputError(f"{path}: cannot parse as CSV: {reason}") from None
        except OSError as error:
            raise InputError(f"{path}: cannot read ({error.strerror})") from None
        names = [str(c) for c in frame.columns]
        check_unique_columns(path, names)
    else:
        import pyarrow

        try:
            frame = pd.read_parquet(path)
        except (pyarrow.ArrowException, ValueError, TypeError, OSError,
                NotImplementedError) as error:
            raise InputError(f"{path}: cannot read as Parquet: {error}") from None
        names = [str(c) for c in frame.columns]
        if len(set(names)) != len(names):
            raise InputError(f"{path}: a column name appears more than once")
    frame.columns = names
    return frame


def write_table(frame: pd.DataFrame, path: str | os.PathLike[str]) -> None:
    """Write a DataFrame as CSV or Parquet (chosen by extension), atomically, without index.

    CSV floats are written with full precision, so ``read_table`` gives them back exactly.
    """
    path = Path(path)
    if _table_kind(path) == "csv":
        with atomic_write(path, "w", newline="") as handle:
            frame.to_csv(handle, index=False)
    else:
        with atomic_write(path, "wb") as handle:
            frame.to_parquet(handle, index=False)


# -- trajectories and measured data -------------------------------------------------------------


def _check_columns(path: Path, names: list[str], measured: bool) -> tuple[str, ...]:
    """Validate column names; return the orientation columns to use."""
    allowed = TIME_POSITION + EULER + QUATERNION + ((FORCES + LENGTHS) if measured else ())
    for name in names:
        if name not in allowed:
            if name in FORCES + LENGTHS:
                raise InputError(f"{path}: column {name!r} belongs in a measured-data file, "
                                 "not in a trajectory")
            raise InputError(f"{path}: unknown column {short(name)}{suggest(name, allowed)}")
    for name in TIME_POSITION:
        if name not in names:
            raise InputError(f"{path}: missing column {name!r}")
    has_euler = [n for n in EULER if n in names]
    has_quaternion = [n for n in QUATERNION if n in names]
    for group, present in ((EULER, has_euler), (QUATERNION, has_quaternion)):
        if present:
            for name in group:
                if name not in names:
                    raise InputError(f"{path}: missing column {name!r} "
                                     f"(columns {', '.join(group)} go together)")
    if not has_euler and not has_quaternion:
        raise InputError(f"{path}: missing orientation: give columns alpha, beta, gamma "
                         "or qw, qx, qy, qz")
    if measured:
        for name in FORCES:
            if name not in names:
                raise InputError(f"{path}: missing column {name!r} (measured data need F1..F6)")
        lengths = [n for n in LENGTHS if n in names]
        if lengths and len(lengths) < 6:
            missing = [n for n in LENGTHS if n not in names]
            raise InputError(f"{path}: missing column {missing[0]!r} "
                             "(give all of D1..D6 or none)")
    return QUATERNION if has_quaternion else EULER


def _column_values(series: pd.Series, name: str) -> tuple[np.ndarray, tuple[int, str] | None]:
    """The column as floats and the first problem as (0-based row, message), or None."""
    import pandas as pd

    kind = series.dtype.kind
    if kind == "b":
        return np.empty(0), (0, f"column {name!r} holds true/false values, not numbers")
    if kind in "iuf":
        values = series.to_numpy(dtype=float, na_value=np.nan)
    elif kind in "OUS":
        try:
            numeric = pd.to_numeric(series, errors="coerce")
        except (TypeError, ValueError):
            return np.empty(0), (0, f"column {name!r} holds values that are not numbers")
        unparsed = numeric.isna().to_numpy() & series.notna().to_numpy()
        spelled_nan = np.array([isinstance(v, str) and v.strip().lower() in _NAN_WORDS
                                for v in series], dtype=bool)
        bad = np.flatnonzero(unparsed & ~spelled_nan)
        if len(bad):
            value = series.iloc[bad[0]]
            return np.empty(0), (int(bad[0]), f"column {name!r} is not a number: {short(value)}")
        values = numeric.to_numpy(dtype=float, na_value=np.nan)
    else:
        return np.empty(0), (0, f"column {name!r} has type {series.dtype}, not numbers")
    bad = np.flatnonzero(~np.isfinite(values))
    if len(bad):
        row = int(bad[0])
        problem = "is empty or NaN" if np.isnan(values[row]) else "is infinite"
        return values, (row, f"column {name!r} {problem}")
    return values, None


def _read_samples(path: str | os.PathLike[str], measured: bool
                  ) -> tuple[Path, dict[str, np.ndarray], tuple[str, ...]]:
    path = Path(path)
    frame = read_table(path)
    names = [name.strip() for name in frame.columns]
    if len(set(names)) != len(names):
        duplicate = next(n for n in names if names.count(n) > 1)
        raise InputError(f"{path}: column {duplicate!r} appears more than once")
    orientation = _check_columns(path, names, measured)
    if len(frame) == 0:
        raise InputError(f"{path}: no data rows")

    columns = numeric_columns(path, frame, names)
    t = columns["t"]
    with np.errstate(over="ignore", invalid="ignore"):
        steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if len(bad):
        i = int(bad[0]) + 1
        if steps[i - 1] == 0:
            raise InputError(f"{path}: row {i + 1}: duplicate time t = {float(t[i])!r} "
                             f"(same as row {i})")
        raise InputError(f"{path}: row {i + 1}: t = {float(t[i])!r} is less than "
                         f"t = {float(t[i - 1])!r} in row {i}; t must increase")
    if len(t) < MIN_SAMPLES:
        raise InputError(f"{path}: {len(t)} data rows; at least {MIN_SAMPLES} are needed "
                         "to differentiate the motion")
    if measured:
        forces = np.stack([columns[n] for n in FORCES], axis=1)
        bad_rows, bad_legs = np.nonzero(np.abs(forces) > MAX_FORCE)
        if len(bad_rows):
            value = forces[bad_rows[0], bad_legs[0]]
            raise InputError(f"{path}: row {bad_rows[0] + 1}: column 'F{bad_legs[0] + 1}' = "
                             f"{value:.4g} N is not a plausible actuator force (|F| > "
                             f"{MAX_FORCE:g} N); forces must be in N")
    if measured and "D1" in columns:
        lengths = np.stack([columns[n] for n in LENGTHS], axis=1)
        bad_rows, bad_legs = np.nonzero(lengths <= 0)
        if len(bad_rows):
            raise InputError(f"{path}: row {bad_rows[0] + 1}: column "
                             f"'D{bad_legs[0] + 1}' must be positive (a leg length)")
    return path, columns, orientation


def _motion(path: Path, columns: dict[str, np.ndarray], orientation: tuple[str, ...],
            window: int | None, polyorder: int) -> Motion:
    position = np.stack([columns[n] for n in ("x", "y", "z")], axis=1)
    angles = np.stack([columns[n] for n in orientation], axis=1)
    key = "quaternion" if orientation == QUATERNION else "euler"
    return Motion.from_samples(columns["t"], position, window=window, polyorder=polyorder,
                               source=str(path), **{key: angles})


def read_trajectory(path: str | os.PathLike[str], *, window: int | None = None,
                    polyorder: int = DEFAULT_POLYORDER) -> Motion:
    """Read a trajectory file and differentiate it into a ``Motion``.

    Parameters
    ----------
    path : path-like
        CSV or Parquet with ``t, x, y, z`` and ``alpha, beta, gamma`` or ``qw, qx, qy, qz``.
    window, polyorder :
        Smoothing of the differentiation, see ``Motion.from_samples``.

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
    """
    path, columns, orientation = _read_samples(path, measured=False)
    return _motion(path, columns, orientation, window, polyorder)


def read_measured(path: str | os.PathLike[str], *, window: int | None = None,
                  polyorder: int = DEFAULT_POLYORDER
                  ) -> tuple[Motion, np.ndarray, np.ndarray | None]:
    """Read a measured-data file: the trajectory columns plus ``F1..F6`` and optional ``D1..D6``.

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
    """
    path, columns, orientation = _read_samples(path, measured=True)
    motion = _motion(path, columns, orientation, window, polyorder)
    forces = np.stack([columns[n] for n in FORCES], axis=1)
    lengths = np.stack([columns[n] for n in LENGTHS], axis=1) if "D1" in columns else None
    return motion, forces, lengths
