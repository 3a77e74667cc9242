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
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    n, half = len(t), window // 2
    starts = np.clip(np.arange(n) - half, 0, n - window)
    powers = np.arange(polyorder + 1)
    out = [np.empty_like(y) for _ in range(3)]
    for lo in range(0, n, BATCH):
        rows = np.arange(lo, min(n, lo + BATCH))
        index = starts[rows, None] + np.arange(window)                 # (B, w)
        stamps = t[index]
        scale = 0.5 * (stamps[:, -1] - stamps[:, 0])                   # (B,)
        x = (stamps - t[rows, None]) / scale[:, None]
        coefficients = np.linalg.pinv(x[..., None] ** powers) @ y[index]   # (B, p + 1, k)
        out[0][rows] = coefficients[:, 0]
        out[1][rows] = coefficients[:, 1] / scale[:, None]
        out[2][rows] = 2.0 * coefficients[:, 2] / scale[:, None] ** 2
    return out
