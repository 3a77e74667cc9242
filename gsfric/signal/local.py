"""Local polynomial fits on any time base: the Savitzky-Golay filter of a window of samples
for time stamps that are not evenly spaced."""

from __future__ import annotations

import numpy as np

BATCH = 4096
"""Samples whose windows are fitted at a time (memory: BATCH x window x (polyorder + 1))."""


def local_polynomial_derivatives(t: np.ndarray, y: np.ndarray, window: int,
                                 polyorder: int) -> list[np.ndarray]:
    """The smoothed signal and its first two time derivatives at every sample, each from the
    least-squares polynomial of order ``polyorder`` through ``window`` samples on their own
    time stamps: centred on the sample, or the first or last ``window`` samples near the ends
    (as ``savgol_filter``'s ``mode="interp"``). On evenly spaced stamps this is the
    Savitzky-Golay filter of that window.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Increasing times, s.
    y : ndarray, shape (N, k)
    window : int
        Odd, ``polyorder < window <= N``.
    polyorder : int

    Returns
    -------
    list of three ndarray, shape (N, k)
        Value, first and second derivative (per s and per s^2).
    """
    y = np.asarray(y, float)
    out = [np.empty_like(y) for _ in range(3)]
    for rows, index, fit, scale in _local_fits(t, window, polyorder):
        coefficients = fit @ y[index]                                  # (B, p + 1, k)
        out[0][rows] = coefficients[:, 0]
        out[1][rows] = coefficients[:, 1] / scale[:, None]
        out[2][rows] = 2.0 * coefficients[:, 2] / scale[:, None] ** 2
    return out


def local_polynomial_gains(t: np.ndarray, window: int, polyorder: int
                           ) -> tuple[np.ndarray, np.ndarray]:
    """The noise gains of ``local_polynomial_derivatives``' first and second derivatives at
    every sample, (N,) each, 1/s and 1/s^2: the norm of the weights that make each derivative
    from the window's samples, so that white noise of standard deviation sigma on y becomes
    ``sigma * gain`` on the derivative."""
    n = len(t)
    gains = np.empty(n), np.empty(n)
    for rows, _, fit, scale in _local_fits(t, window, polyorder):
        gains[0][rows] = np.linalg.norm(fit[:, 1], axis=1) / scale
        gains[1][rows] = 2.0 * np.linalg.norm(fit[:, 2], axis=1) / scale ** 2
    return gains


def _local_fits(t: np.ndarray, window: int, polyorder: int):
    """The least-squares fits of ``local_polynomial_derivatives``, BATCH samples at a time:
    (rows (B,), the window's sample indices (B, w), the matrices (B, p + 1, w) that map the
    window's samples to the coefficients of the powers of (t - t_row) / scale, scale (B,))."""
    t = np.asarray(t, float)
    n, half = len(t), window // 2
    starts = np.clip(np.arange(n) - half, 0, n - window)
    powers = np.arange(polyorder + 1)
    for lo in range(0, n, BATCH):
        rows = np.arange(lo, min(n, lo + BATCH))
        index = starts[rows, None] + np.arange(window)                 # (B, w)
        stamps = t[index]
        scale = 0.5 * (stamps[:, -1] - stamps[:, 0])                   # (B,)
        x = (stamps - t[rows, None]) / scale[:, None]
        yield rows, index, np.linalg.pinv(x[..., None] ** powers), scale
