"""Reading and writing files: tables (CSV or Parquet), trajectories, measured data.

The format follows the extension: ``.csv`` or ``.parquet`` / ``.pq`` (case-insensitive). Every
problem with an input file raises an ``InputError`` with a one-line message naming the file and,
where it applies, the row and the column, e.g. ``trajectory.csv: row 17: column 'x' is NaN``.
Rows are data rows counted from 1 (the CSV header is not counted).

Trajectory files hold ``t, x, y, z`` (s, m; platform frame origin in the base frame) and either
the ZXZ angles ``alpha, beta, gamma`` (rad) or a unit quaternion ``qw, qx, qy, qz`` (platform
frame to base frame) or roll, pitch, yaw angles ``roll, pitch, yaw`` (see ``LogFormat`` for
their convention). When several sets are present the quaternion is used, then the ZXZ angles.
Measured-data files add ``F1..F6`` (actuator forces, N, all six required) and optionally
``D1..D6`` (leg lengths, m, all six or none). Other columns are ignored, with one warning naming
them.

A log written by another program (a controller's names and units, a wrapping microsecond
counter, roll/pitch/yaw) is read with a ``LogFormat``: a column map, units per column, the
angle convention and the columns to carry through; see docs/logs.md.

Writes are atomic (``atomic_write``): a reader never sees a partly written file.
"""

from __future__ import annotations

import contextlib
import contextvars
import csv
import difflib
import errno
import os
import re
import stat
import tempfile
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from gsfric._checks import short, suggest
from gsfric.errors import GsfricError, GsfricWarning, InputError, OutputError
from gsfric.trajectory import DEFAULT_POLYORDER, MIN_SAMPLES, Motion

if TYPE_CHECKING:
    import pandas as pd

TIME_POSITION = ("t", "x", "y", "z")
EULER = ("alpha", "beta", "gamma")
QUATERNION = ("qw", "qx", "qy", "qz")
FORCES = tuple(f"F{i}" for i in range(1, 7))
LENGTHS = tuple(f"D{i}" for i in range(1, 7))

RPY = ("roll", "pitch", "yaw")
KNOWN = TIME_POSITION + EULER + QUATERNION + RPY + FORCES + LENGTHS
"""Every input column gsfric reads; others are ignored (or carried through, ``LogFormat.keep``)."""

UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6},
    "angle": {"rad": 1.0, "deg": np.pi / 180.0, "mrad": 1e-3},
    "force": {"N": 1.0, "kN": 1e3},
    "quaternion": {"1": 1.0},
}
"""Accepted units per quantity and their factor to SI."""

RPY_CONVENTIONS = {"xyz": "extrinsic x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll)",
                   "XYZ": "intrinsic X, Y, Z: R = Rx(roll) Ry(pitch) Rz(yaw)"}

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


_COMMIT_CHECK: contextvars.ContextVar = contextvars.ContextVar("gsfric_commit_check",
                                                               default=None)


@contextlib.contextmanager
def commit_check(check) -> Iterator[None]:
    """Within the block, ``atomic_write`` and ``output_folder`` call ``check()`` (in the calling
    context) just before they move their outputs into place; an exception it raises leaves the
    earlier outputs as they were. The command line checks for a stop signal there: one whose
    exception the interpreter swallowed (raised inside a callback, reported as "Exception
    ignored") must still keep a half-done run from replacing them."""
    token = _COMMIT_CHECK.set(check)
    try:
        yield
    finally:
        _COMMIT_CHECK.reset(token)


def _before_commit() -> None:
    check = _COMMIT_CHECK.get()
    if check is not None:
        check()


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
            _before_commit()
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
            _before_commit()
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


def count_rows(path: str | os.PathLike[str]) -> int | None:
    """Data rows of a table file (for a progress bar's total), or None if it cannot tell.

    Parquet: from the metadata. CSV: the lines after the header, counted in binary
    blocks (about a second per gigabyte; quoted line breaks are not expected in these files).
    """
    path = Path(path)
    try:
        if _table_kind(path) == "parquet":
            import pyarrow.parquet as pq

            return int(pq.ParquetFile(path).metadata.num_rows)
        lines, last = 0, b"\n"
        with open(path, "rb") as handle:
            while block := handle.read(1 << 20):
                lines += block.count(b"\n")
                last = block[-1:]
        return max(0, lines + (last != b"\n") - 1)
    except Exception:  # noqa: BLE001 - the reader reports the problem properly
        return None


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


