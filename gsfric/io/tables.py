"""Tables on disk, CSV or Parquet by extension: reading with one-line errors naming the file, row
and column, and writing atomically."""

from __future__ import annotations

import csv
import errno
import os
import re
import stat
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from gsfric._checks import short
from gsfric._optional import optional
from gsfric.errors import InputError
from gsfric.io.arrow import column_from_arrow, data_columns
from gsfric.io.files import atomic_write, is_stream, not_utf8

if TYPE_CHECKING:
    import pandas as pd

NAN_WORDS = ("nan", "-nan", "+nan")


_CSV = (".csv",)


_PARQUET = (".parquet", ".pq")


def table_kind(path: Path) -> str:
    """"csv" or "parquet", by the extension; "csv" for a character device or FIFO without one
    (``/dev/null``, ``/dev/stdout``)."""
    suffix = path.suffix.lower()
    if suffix in _CSV or (not suffix and is_stream(path)):
        return "csv"
    if suffix in _PARQUET:
        return "parquet"
    raise InputError(f"{path}: unknown extension {suffix or '(none)'!r}; "
                     "use .csv, .parquet or .pq")


def field_count_problem(path: Path) -> str | None:
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
    kind = table_kind(path)
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
    pd = optional("pandas")

    options: dict[str, Any] = {"index_col": False, "skipinitialspace": True,
                               "keep_default_na": False, "na_values": [""]}
    if int(pd.__version__.split(".")[0]) < 3:
        options["float_precision"] = "round_trip"
    return options


OTHER_SEPARATORS = {";": "semicolons", "\t": "tabs", "|": "vertical bars"}
"""Separators of other CSV dialects: a header read as one column holding one of them is such
a file (gsfric reads comma-separated values, with a point as the decimal mark)."""


@contextmanager
def csv_errors(path: Path) -> Iterator[None]:
    """Around pandas reading the CSV file ``path``: its ``ParserWarning`` made an error, and
    its errors (empty file, not UTF-8, unparsable, unreadable) as one-line ``InputError``s
    naming the file (and the first row with too many or too few fields)."""
    pd = optional("pandas")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", pd.errors.ParserWarning)
            yield
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: file is empty (no header line)") from None
    except UnicodeDecodeError:
        raise not_utf8(path) from None
    except (ValueError, OverflowError, pd.errors.ParserError, pd.errors.ParserWarning) as error:
        reason = field_count_problem(path) or str(error)
        raise InputError(f"{path}: cannot parse as CSV: {reason}") from None
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None


def check_csv_header(path: Path, names: list[str]) -> None:
    """InputError for a CSV header read as one column that holds another dialect's separator
    (``OTHER_SEPARATORS``, naming it), or with a repeated column (``x`` renamed ``x.1`` by
    pandas)."""
    if len(names) == 1:
        for mark, what in OTHER_SEPARATORS.items():
            if mark in names[0]:
                raise InputError(f"{path}: the header {names[0][:40]!r} is one column separated "
                                 f"by {what}: write the file with commas between the columns "
                                 "(and a point as the decimal mark)")
    for name in names:
        match = re.fullmatch(r"(.*)\.[0-9]+", name)
        if match and match.group(1) in names:
            raise InputError(f"{path}: column {match.group(1)!r} appears more than once")


def numeric_columns(path: Path, columns: list, names: list[str], first_row: int = 0) -> dict:
    """The ``columns`` (Series or NumPy arrays) as float arrays under ``names``; InputError
    naming the first bad row.

    ``first_row`` is the 0-based data row of the columns' first row in the file (for blocks).
    """
    values_of: dict[str, np.ndarray] = {}
    problems = []
    for column, name in zip(columns, names):
        values, problem = column_values(column, name)
        values_of[name] = values
        if problem is not None:
            problems.append(problem)
    if problems:
        row, message = min(problems, key=lambda p: p[0])
        raise InputError(f"{path}: row {first_row + row + 1}: {message}")
    return values_of


def count_rows(path: str | os.PathLike[str]) -> int | None:
    """Data rows of a table file (for a progress bar's total), or None if it cannot tell.

    Parquet: from the metadata. CSV: the lines after the header, counted in binary
    blocks (about a second per gigabyte; quoted line breaks are not expected in these files).
    """
    path = Path(path)
    try:
        if table_kind(path) == "parquet":
            pq = optional("pyarrow.parquet")
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
    pd = optional("pandas")

    path = Path(path)
    kind = check_file(path)
    if kind == "csv":
        with csv_errors(path):
            frame = pd.read_csv(path, **csv_options())
        names = [str(c) for c in frame.columns]
        check_csv_header(path, names)
    else:
        pyarrow = optional("pyarrow")
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


def read_columns(path: str | os.PathLike[str]) -> tuple[list[str], list]:
    """The columns of a CSV or Parquet file, with the checks and messages of ``read_table``.

    Returns the column names and the columns: NumPy arrays for numbers without gaps, pandas
    Series for anything else. A Parquet file of numbers is read without pandas. Of an index
    that pandas stored in the file, a named one (``df.set_index("t")``) is a column like the
    others, an unnamed one is left out.
    """
    path = Path(path)
    if check_file(path) == "csv":
        frame = read_table(path)
        return list(frame.columns), [frame.iloc[:, k] for k in range(frame.shape[1])]
    pyarrow = optional("pyarrow")
    pq = optional("pyarrow.parquet")
    try:
        table = pq.ParquetFile(path).read()
        keep = data_columns(table.schema)
        names = [str(table.schema.names[k]) for k in keep]
        columns = [column_from_arrow(table.column(k)) for k in keep]
    except (pyarrow.ArrowException, ValueError, TypeError, OSError,
            NotImplementedError) as error:
        raise InputError(f"{path}: cannot read as Parquet: {error}") from None
    if len(set(names)) != len(names):
        raise InputError(f"{path}: a column name appears more than once")
    return names, columns


def write_table(frame: pd.DataFrame, path: str | os.PathLike[str]) -> None:
    """Write a DataFrame as CSV or Parquet (chosen by extension), atomically, without index.

    CSV floats are written with full precision, so ``read_table`` gives them back exactly.
    """
    path = Path(path)
    if table_kind(path) == "csv":
        with atomic_write(path, "w", newline="") as handle:
            frame.to_csv(handle, index=False)
    else:
        with atomic_write(path, "wb") as handle:
            frame.to_parquet(handle, index=False)


def column_values(series: pd.Series | np.ndarray,
                  name: str) -> tuple[np.ndarray, tuple[int, str] | None]:
    """The column (a Series, or a NumPy array of numbers) as floats and the first problem as
    (0-based row, message), or None."""
    kind = series.dtype.kind
    if kind == "b":
        return np.empty(0), (0, f"column {name!r} holds true/false values, not numbers")
    if kind in "iuf" and isinstance(series, np.ndarray):
        values = series.astype(float, copy=False)
    elif kind in "iuf":
        values = series.to_numpy(dtype=float, na_value=np.nan)
    elif kind in "OUS":
        pd = optional("pandas")
        series = pd.Series(series, copy=False)
        try:
            numeric = pd.to_numeric(series, errors="coerce")
        except (TypeError, ValueError):
            return np.empty(0), (0, f"column {name!r} holds values that are not numbers")
        unparsed = numeric.isna().to_numpy() & series.notna().to_numpy()
        spelled_nan = np.array([isinstance(v, str) and v.strip().lower() in NAN_WORDS
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
