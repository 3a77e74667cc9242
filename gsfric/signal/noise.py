"""White-noise level of sampled signals, from high-order differences (uniform or not); the load
cells' noise as a user gives it (``ForceNoise``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from gsfric._checks import is_number, short
from gsfric._optional import optional
from gsfric.errors import InputError, InputTypeError
from gsfric.signal.savgol import savgol_filter, savgol_weights

PLAUSIBLE_SPREAD = (1e-9, 10.0)
"""A given force noise must lie within these multiples of each measured force channel's
standard deviation (``ForceNoise.check_plausible``): a channel's spread holds its noise, so a
noise ten times larger is a unit error (kN given as N, a wrong channel); a billionth of it no
load cell's converter resolves (24 bits are 6e-8)."""

HIGH_FREQUENCY_WINDOW = 15
"""Window (samples) of the local cubic fit whose residual measures a force channel's noise
(``high_frequency_std``): long enough for a robust scale, short beside the moves."""

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
    changing = changing_windows(y, m + 1)
    return np.array([robust_std(d[c]) if c.any() else 0.0
                     for d, c in zip(differences.T, changing.T)]) / np.sqrt(math.comb(2 * m, m))


def changing_windows(y: np.ndarray, width: int) -> np.ndarray:
    """(N - width + 1, k): whether the readings of each column of y (N, k) change over each
    window of ``width`` consecutive samples (some consecutive pair differs; the windows of
    ``sliding_window_view`` whose range is not 0), in one pass."""
    changes = np.cumsum(np.diff(y, axis=0) != 0.0, axis=0)
    changes = np.concatenate([np.zeros((1,) + changes.shape[1:], changes.dtype), changes])
    return changes[width - 1:] - changes[:len(changes) - width + 1] > 0


def divided_difference_coefficients(x: np.ndarray, width: int) -> np.ndarray:
    """1 / prod_{k != i} (x_i - x_k) over every window of ``width`` consecutive samples."""

    windows = sliding_window_view(x, width)
    diffs = windows[:, :, None] - windows[:, None, :]
    diffs[:, np.arange(width), np.arange(width)] = 1.0
    return 1.0 / diffs.prod(axis=2)


CHI2_1_MEDIAN = 0.454936
"""Median of the chi-square distribution of one degree of freedom: the median of the
normalised squared divided differences of white noise of unit variance."""


