"""White-noise level of sampled signals, from high-order differences (uniform or not)."""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.special import comb

NOISE_DIFFERENCE_ORDER = 6
"""Order of the differences from which ``white_noise_std`` estimates the noise of a sampled
signal."""


def robust_std(e: np.ndarray) -> np.ndarray:
    """Standard deviation of each column of e (N, k) from its median absolute deviation
    (1.4826 MAD: the standard deviation for Gaussian samples, unmoved by a few outliers)."""
    med = np.median(e, axis=0)
    return 1.4826 * np.median(np.abs(e - med), axis=0)


def white_noise_std(y: np.ndarray) -> np.ndarray:
    """Standard deviation of white noise on each column of a uniformly sampled signal.

    From differences of order m = ``NOISE_DIFFERENCE_ORDER`` (6): for white noise of standard
    deviation sigma their variance is ``C(2m, m) sigma^2`` (924 sigma^2), while a smooth
    signal contributes ``y^(m) step^m``, negligible where the sampling resolves the motion
    (1e-9 m for a 0.03 m sine of 2 Hz sampled at 200 Hz). The scale is robust (median
    absolute deviation), so that the few samples where a move starts or stops (a jump of the
    jerk) do not count. Only the differences whose readings change count: a rest logged at a
    finite resolution (positions in mm with four decimals) reads the very same value, says
    nothing of the noise in the moves, and would make it zero when the rests fill more than
    half of the record.

    Parameters
    ----------
    y : ndarray, shape (N, k)

    Returns
    -------
    ndarray, shape (k,)
        In the unit of y; zeros when N <= ``NOISE_DIFFERENCE_ORDER``.
    """

    y = np.asarray(y, float)
    m = NOISE_DIFFERENCE_ORDER
    if len(y) <= m:
        return np.zeros(y.shape[1:])
    differences = np.diff(y, n=m, axis=0)
    changing = np.ptp(sliding_window_view(y, m + 1, axis=0), axis=-1) > 0.0
    return np.array([robust_std(d[c]) if c.any() else 0.0
                     for d, c in zip(differences.T, changing.T)]) / np.sqrt(comb(2 * m, m))


def divided_difference_coefficients(x: np.ndarray, width: int) -> np.ndarray:
    """1 / prod_{k != i} (x_i - x_k) over every window of ``width`` consecutive samples."""

    windows = sliding_window_view(x, width)
    diffs = windows[:, :, None] - windows[:, None, :]
    diffs[:, np.arange(width), np.arange(width)] = 1.0
    return 1.0 / diffs.prod(axis=2)


def divided_noise_std(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """White-noise standard deviation of each column of y (N, k) at the non-uniform times t
    (N,), from the 6th divided differences (noise variance ``sigma^2 sum w^2``, w their
    weights; the motion's part ``y^(6) / 6!`` does not grow with a jitter of the times);
    robust scale (median of the normalised squares), over the windows whose readings change."""

    m = NOISE_DIFFERENCE_ORDER
    scale = (t[-1] - t[0]) / (len(t) - 1)
    w = divided_difference_coefficients((t - t[0]) / scale, m + 1)
    windows = sliding_window_view(y, m + 1, axis=0)                     # (N - m, k, m + 1)
    d = np.einsum("nkj,nj->nk", windows, w)
    z2 = d ** 2 / np.sum(w ** 2, axis=1)[:, None]
    # readings that do not change over a window (a rest logged at a finite resolution) carry
    # no noise that the motion would see: the noise is that of the windows that change
    changing = np.ptp(windows, axis=2) > 0.0
    out = np.zeros(y.shape[1])
    for j in range(y.shape[1]):
        changed = z2[:, j][changing[:, j]]
        if len(changed):
            out[j] = np.sqrt(np.median(changed) / 0.454936)     # median of chi-square(1)
    return out
