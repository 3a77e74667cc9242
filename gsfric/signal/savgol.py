"""Savitzky-Golay weights and filters: smoothing and derivatives of uniformly sampled signals."""

from __future__ import annotations

import functools

import numpy as np
from numpy.polynomial import legendre

from gsfric._optional import optional
from gsfric.errors import InputError

DEFAULT_POLYORDER = 4
"""Polynomial order of the Savitzky-Golay filter."""


@functools.lru_cache(maxsize=256)
def polynomial_fit(window: int, polyorder: int) -> np.ndarray:
    """The least-squares polynomial of order ``polyorder`` through a window's samples: the
    matrix (p + 1, window) that maps the samples to its coefficients in Legendre polynomials
    of the abscissa scaled to [-1, 1] (``polynomial_derivative`` evaluates them). Read-only.

    Legendre polynomials keep the least-squares problem well conditioned for any window:
    ``scipy.signal.savgol_coeffs`` fits powers of the sample index, and at order 6 its weights
    are wrong beyond about 300 samples (those of the value are all zero at 401).
    """

    fit = np.linalg.pinv(legendre.legvander(_abscissa(window)[0], polyorder))
    fit.flags.writeable = False
    return fit


@functools.lru_cache(maxsize=256)
def polynomial_derivative(window: int, polyorder: int, deriv: int) -> np.ndarray:
    """The matrix (window, p + 1) that maps the coefficients of ``polynomial_fit`` to the
    polynomial's ``deriv``-th derivative (unit sample step) at each sample of the window.
    Read-only."""

    x, half = _abscissa(window)
    derivative = np.stack([legendre.legval(x, legendre.legder(b, deriv))
                           for b in np.eye(polyorder + 1)], axis=1) / half ** deriv
    derivative.flags.writeable = False
    return derivative


def _abscissa(window: int) -> tuple[np.ndarray, int]:
    """The window's samples (window,) scaled to [-1, 1] about its centre, and the scale (half
    the window, samples, at least 1)."""
    half = max(window // 2, 1)
    return (np.arange(window) - window // 2) / half, half


@functools.lru_cache(maxsize=256)
def savgol_weights(window: int, polyorder: int, deriv: int = 0) -> np.ndarray:
    """Savitzky-Golay weights (window,), read-only: times the window's samples, the
    ``deriv``-th derivative (unit sample step) at its centre of the least-squares polynomial
    of order ``polyorder`` through them (``scipy.signal.savgol_coeffs(..., use="dot")``,
    computed as ``polynomial_fit``)."""
    weights = polynomial_derivative(window, polyorder, deriv)[window // 2] \
        @ polynomial_fit(window, polyorder)
    weights.flags.writeable = False
    return weights


def savgol_filter(y: np.ndarray, window: int, polyorder: int, deriv: int = 0) -> np.ndarray:
    """``scipy.signal.savgol_filter(y, window, polyorder, deriv, axis=0, mode="interp")``
    (unit sample step) with the well-conditioned fit of ``polynomial_fit``: the centred
    weights inside, the polynomial through the first and last ``window`` samples at the ends.

    Parameters
    ----------
    y : ndarray, shape (N, k)
        Uniformly sampled, N >= window.

    Returns
    -------
    ndarray, shape (N, k)
    """

    y = np.asarray(y, float)
    window, polyorder, deriv = int(window), int(polyorder), int(deriv)
    correlate1d = optional("scipy.ndimage").correlate1d
    out = correlate1d(y, savgol_weights(window, polyorder, deriv), axis=0, mode="constant")
    fill_ends(out, y, window, polyorder, deriv)
    return out


def fill_ends(out: np.ndarray, y: np.ndarray, window: int, polyorder: int,
              deriv: int = 0) -> None:
    """Write ``savgol_filter``'s first and last ``window // 2`` rows into ``out`` (the shape of
    y, (N, ...)): the ``deriv``-th derivative of the polynomial of order ``polyorder`` through
    the first and the last ``window`` samples of y."""
    derivative = polynomial_derivative(window, polyorder, deriv)
    fit = polynomial_fit(window, polyorder)
    half, n = window // 2, len(y)
    out[:half] = derivative[:half] @ (fit @ y[:window])
    out[n - half:] = derivative[half + 1:] @ (fit @ y[n - window:])


def savgol_derivatives(y: np.ndarray, window: int, polyorder: int, step: float) -> list[np.ndarray]:
    """The smoothed signal and its first two derivatives (``savgol_filter`` of orders 0, 1, 2
    divided by ``step**k``): three arrays of the shape of y (N, k), time step ``step``, s."""
    return [savgol_filter(y, window, polyorder, deriv=k) / step**k for k in (0, 1, 2)]


def savgol_gains(n: int, window: int, polyorder: int, deriv: int) -> np.ndarray:
    """The noise gain of ``savgol_filter``'s ``deriv``-th derivative at each of n samples (N,),
    per unit sample step: the norm of the weights that make it (centred inside, the end
    polynomials' at the first and last ``window // 2`` samples), so that white noise of
    standard deviation sigma becomes ``sigma * gain / step**deriv``."""
    window, polyorder, half = int(window), int(polyorder), int(window) // 2
    rows = np.linalg.norm(polynomial_derivative(window, polyorder, deriv)
                          @ polynomial_fit(window, polyorder), axis=1)      # (window,)
    gains = np.full(n, rows[half])
    ends = min(half, n)
    gains[:ends] = rows[:ends]
    gains[n - ends:] = rows[window - ends:]
    return gains


def savgol_core(y: np.ndarray, window: int, polyorder: int, step: float,
                lo: int, hi: int) -> list[np.ndarray]:
    """``savgol_derivatives`` at the rows lo..hi-1 of y (N, k) only, which need
    ``window // 2`` samples on each side: three contiguous arrays (hi - lo, k), equal to the
    last bit to ``savgol_derivatives(y, ...)[k][lo:hi]`` (the same ``correlate1d`` with the same
    weights, run on the rows it needs only)."""
    h = window // 2
    block = y[lo - h:hi + h]
    correlate1d = optional("scipy.ndimage").correlate1d
    out = []
    for k in (0, 1, 2):
        value = correlate1d(block, savgol_weights(window, polyorder, k), axis=0)[h:h + hi - lo]
        if k:
            value /= step ** k
        out.append(value)
    return out


def check_polyorder(polyorder: object, n: int, what: str = "samples") -> None:
    """Raise ``InputError`` unless ``polyorder`` is an integer >= 2 below ``n - 1``, n the
    ``what`` ("samples", or "steps of a chunk") that are filtered together."""
    if isinstance(polyorder, bool) or not isinstance(polyorder, (int, np.integer)) \
            or polyorder < 2:
        raise InputError(f"polyorder must be an integer >= 2, got {polyorder!r}")
    if polyorder + 1 >= n:
        raise InputError(f"polyorder = {polyorder} needs more than {polyorder + 1} {what}, "
                         f"got {n}")


def check_window(window: object, polyorder: int, n: int) -> None:
    """Raise ``InputError`` unless ``window`` is an odd integer with
    ``polyorder < window <= n`` (n: the samples it filters)."""
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)):
        raise InputError(f"window must be an odd integer, got {window!r}")
    if window % 2 == 0:
        raise InputError(f"window must be odd, got {window}")
    if window <= polyorder:
        raise InputError(f"window = {window} must exceed polyorder = {polyorder}")
    if window > n:
        raise InputError(f"window = {window} is longer than the {n} samples")