def _divided_squares(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The squared 6th divided differences of each column of y (N, k) at the times t (N,),
    each divided by its noise variance per unit sigma^2 (``sum w^2``, w the weights):
    (N - m, k); and the windows of ``m + 1`` samples they come from, (N - m, k, m + 1)."""
    m = NOISE_DIFFERENCE_ORDER
    scale = (t[-1] - t[0]) / (len(t) - 1)
    w = divided_difference_coefficients((t - t[0]) / scale, m + 1)      # (N - m, m + 1)
    windows = sliding_window_view(y, m + 1, axis=0)                     # (N - m, k, m + 1)
    d = np.einsum("nkj,nj->nk", windows, w)
    return d ** 2 / np.sum(w ** 2, axis=1)[:, None], windows


def divided_noise_std(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """White-noise standard deviation of each column of y (N, k) at the non-uniform times t
    (N,), from the 6th divided differences (noise variance ``sigma^2 sum w^2``, w their
    weights; the motion's part ``y^(6) / 6!`` does not grow with a jitter of the times);
    robust scale (median of the normalised squares), over the windows whose readings change
    (as ``white_noise_std``: the noise a smoother of recorded poses must remove; see
    ``divided_noise_std_every_window`` for the estimate over every window)."""

    z2, _ = _divided_squares(t, y)
    # readings that do not change over a window (a rest logged at a finite resolution) carry
    # no noise that the motion would see: the noise is that of the windows that change
    changing = changing_windows(y, NOISE_DIFFERENCE_ORDER + 1)
    out = np.zeros(y.shape[1])
    for j in range(y.shape[1]):
        changed = z2[:, j][changing[:, j]]
        if len(changed):
            out[j] = np.sqrt(np.median(changed) / CHI2_1_MEDIAN)
    return out


def divided_noise_std_every_window(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``divided_noise_std`` over every window, those whose readings do not change included:
    the noise of a signal computed from noisy recordings (the leg lengths of recorded poses),
    whose windows never repeat a value exactly; zeros when N <= ``NOISE_DIFFERENCE_ORDER``.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Sample times, s (non-uniform: differences on a jittered time base would count the
        motion times the jitter as noise; divided differences do not).
    y : ndarray, shape (N, k)

    Returns
    -------
    ndarray, shape (k,)
        In the unit of y.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    if len(t) <= NOISE_DIFFERENCE_ORDER:
        return np.zeros(y.shape[1])
    z2, _ = _divided_squares(t, y)
    return np.sqrt(np.median(z2, axis=0) / CHI2_1_MEDIAN)


def high_frequency_std(y: np.ndarray, window: int) -> np.ndarray:
    """Standard deviation of white noise in each column of y (N, k), from the residual of a
    local cubic fit (corrected by ``1 - h0``, h0 the fit's centre weight).

    Parameters
    ----------
    y : ndarray, shape (N, k)
    window : int
        Samples of the local fit (odd; shortened to the record).

    Returns
    -------
    ndarray, shape (k,)
    """
    y = np.asarray(y, float)
    window = int(min(window, len(y) - (1 - len(y) % 2)))
    if window < 5:
        return np.zeros(y.shape[1])
    smooth = savgol_filter(y, window, 3)
    h0 = savgol_weights(window, 3)[window // 2]
    core = slice(window, len(y) - window) if len(y) > 3 * window else slice(None)
    return robust_std((y - smooth)[core]) / np.sqrt(1.0 - h0)



EXPONENTIAL_MEDIAN = math.log(2.0)
"""Median of the exponential distribution of unit mean: the median of a white noise's
periodogram ordinates (away from 0 and the Nyquist frequency) over their mean."""


def spectral_noise_std(y: np.ndarray, step: float, low: float, segment: int = 32
                       ) -> np.ndarray:
    """Standard deviation of white noise in each column of y (N, k), from the median level of
    its spectrum above the frequency ``low`` (Hz), robust in time and in frequency.

    The record is cut into segments of ``segment`` samples, each detrended (a line) and
    tapered (Hann); at each frequency, the median of the segments' periodogram ordinates
    over ``ln 2`` is the level (a white noise of standard deviation sigma has ordinates of
    mean ``2 sigma^2 step``, exponentially distributed): what happens in fewer than half
    of the segments (a friction step at a reversal, a jump) does not count. Of the levels
    above ``low`` the lower quartile is taken: what occupies up to three quarters of the
    frequencies (narrowband lines, each widened by the taper to three or four of the
    segment's frequencies; the harmonics of the motion) does not count either (each level is
    a median over the record's segments, nearly constant over the frequencies for white
    noise, so that its quartile is within a few percent of its median). A noise that is not
    white reads at its level above ``low``.

    Parameters
    ----------
    y : ndarray, shape (N, k)
    step : float
        Sample step, s.
    low : float
        Lowest frequency counted, Hz.
    segment : int
        Samples per segment (even).

    Returns
    -------
    ndarray, shape (k,)
        In the unit of y; zeros when the record holds fewer than 3 segments or no frequency
        of a segment lies above ``low``.
    """
    y = np.asarray(y, float)
    n, segment = len(y), int(segment)
    if n // segment < 3:
        return np.zeros(y.shape[1:])
    # Welch's segments (scipy.signal.spectrogram: each segment's own periodogram), one-sided
    # density 2 |X|^2 step / sum(taper^2) between 0 and the Nyquist frequency; their median
    # here, not welch's mean or its median over SciPy's small-sample bias
    freqs, _, density = optional("scipy.signal").spectrogram(
        y, 1.0 / step, np.hanning(segment + 2)[1:-1], segment, 0, detrend="linear", axis=0)
    above = (freqs > low) & (freqs < freqs[-1])
    if not above.any():
        return np.zeros(y.shape[1:])
    level = np.median(density[above], axis=-1) / (2 * step) / EXPONENTIAL_MEDIAN
    return np.sqrt(np.quantile(level, 0.25, axis=0))


@dataclass
class ForceNoise:
    """The load cells' noise as the user gives it.

    Attributes
    ----------
    std : tuple of float
        Standard deviation per leg (6), N.
    source : str
        ``specified`` or ``noise record``.
    detail : str
        Where it comes from (the option, the file).
    motion : (float, float) or None
        A noise record's poses: the largest travel of the platform frame's origin from its
        first sample, m, and the largest turn, rad; None without poses.
    """

    std: tuple[float, ...]
    source: str
    detail: str = ""
    motion: tuple[float, float] | None = None

    @classmethod
    def specified(cls, values: float | Sequence[float], detail: str = "--force-noise"
                  ) -> ForceNoise:
        """A sensor specification: one value for the six legs or six, each finite and > 0;
        ``InputTypeError`` for what is not a number (text, a bool, None)."""
        if not all(is_number(v) for v in np.ravel(np.asarray(values, dtype=object))):
            raise InputTypeError(f"{detail}: expected a number (N) or six, got {short(values)}")
        values = np.atleast_1d(np.asarray(values, dtype=float)).ravel()
        if values.size not in (1, 6):
            raise InputError(f"{detail}: give one value or six (one per leg), got "
                             f"{values.size}")
        bad = np.flatnonzero(~np.isfinite(values) | (values <= 0))
        if bad.size:
            raise InputError(f"{detail}: the force noise must be a finite number > 0 N, got "
                             f"{values[bad[0]]:g}")
        return cls(tuple(float(v) for v in np.broadcast_to(values, (6,))), "specified", detail)

    @classmethod
    def from_record(cls, forces: np.ndarray, detail: str) -> ForceNoise:
        """A recording at rest: each force channel (N, 6) less its mean."""
        forces = np.asarray(forces, float)
        if len(forces) < 20:
            raise InputError(f"{detail}: a noise record needs at least 20 samples, got "
                             f"{len(forces)}")
        std = forces.std(axis=0, ddof=1)
        if not np.all(std > 0):
            leg = int(np.flatnonzero(~(std > 0))[0]) + 1
            raise InputError(f"{detail}: F{leg} does not change over the record: no noise to "
                             "measure")
        return cls(tuple(float(v) for v in std), "noise record", detail)

    def check_at_rest(self, travel: float, turn: float) -> None:
        """``InputError`` when the record's poses (``motion``) travel more than ``travel`` m
        or turn more than ``turn`` rad (``Settings.record_travel``, ``record_turn``)."""
        if self.motion is None:
            return
        moved, turned = self.motion
        if moved > travel or turned > turn:
            raise InputError(f"{self.detail}: not at rest: the platform moves {moved:.3g} m "
                             f"and turns {turned:.3g} rad from its first sample (a noise "
                             f"record must stay within {travel:g} m and {turn:g} rad); record "
                             "the load cells with the platform still")

    def check_plausible(self, forces: np.ndarray, limits: tuple[float, float]) -> None:
        """``InputError`` when a leg's noise lies outside ``limits`` (``PLAUSIBLE_SPREAD``,
        discovery's ``Settings.noise_spread``) times the standard deviation of its measured
        channel ``forces`` (N, 6), N."""
        spread = np.asarray(forces, float).std(axis=0)
        std = np.asarray(self.std)
        for leg in np.flatnonzero((spread > 0) & ((std > limits[1] * spread)
                                                  | (std < limits[0] * spread))):
            raise InputError(f"{self.detail}: F{leg + 1}: a force noise of {std[leg]:.3g} N is "
                             f"implausible against the measured channel's spread "
                             f"{spread[leg]:.3g} N (standard deviation); the noise must lie "
                             f"within {limits[0]:g} to {limits[1]:g} times it (is it in N?)")
