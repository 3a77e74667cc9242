"""Linear filters along time: a moving-average (FIR) filter and a recursive (IIR) one, as the
discovery's noise models filter every residual and design column."""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dtbtrs

from gsfric._optional import optional


def fir(b: np.ndarray, x: np.ndarray, start: int = 0) -> np.ndarray:
    """``y[t] = sum_j b[j] x[t - j]`` along the first axis of x (N, ...), from rest, without
    its first ``start`` samples (the callers drop those whose window reaches before the record,
    ``start = len(b) - 1``): ``scipy.signal.lfilter`` with a denominator ``[1, 0, ..., 0]``.

    The zeros keep ``lfilter``'s recursion, which adds the taps oldest first; SciPy (1.17)
    convolves a filter without a denominator, adding them in another order. The two differ by
    rounding, which the discovery's fits can amplify (a parameter chosen on a grid of nearly
    equal sums of squares moved by 5 %), so the order is the one the discovery was tuned with.

    Examples
    --------
    >>> from gsfric.signal.filters import fir
    >>> import numpy as np
    >>> fir(np.array([1.0, -0.5]), np.arange(4.0), start=1)
    array([1. , 1.5, 2. ])
    """
    b = np.asarray(b, float)
    a = np.r_[1.0, np.zeros(len(b) - 1)]
    return optional("scipy.signal").lfilter(b, a, x, axis=0)[start:]


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


FIR_BYTES = 1 << 18
"""Bytes of output ``fir_channels`` computes at a time: each tap's pass over the samples then
reads and writes memory in the processor's cache (a pass over a whole block of a 40-column
design, a few megabytes, is bound by memory instead: about twice as slow)."""


def fir_channels(b: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Each channel filtered by its own taps, full windows only: ``y[t, c] = sum_j b[j, c]
    x[t + p - j, c]`` for t = 0 .. N - p - 1, p = len(b) - 1.

    Channel c of the result equals ``fir(b[:, c], x[:, c], start=p)`` to the last bit
    (the taps added in ``lfilter``'s order, oldest first; a channel with fewer taps is given
    zeros on its oldest ones, which add nothing), computed in one pass over every channel.

    Parameters
    ----------
    b : ndarray (p + 1, C)
        Taps of each channel, newest first (``b[0]`` multiplies the current sample).
    x : ndarray (N, C, ...)
        Signals along the first axis, channels along the second (N > p).

    Returns
    -------
    ndarray (N - p, C, ...)

    Examples
    --------
    >>> from gsfric.signal.filters import fir_channels
    >>> import numpy as np
    >>> fir_channels(np.array([[1.0, 1.0], [-0.5, 0.0]]), np.arange(8.0).reshape(4, 2))
    array([[2., 3.],
           [3., 5.],
           [4., 7.]])
    """
    b = np.asarray(b, float)
    x = np.asarray(x, float)
    p, n = len(b) - 1, x.shape[0]
    taps = b.reshape(b.shape + (1,) * (x.ndim - 2))
    y = np.empty((n - p,) + x.shape[1:])
    step = max(1, FIR_BYTES // (8 * max(1, x[0].size)))
    term = np.empty((min(step, n - p),) + x.shape[1:])
    for s in range(0, n - p, step):
        e = min(n - p, s + step)
        out, part = y[s:e], term[:e - s]
        np.multiply(x[s:e], taps[p], out=out)
        for j in range(p - 1, -1, -1):
            np.multiply(x[s + p - j:e + p - j], taps[j], out=part)
            out += part
    return y