# -- logs: column maps, units, angle conventions ------------------------------------------------


def _quantity(name: str) -> str:
    if name == "t":
        return "time"
    if name in ("x", "y", "z") or name in LENGTHS:
        return "length"
    if name in EULER or name in RPY:
        return "angle"
    if name in FORCES:
        return "force"
    return "quaternion"


def _pairs(text: str, what: str) -> dict[str, str]:
    """``"a=b,c=d"`` as {a: b, c: d}; InputError naming ``what`` on a malformed item."""
    out: dict[str, str] = {}
    for item in (part.strip() for part in str(text).split(",")):
        if not item:
            continue
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise InputError(f"{what}: expected name=value, got {short(item)}")
        out[key.strip()] = value.strip()
    return out


@dataclass(frozen=True)
class LogFormat:
    """How to read a log whose column names, units or angles are not gsfric's own.

    Parameters
    ----------
    columns : mapping of str to str
        gsfric's column name (``t, x, y, z``, ``alpha, beta, gamma``, ``qw..qz``,
        ``roll, pitch, yaw``, ``F1..F6``, ``D1..D6``) to the log's column name. Unmapped names
        are looked up as they are.
    units : mapping of str to str
        gsfric's column name to the unit of the log's column: ``s, ms, us, ns`` (t);
        ``m, cm, mm, um`` (x, y, z, D1..D6); ``rad, deg, mrad`` (angles); ``N, kN`` (F1..F6).
        Values are converted to SI on reading; unlisted columns are in SI already.
    angles : {"xyz", "XYZ"}
        Convention of ``roll, pitch, yaw`` (rotation from platform frame to base frame, as
        SciPy's ``Rotation.from_euler`` names it): "xyz" extrinsic about the base axes x, then
        y, then z, R = Rz(yaw) Ry(pitch) Rx(roll) (the usual vehicle/motion-platform
        convention, the default); "XYZ" intrinsic, R = Rx(roll) Ry(pitch) Rz(yaw).
    wrap : int, optional
        Modulus of an integer time counter that wraps around (e.g. 2**32 for a uint32
        microsecond counter). Default: 2**16, 2**32 or 2**64, the smallest above the largest
        count read. A decrease of more than half the modulus is unwrapped (with a warning);
        any other decrease is an error.
    keep : sequence of str
        Log columns carried through unchanged to ``simulate``'s output (others are ignored).

    The TOML form (``LogFormat.from_toml``; ``gsfric simulate --column-map FILE.toml``)::

        angles = "xyz"
        keep = ["temperature"]
        [columns]
        t = "C2H time (us)"
        x = "pos_x"
        [units]
        t = "us"
        x = "mm"
    """

    columns: Mapping[str, str] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    angles: str = "xyz"
    wrap: int | None = None
    keep: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        columns = {str(k): str(v) for k, v in dict(self.columns).items()}
        units = {str(k): str(v) for k, v in dict(self.units).items()}
        for key in list(columns) + list(units):
            if key not in KNOWN:
                raise InputError(f"column map: unknown gsfric column {short(key)}"
                                 f"{suggest(key, KNOWN)}")
        seen: dict[str, str] = {}
        for key, source in columns.items():
            if source in seen:
                raise InputError(f"column map: column {source!r} is mapped to both "
                                 f"{seen[source]!r} and {key!r}")
            seen[source] = key
        for key, unit in units.items():
            choices = UNITS[_quantity(key)]
            if unit not in choices:
                raise InputError(f"units: {key!r} in {unit!r}: use one of "
                                 f"{', '.join(choices)}")
        if self.angles not in RPY_CONVENTIONS:
            raise InputError(f"angles: unknown convention {short(self.angles)}; use 'xyz' "
                             "(extrinsic) or 'XYZ' (intrinsic)")
        wrap = self.wrap
        if wrap is not None and (isinstance(wrap, bool) or not isinstance(wrap, (int, np.integer))
                                 or wrap < 2):
            raise InputError(f"wrap: must be an integer >= 2, got {short(wrap)}")
        keep = (self.keep,) if isinstance(self.keep, str) else tuple(map(str, self.keep))
        object.__setattr__(self, "columns", columns)
        object.__setattr__(self, "units", units)
        object.__setattr__(self, "keep", keep)

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str]) -> LogFormat:
        """Read a TOML file with ``[columns]``, ``[units]``, ``angles``, ``wrap``, ``keep``."""
        return cls.from_mapping(_read_toml(path), str(path))

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "column map") -> LogFormat:
        allowed = ("columns", "units", "angles", "wrap", "keep")
        for key in data:
            if key not in allowed:
                raise InputError(f"{where}: unknown key {short(key)}{suggest(key, allowed)}")
        for key in ("columns", "units"):
            if not isinstance(data.get(key, {}), dict):
                raise InputError(f"{where}: [{key}] must be a table of name = \"value\"")
        try:
            return cls(columns=data.get("columns", {}), units=data.get("units", {}),
                       angles=data.get("angles", "xyz"), wrap=data.get("wrap"),
                       keep=tuple(data.get("keep", ())))
        except InputError as error:
            raise InputError(f"{where}: {error}") from None

    @classmethod
    def from_options(cls, column_map: str | None = None, units: str | None = None,
                     angles: str | None = None, keep: str | None = None) -> LogFormat | None:
        """The command line's form: ``--column-map`` (a .toml file or ``t=col,x=col``),
        ``--units t=us,x=mm``, ``--angles``, ``--keep-columns a,b``; None when all are None."""
        if column_map is None and units is None and angles is None and keep is None:
            return None
        data: dict[str, Any] = {}
        if column_map is not None:
            if str(column_map).lower().endswith(".toml"):
                data = dict(_read_toml(column_map))
            else:
                data["columns"] = _pairs(column_map, "--column-map")
        where = str(column_map) if data and column_map and str(column_map).lower().endswith(
            ".toml") else "column map"
        if units is not None:
            data["units"] = {**data.get("units", {}), **_pairs(units, "--units")}
        if angles is not None:
            data["angles"] = angles
        if keep is not None:
            data["keep"] = [k.strip() for k in keep.split(",") if k.strip()]
        return cls.from_mapping(data, where)


