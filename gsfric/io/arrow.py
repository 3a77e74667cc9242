"""Arrow arrays of numbers to NumPy and back, without copies and without pandas.

``pyarrow``'s own conversions (``Array.to_numpy``, ``pyarrow.array``) import pandas on first
use, to recognise pandas objects, which costs about 0.15 s at the start of every streamed run
that never needs it. Arrays of fixed-width numbers without nulls are plain buffers on both
sides, and are converted here; anything else is left to pyarrow and pandas.
"""

from __future__ import annotations

import numpy as np

from gsfric._optional import optional


def numpy_view(array) -> np.ndarray | None:
    """A NumPy view of ``array`` (a ``pyarrow.Array``) when it holds integers or
    floats without nulls; None for anything else (nulls, booleans, strings, times...)."""
    pa = optional("pyarrow")
    kind = array.type
    if array.null_count or not (pa.types.is_integer(kind) or pa.types.is_floating(kind)):
        return None
    dtype = np.dtype(kind.to_pandas_dtype())
    return np.frombuffer(array.buffers()[1], dtype=dtype, count=len(array),
                         offset=array.offset * dtype.itemsize)


def arrow_array(values: np.ndarray):
    """A ``pyarrow.Array`` of a 1-D NumPy array: over the same memory for contiguous integers
    or floats, as ``pyarrow.array`` converts it otherwise."""
    pa = optional("pyarrow")
    if values.ndim != 1 or values.dtype.kind not in "iuf" or not values.flags.c_contiguous \
            or not values.dtype.isnative:
        return pa.array(values)
    return pa.Array.from_buffers(pa.from_numpy_dtype(values.dtype), len(values),
                                 [None, pa.py_buffer(values)])
