"""Arrow arrays of numbers to NumPy and back, without copies and without pandas.

``pyarrow``'s own conversions (``Array.to_numpy``, ``pyarrow.array``) import pandas on first
use, to recognise pandas objects, which costs about 0.15 s at the start of every streamed run
that never needs it. Arrays of fixed-width numbers without nulls are plain buffers on both
sides, and are converted here; anything else is left to pyarrow and pandas.
"""

from __future__ import annotations

import json
import re

import numpy as np

from gsfric._optional import optional

_UNNAMED_INDEX = re.compile(r"__index_level_[0-9]+__")
"""How pandas names the column of an unnamed index it stores in a Parquet file."""


def numpy_view(array) -> np.ndarray | None:
    """A NumPy view of ``array`` (a ``pyarrow.Array``) when it holds integers or
    floats without nulls; None for anything else (nulls, booleans, strings, times...)."""
    pa = optional("pyarrow")
    kind = array.type
    if array.null_count or not (pa.types.is_integer(kind) or pa.types.is_floating(kind)):
        return None
    # not kind.to_pandas_dtype(), which imports pandas (before pyarrow 26)
    code = "f" if pa.types.is_floating(kind) else "iu"[pa.types.is_unsigned_integer(kind)]
    dtype = np.dtype(f"{code}{kind.byte_width}")
    return np.frombuffer(array.buffers()[1], dtype=dtype, count=len(array),
                         offset=array.offset * dtype.itemsize)


def arrow_array(values: np.ndarray):
    """A ``pyarrow.Array`` of a 1-D NumPy array: over the same memory for contiguous integers
    or floats, as ``pyarrow.array`` converts it otherwise; in an array of objects (text with
    gaps, as pandas reads it), None and NaN are missing values."""
    pa = optional("pyarrow")
    if values.ndim != 1 or values.dtype.kind not in "iuf" or not values.flags.c_contiguous \
            or not values.dtype.isnative:
        return pa.array(values, from_pandas=values.dtype.kind == "O")
    return pa.Array.from_buffers(pa.from_numpy_dtype(values.dtype), len(values),
                                 [None, pa.py_buffer(values)])


def column_from_arrow(array):
    """A column of an Arrow table or record batch (``Array`` or ``ChunkedArray``): numbers
    without nulls as NumPy (a view of a single chunk), anything else as the pandas Series
    pyarrow converts it to (nulls, strings, timestamps...)."""
    chunks = getattr(array, "chunks", [array])
    views = [numpy_view(chunk) for chunk in chunks]
    if not views or any(v is None for v in views):
        return array.to_pandas()
    return views[0] if len(views) == 1 else np.concatenate(views)


def data_columns(schema) -> list[int]:
    """The indices of the columns of an Arrow ``schema`` that hold data: all but an unnamed
    index a pandas DataFrame stored beside its columns (``__index_level_0__``, named in the
    schema's pandas metadata). A named index (``df.set_index("t")``) is a column like the
    others; metadata that cannot be read is ignored."""
    try:
        index = json.loads((schema.metadata or {})[b"pandas"])["index_columns"]
        unnamed = {c for c in index if isinstance(c, str) and _UNNAMED_INDEX.fullmatch(c)}
    except (KeyError, TypeError, ValueError):
        unnamed = set()
    return [k for k, name in enumerate(schema.names) if name not in unnamed]