def _read_toml(path) -> dict:
    import tomllib

    path = Path(path)
    try:
        with open(path, "rb") as handle:
            return tomllib.load(handle)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{path}: not valid TOML ({error})") from None


def _rpy_quaternion(angles: np.ndarray, convention: str) -> np.ndarray:
    """Unit quaternions (w, x, y, z), (N, 4), of roll, pitch, yaw (N, 3) rad."""
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_euler(convention, angles).as_quat()
    return np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)


class ColumnReader:
    """Reads a log's blocks of rows into gsfric's columns, in SI units.

    One reader per file, fed its blocks in order (it keeps the state of a wrapping time
    counter). ``check`` validates the header once; ``read`` converts a block.

    Attributes
    ----------
    orientation : tuple of str
        The orientation columns of the converted blocks: ``QUATERNION`` (also for roll, pitch,
        yaw, converted) or ``EULER``.
    forces : bool
        The log has F1..F6.
    keep : tuple of str
        Log columns carried through (``LogFormat.keep``).
    """

    def __init__(self, path: str | os.PathLike[str], log_format: LogFormat | None = None,
                 measured: bool = False) -> None:
        self.path = Path(path)
        self.format = log_format or LogFormat()
        self.measured = measured
        self.source: dict[str, str] = {}
        self.orientation: tuple[str, ...] = ()
        self.forces = False
        self.keep: tuple[str, ...] = ()
        self._last: int | None = None
        self._offset = 0
        self._largest = 0
        self._wraps: list[int] = []
        self._warned_radians = False

    def check(self, names: list[str]) -> tuple[str, ...]:
        """Validate the header (stripped names); return ``orientation``. Warns of ignored columns."""
        path, fmt = self.path, self.format
        present = set(names)
        for key, column in fmt.columns.items():
            if column not in present:
                raise InputError(f"{path}: column map {key} = {column!r}: no such column"
                                 f"{suggest(column, names)}")
        mapped_sources = set(fmt.columns.values())
        source = {}
        for key in KNOWN:
            column = fmt.columns.get(key, key)
            if key not in fmt.columns and (key not in present or key in mapped_sources):
                continue
            source[key] = column
        for column in fmt.keep:
            if column not in present:
                raise InputError(f"{path}: column {column!r} to keep: no such column"
                                 f"{suggest(column, names)}")
        ignored = [n for n in names if n not in source.values() and n not in fmt.keep]

        def missing(key: str, why: str) -> InputError:
            close = difflib.get_close_matches(key.lower(), [n.lower() for n in ignored], n=1,
                                              cutoff=0.6)
            if close:
                match = next(n for n in ignored if n.lower() == close[0])
                return InputError(f"{path}: missing column {key!r} (is it {match!r}? map it "
                                  f"with --column-map {key}={match})")
            return InputError(f"{path}: missing column {key!r}{why}")

        for key in TIME_POSITION:
            if key not in source:
                raise missing(key, f" (map the log's column to it with --column-map {key}=NAME)")
        has = {group: [n for n in group if n in source] for group in (EULER, QUATERNION, RPY)}
        for group, found in has.items():
            if found:
                for key in group:
                    if key not in source:
                        raise missing(key, f" (columns {', '.join(group)} go together)")
        if not any(has.values()):
            raise InputError(f"{path}: missing orientation: give columns alpha, beta, gamma, "
                             "qw, qx, qy, qz or roll, pitch, yaw")
        angles = QUATERNION if has[QUATERNION] else EULER if has[EULER] else RPY
        for group in (EULER, QUATERNION, RPY):   # other orientation sets: unused, silently
            if group is not angles:
                for key in group:
                    source.pop(key, None)
        forces = [n for n in FORCES if n in source]
        if (self.measured or forces) and len(forces) < 6:
            raise missing(next(n for n in FORCES if n not in source),
                          " (measured data need F1..F6)")
        lengths = [n for n in LENGTHS if n in source]
        if lengths and len(lengths) < 6:
            raise missing(next(n for n in LENGTHS if n not in source),
                          " (give all of D1..D6 or none)")
        for key in fmt.units:
            if key not in source:
                raise InputError(f"{path}: units given for {key!r}, which the file does not have")
        if ignored:
            shown = ", ".join(repr(n) for n in ignored[:8])
            more = f" and {len(ignored) - 8} more" if len(ignored) > 8 else ""
            warnings.warn(f"{path}: ignored columns {shown}{more} (not gsfric inputs; map them "
                          "with --column-map or carry them to the output with --keep-columns; "
                          "in Python: LogFormat columns, keep)",
                          GsfricWarning, stacklevel=3)
        self.source = source
        self.forces = len(forces) == 6
        self.keep = fmt.keep
        self._angles = angles
        self.orientation = QUATERNION if angles is RPY else angles
        return self.orientation

    def read(self, frame, first_row: int = 0) -> dict[str, np.ndarray]:
        """The block's columns (a DataFrame with the stripped header) as gsfric's, SI units.

        Keys: ``t, x, y, z``, the orientation columns, F1..F6 and D1..D6 where present, and
        ``keep:NAME`` for each column carried through (values as in the file).
        """
        keys = list(self.source)
        raw = numeric_columns(self.path, frame[[self.source[k] for k in keys]],
                              [self.source[k] for k in keys], first_row)
        out: dict[str, np.ndarray] = {}
        for key in keys:
            values = raw[self.source[key]]
            if key == "t" and frame[self.source["t"]].dtype.kind in "iu":
                values = self._unwrap(frame[self.source["t"]].to_numpy(), first_row)
            unit = self.format.units.get(key)
            if unit is not None and unit != "1":
                values = values * UNITS[_quantity(key)][unit]
            out[key] = values
        if self._angles is RPY:
            angles = np.stack([out.pop(k) for k in RPY], axis=1)
            if not self._warned_radians and "roll" not in self.format.units and len(angles) \
                    and np.abs(angles).max() > 2 * np.pi:
                self._warned_radians = True
                warnings.warn(f"{self.path}: roll, pitch, yaw look like degrees (above 2*pi); "
                              "give their unit with --units roll=deg,pitch=deg,yaw=deg",
                              GsfricWarning, stacklevel=3)
            q = _rpy_quaternion(angles, self.format.angles)
            for k, key in enumerate(QUATERNION):
                out[key] = q[:, k]
        for column in self.keep:
            out[f"keep:{column}"] = frame[column].to_numpy()
        return out

    def _unwrap(self, counts: np.ndarray, first_row: int) -> np.ndarray:
        """An integer time counter made increasing across its wrap-arounds (as float)."""
        counts = counts.astype(np.int64) if counts.dtype.kind == "u" and counts.max(
            initial=0) < 2**63 else counts
        if len(counts) == 0:
            return counts.astype(float)
        self._largest = max(self._largest, int(counts.max()))
        modulus = self.format.wrap or next(
            (m for m in (2**16, 2**32, 2**64) if self._largest < m), 2**64)
        joined = counts if self._last is None else np.concatenate([[self._last], counts])
        steps = np.diff(joined.astype(float))
        wraps = steps < -modulus / 2
        offsets = np.cumsum(wraps) * float(modulus)
        if self._last is not None:
            values = counts.astype(float) + self._offset + offsets
        else:
            values = counts.astype(float) + self._offset + np.concatenate([[0.0], offsets])
        rows = np.flatnonzero(wraps) + first_row + (1 if self._last is None else 0)
        for row in rows:
            warnings.warn(f"{self.path}: row {row + 1}: time counter {self.source['t']!r} wraps "
                          f"around (modulus {modulus}); unwrapped", GsfricWarning, stacklevel=4)
        self._offset = values[-1] - float(counts[-1])
        self._last = int(counts[-1])
        return values


