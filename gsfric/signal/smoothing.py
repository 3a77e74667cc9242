"""A sampled signal smoothed and differentiated twice by the method its time base calls for,
with the noise of its derivatives.

The time base. Stamps that jitter are either the true sampling instants (the smoother must use
them) or a clock read with an error at samples taken evenly (the smoother must not). Which one
a record is shows in its poses: the white noise of its 6th differences is measured twice, on
the even grid (``white_noise_std``) and on the stamps themselves (``divided_noise_std``). On the
wrong time base the motion times the stamp error adds to the noise (``|y'| * dt``); on the right
one only the pose noise remains. The even grid is used unless the noise seen on it exceeds
``EVEN_NOISE_RATIO`` times (in variance) the noise seen on the stamps (``evenly_spaced``).

The noise of the derivatives. Every smoother here is linear in the samples: white noise of
standard deviation sigma on a signal becomes ``sigma * gain`` on its k-th derivative, the gain
being the norm of the weights that make it (exact for the Savitzky-Golay and local polynomial
filters, measured on unit white noise for the smoothing spline). sigma is the white noise of
the signal on the time base used, so that on the even grid it includes the stamps' jitter
(``|y'| * dt``) as the smoother sees it. Correlated errors (a drift, a bias of the smoother at a
sudden stop) are not included.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsfric.errors import InputError
from gsfric.signal.local import local_polynomial_derivatives, local_polynomial_gains
from gsfric.signal.noise import divided_noise_std, white_noise_std
from gsfric.signal.savgol import check_window, savgol_derivatives, savgol_gains
from gsfric.signal.spline import spline_fit, spline_noise_gains
from gsfric.signal.windows import adaptive_gains, motion_filters, savgol_adaptive

EVEN_NOISE_RATIO = 2.0
"""Jittered stamps are taken as evenly spaced while the white-noise variance of the signals on
the even grid is at most this times their variance on the stamps: treating them as even then
at most doubles the noise the smoother removes (and the noise reported with the derivatives
says so), while the even grid keeps the per-sample Savitzky-Golay filters. Beyond, the stamps
are the sampling instants and the fits use them."""

EXACT_RTOL = 1e-9
"""Stamps within this fraction of the mean step are evenly spaced without a test."""


def evenly_spaced(t: np.ndarray, *signals: np.ndarray) -> bool:
    """Whether the signals (N, k) each sampled at the times t (N,), s, are differentiated on
    the even grid of the mean step (see the module's docstring and ``EVEN_NOISE_RATIO``)."""
    t = np.asarray(t, float)
    steps = np.diff(t)
    mean_step = (t[-1] - t[0]) / (len(t) - 1)
    if np.all(np.abs(steps - mean_step) <= EXACT_RTOL * mean_step):
        return True
    for y in signals:
        on_grid = float(np.sum(white_noise_std(y) ** 2))
        on_stamps = float(np.sum(divided_noise_std(t, y) ** 2))
        if on_grid > EVEN_NOISE_RATIO * on_stamps:
            return False
    return True


@dataclass(frozen=True)
class Smoothed:
    """A signal (N, k) smoothed and differentiated twice (``smooth``).

    Attributes
    ----------
    value, first, second : ndarray, shape (N, k)
        The smoothed signal and its first and second time derivatives (per s, per s^2).
    gains : tuple of two ndarray (N,), or None
        The noise gains of the first and second derivative, 1/s and 1/s^2; None where they are
        not known (a smoothing spline of at most ``SPLINE_GCV_ROWS`` samples, whose penalties
        SciPy chooses per column).
    noise : ndarray, shape (k,)
        White-noise standard deviation of the signal on the time base used, its unit.
    filters : per-sample filters (``motion_filters``) or None
        Those chosen on the even grid without a window.
    """

    value: np.ndarray
    first: np.ndarray
    second: np.ndarray
    gains: tuple[np.ndarray, np.ndarray] | None
    noise: np.ndarray
    filters: object = None

    def sigma(self) -> tuple[np.ndarray, np.ndarray] | None:
        """One standard deviation of the first and second derivative, (N, k) each, from the
        white noise alone (independent samples); None when the gains are not known."""
        if self.gains is None:
            return None
        return (self.gains[0][:, None] * self.noise[None, :],
                self.gains[1][:, None] * self.noise[None, :])


def smooth(t: np.ndarray, y: np.ndarray, even: bool, window: int | None, polyorder: int,
           lam: float | None = None) -> Smoothed:
    """The signal y (N, k) at the times t (N,) smoothed and differentiated twice.

    * ``even`` (``evenly_spaced``): a Savitzky-Golay filter at the mean step, of ``window``
      samples, or, with ``window=None``, the filter of least estimated error chosen per sample
      (``motion_filters``);
    * uneven stamps with a ``window``: the polynomial of that window fitted on the stamps
      (``local_polynomial_derivatives``);
    * uneven stamps without a window: a cubic smoothing spline of penalty ``lam``, chosen from
      the data when None (``spline_fit``).
    """
    n = len(t)
    if even:
        step = (t[-1] - t[0]) / (n - 1)
        noise = white_noise_std(y)
        if window is None:
            filters = motion_filters(y, polyorder)
            g1, g2 = adaptive_gains(filters, n)
            return Smoothed(*savgol_adaptive(y, filters, step), (g1 / step, g2 / step ** 2),
                            noise, filters)
        check_window(window, polyorder, n)
        gains = (savgol_gains(n, window, polyorder, 1) / step,
                 savgol_gains(n, window, polyorder, 2) / step ** 2)
        return Smoothed(*savgol_derivatives(y, window, polyorder, step), gains, noise)
    noise = divided_noise_std(t, y)
    if window is not None:
        check_window(window, polyorder, n)
        return Smoothed(*local_polynomial_derivatives(t, y, window, polyorder),
                        local_polynomial_gains(t, window, polyorder), noise)
    try:
        derivatives, penalties = spline_fit(t, y, lam)
    except ValueError as error:
        raise InputError(f"smoothing spline failed: {error}") from None
    gains = None if penalties is None else spline_noise_gains(t, penalties[0])
    return Smoothed(*derivatives, gains, noise)
