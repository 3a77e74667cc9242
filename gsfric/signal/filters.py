"""Linear filters along time: a moving-average (FIR) filter and a recursive (IIR) one.

The discovery's noise models filter every residual and design column; these are the two
filters it needs, on NumPy and ``scipy.linalg`` alone (``scipy.signal`` takes half a second to
import, which a short ``gsfric discover`` would spend on it).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dtbtrs


def fir(b: np.ndarray, x: np.ndarray, start: int = 0) -> np.ndarray:
    """``scipy.signal.lfilter(b, [1.0], x, axis=0)[start:]``, bit for bit, for
    ``start >= len(b) - 1`` (every output sample sees a whole window of input).

    Parameters
    ----------
    b : ndarray (q + 1,)
        Taps: ``y[t] = sum_j b[j] x[t - j]``.
    x : ndarray (N, ...)
        Filtered along the first axis.
    start : int
        First output sample, at least ``q``.

    Returns
    -------
    ndarray (N - start, ...)
        Summed in the order of ``lfilter``'s transposed direct form (the oldest tap first),
        so both give the same bits.

    Examples
    --------
    >>> from gsfric.signal.filters import fir
    >>> import numpy as np
    >>> fir(np.array([1.0, -0.5]), np.arange(4.0), start=1)
    array([1. , 1.5, 2. ])
    """
    b = np.asarray(b, float)
    q, n = len(b) - 1, x.shape[0]
    if start < q:
        raise ValueError(f"fir: start {start} is before the first whole window ({q})")
    acc = b[q] * x[start - q:n - q]
    for j in range(q - 1, -1, -1):
        acc = acc + b[j] * x[start - j:n - j]
    return acc


def all_pole(a: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The recursion ``sum_k a[k] y[t - k] = u[t]`` from rest, solved as a banded lower
    triangular system (LAPACK ``dtbtrs``): ``scipy.signal.lfilter([1.0], a, u, axis=0)`` to
    rounding.

    Parameters
    ----------
    a : ndarray (p + 1,)
        Denominator, ``a[0] != 0``.
    u : ndarray (N,) or (N, m)
        Each column filtered along time.

    Returns
    -------
    ndarray, the shape of ``u``

    Examples
    --------
    >>> from gsfric.signal.filters import all_pole
    >>> import numpy as np
    >>> all_pole(np.array([1.0, -0.5]), np.array([1.0, 0.0, 0.0]))
    array([1.  , 0.5 , 0.25])
    """
    a, u = np.asarray(a, float), np.asarray(u, float)
    n, p = u.shape[0], len(a) - 1
    if p == 0:
        return u / a[0]
    # band storage of the lower triangular Toeplitz matrix: row k holds a[k] on the k-th
    # subdiagonal
    band = np.zeros((p + 1, n))
    for k in range(p + 1):
        band[k, :n - k] = a[k]
    y, info = dtbtrs(band, u.reshape(n, -1), uplo="L")
    if info != 0:
        raise ValueError(f"all_pole: the recursion is singular (LAPACK info {info})")
    return y.reshape(u.shape)