# -- trajectories and measured data -------------------------------------------------------------


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


def _read_samples(path: str | os.PathLike[str], measured: bool,
                  log_format: LogFormat | None = None
                  ) -> tuple[Path, dict[str, np.ndarray], tuple[str, ...]]:
    path = Path(path)
    return _samples(path, read_table(path), measured, log_format)


def _samples(path, frame, measured: bool, log_format: LogFormat | None
             ) -> tuple[Path, dict[str, np.ndarray], tuple[str, ...]]:
    """The checked columns of a whole table; ``path`` names it in messages."""
    frame = frame.copy(deep=False)
    names = [str(name).strip() for name in frame.columns]
    if len(set(names)) != len(names):
        duplicate = next(n for n in names if names.count(n) > 1)
        raise InputError(f"{path}: column {duplicate!r} appears more than once")
    reader = ColumnReader(path, log_format, measured)
    orientation = reader.check(names)
    if len(frame) == 0:
        raise InputError(f"{path}: no data rows")

    frame.columns = names
    columns = reader.read(frame)
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
    path, columns, orientation = _samples(name, frame.reset_index(drop=True), False,
                                          log_format)
    return _motion(path, columns, orientation, window, polyorder)


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
    """
    path, columns, orientation = _read_samples(path, False, log_format)
    return _motion(path, columns, orientation, window, polyorder)


def read_measured(path: str | os.PathLike[str], *, window: int | None = None,
                  polyorder: int = DEFAULT_POLYORDER, log_format: LogFormat | None = None
                  ) -> tuple[Motion, np.ndarray, np.ndarray | None]:
    """Read a measured-data file: the trajectory columns plus ``F1..F6`` and optional ``D1..D6``.

    ``window``, ``polyorder`` and ``log_format`` as for ``read_trajectory``.

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
    return _read_measured(path, window, polyorder, log_format)[:3]


def _read_measured(path, window, polyorder, log_format):
    """``read_measured`` and the file's columns as read (SI), for callers that also need the
    recorded poses (discovery's rest detection)."""
    path, columns, orientation = _read_samples(path, True, log_format)
    motion = _motion(path, columns, orientation, window, polyorder)
    forces = np.stack([columns[n] for n in FORCES], axis=1)
    lengths = np.stack([columns[n] for n in LENGTHS], axis=1) if "D1" in columns else None
    return motion, forces, lengths, columns
