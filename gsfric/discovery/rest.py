"""Rests and reversals: where the leg speed obtained from noisy poses does not say whether a leg
slides, and an independent estimate of the force noise.

Why: the leg speed comes from differentiating recorded poses. At rest the true speed is zero and
the estimate is the pose noise passed through the differentiator, sigma_v = sigma_D ||h||, with
sigma_D the noise of the leg length and h the Savitzky-Golay derivative filter used by
``Motion.from_samples``. A Coulomb-type friction evaluated as ``sgn(v)`` there flips with the
noise; physically, friction at rest (static friction) holds whatever force is needed, up to its
static level, and is not a function of the speed at all. So a (sample, leg) pair whose speed
lies within ``Settings.rest_band`` sigma_v of zero is treated as *not sliding*: its friction is
only bounded, and it carries no information about any friction law. So is every pair whose
differentiator window reaches into a rest (``sliding_mask``): there the differentiated speed is
biased by the stop. The workflow leaves those pairs out of every fit and statistic (they are
masked: residual and derivative columns set to zero, which is the least-squares solution of the
bound when the bound is not active). The model's own evaluation keeps its documented
regularisation of the sign (PRISMATIC_EPS).

The force noise comes from the force channels alone, without the model
(``gsfric.signal.noise.high_frequency_std``): the high-frequency part of each channel after
removing its smooth part with a local cubic fit (robust scale), corrected for the smoother.
It measures the white (innovation) part of the noise; strongly correlated noise has more power at low frequencies than this sees.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_closing, binary_opening, uniform_filter1d

from gsfric.evaluation.uncertainty import possibly_at_rest
from gsfric.signal.noise import white_noise_std
from gsfric.signal.rotations import (
    continuous_quaternions,
    quaternion_from_rotation,
    rotation_from_euler,
    rotation_from_quaternion,
)
from gsfric.signal.savgol import DEFAULT_POLYORDER, savgol_weights
from gsfric.signal.spline import smoothing_splines, spline_penalties
from gsfric.signal.windows import candidate_windows, filter_pairs, motion_filters


def differentiator(position: np.ndarray, rotation: np.ndarray, polyorder: int | None = None,
                   filters=None, *, move_to_noise: float) -> tuple[np.ndarray, np.ndarray]:
    """The velocity filters ``Motion.from_samples`` chooses at each sample for the recorded
    positions (N, 3) and orientations (N, 3, 3) (``trajectory.motion_filters``), or their
    gains and reaches from the ``filters`` it chose (``Motion.sample_filters``: the motion
    made from these poses), without choosing them again; a signal that does not move beyond
    ``move_to_noise`` times its noise (``moves``) reaches nowhere.

    Returns
    -------
    gain : ndarray, shape (N,)
        The larger (position or orientation) noise gain ``||h||`` of the first-derivative
        filter, per sample step: a white noise sigma becomes a velocity noise
        ``sigma gain / step``.
    reach : ndarray of int, shape (N,)
        Half the longer of the two windows, samples; of the position's alone when the
        orientation does not move (``moves``).
    """
    polyorder = DEFAULT_POLYORDER if polyorder is None else int(polyorder)
    signals = _pose_signals(position, rotation)
    if filters is None:
        filters = [motion_filters(signal, polyorder) for signal in signals]
    gains, reaches = [], []
    for chosen, signal in zip(filters, signals):
        orders, windows = chosen[0]
        gains.append(_noise_gain(orders, windows))
        reaches.append(windows // 2 if moves(signal, move_to_noise)
                       else np.zeros_like(windows))
    return np.maximum(*gains), np.maximum(*reaches)


def _pose_signals(position: np.ndarray, rotation: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The signals the motion's filters differentiate: positions (N, 3), m, and continuous
    unit quaternions (N, 4) of the rotations (N, 3, 3)."""
    return (np.asarray(position, float),
            continuous_quaternions(quaternion_from_rotation(np.asarray(rotation, float))))


def _noise_gain(orders: np.ndarray, windows: np.ndarray) -> np.ndarray:
    """The noise gain ``||h||`` (N,) of each sample's first-derivative Savitzky-Golay filter
    (polynomial order and window (N,) each), per sample step."""
    gain = np.empty(len(windows))
    for p, w in filter_pairs(orders, windows):
        rows = (orders == p) & (windows == w)
        gain[rows] = np.linalg.norm(savgol_weights(int(w), int(p), 1))
    return gain


def moves(signal: np.ndarray, ratio: float) -> bool:
    """Whether a recorded signal (N, k) moves beyond its noise: the range of a component
    exceeds ``ratio`` (``Settings.move_to_noise``) times its white noise
    (``gsfric.signal.noise.white_noise_std``).

    The reach of a differentiator matters where its window mixes a rest with a move; a channel
    that does not move mixes nothing, whatever window it was given. An orientation held fixed
    (translations only, a common test) gets the longest window there is, since nothing is to
    be resolved, and counting its reach would widen every rest by it: 0.3 s moves at 500 Hz
    with a fixed orientation were left without a sliding pair."""
    signal = np.asarray(signal, float)
    return bool(np.any(np.ptp(signal, axis=0) > ratio * white_noise_std(signal)
                       + 1e-12 * np.max(np.abs(signal), initial=1.0)))


def spline_differentiator(t: np.ndarray, position: np.ndarray, rotation: np.ndarray,
                          draws: int) -> tuple[np.ndarray, np.ndarray] | None:
    """``differentiator`` for a non-uniform time base, where ``Motion.from_samples`` fits
    smoothing splines: the velocity noise gain (N,), 1/s, of unit white noise through the same
    splines (same penalties; the larger of position and orientation; measured on
    ``draws`` draws (``Settings.spline_noise_draws``), averaged over 51 samples), and the reach
    (N,), the half window of the order-4 Savitzky-Golay filter of the same gain at the mean
    step. None when the spline's penalties are not available (short records)."""
    t = np.asarray(t, float)
    n = len(t)
    q = continuous_quaternions(quaternion_from_rotation(np.asarray(rotation, float)))
    rng = np.random.default_rng(0)
    gain = np.zeros(n)
    for signal in (np.asarray(position, float), q):
        penalties = spline_penalties(t, signal)
        if penalties is None:
            return None
        power = np.zeros(n)
        for _ in range(draws):
            noise = rng.standard_normal(signal.shape)
            power += np.mean(smoothing_splines(t, noise, penalties).derivative(1)(t) ** 2,
                             axis=1)
        gain = np.maximum(gain, np.sqrt(uniform_filter1d(power / draws, 51,
                                                         mode="nearest")))
    step = (t[-1] - t[0]) / (n - 1)
    windows = np.array(candidate_windows(n, DEFAULT_POLYORDER))
    gains = np.array([np.linalg.norm(savgol_weights(int(w), DEFAULT_POLYORDER, 1))
                      for w in windows]) / step                           # decreasing
    index = np.clip(np.searchsorted(-gains, -gain), 0, len(windows) - 1)
    return gain, windows[index] // 2


def speed_uncertainty(platform, t: np.ndarray, position: np.ndarray, rotation: np.ndarray,
                      window: int | None = None, polyorder: int | None = None,
                      gain: np.ndarray | None = None) -> np.ndarray:
    """Standard deviation of each leg's differentiated speed due to pose noise, m/s.

    ``sigma_D ||h|| / step``: sigma_D the white noise of the leg length computed from the
    recorded poses (``gsfric.signal.noise.white_noise_std``, the estimator the filter choice uses),
    h the Savitzky-Golay first-derivative filter of the sample.

    Parameters
    ----------
    platform : Platform
    t : ndarray, shape (N,)
        Sample times, s (uniform).
    position : ndarray, shape (N, 3)
        Recorded (unsmoothed) positions, m.
    rotation : ndarray, shape (N, 3, 3)
        Recorded (unsmoothed) orientations.
    window, polyorder : int, optional
        One fixed differentiator for every sample (``Motion.from_samples(window=...)``).
    gain : ndarray, shape (N,), optional
        The per-sample gain of ``differentiator`` (computed when neither it nor ``window`` is
        given: of the filters ``Motion.from_samples`` chooses).

    Returns
    -------
    ndarray, shape (N, 6)
        Per sample and leg; (6,) with a fixed ``window``.
    """
    polyorder = DEFAULT_POLYORDER if polyorder is None else int(polyorder)
    D = platform.leg_lengths(np.asarray(position, float), np.asarray(rotation, float))
    sigma_D = white_noise_std(D)
    step = float(np.mean(np.diff(t)))
    if window is not None:
        return sigma_D * float(np.linalg.norm(savgol_weights(int(window), polyorder, 1))) / step
    if gain is None:
        gain = np.maximum(*(_noise_gain(*motion_filters(signal, polyorder)[0])
                            for signal in _pose_signals(position, rotation)))
    return np.asarray(gain, float)[:, None] * sigma_D[None, :] / step


def move_reach(reach: np.ndarray, moving: np.ndarray) -> int:
    """The differentiator's reach where the legs move: the median of ``reach`` (N,), samples,
    over the samples where ``moving`` (N,) is True (over all when none is).

    The reach that matters at a rest's ends is that of the windows of the moves next to it.
    A rest's own windows are long (nothing to bias them: up to ``MAX_AUTO_WINDOW`` samples),
    and the median over a record that mostly rests would be theirs: at 200 Hz a run of 455
    samples, which closed the gaps between moves of 0.7 s and took them for rests."""
    reach = np.asarray(reach, int)
    chosen = reach[np.asarray(moving, bool)]
    return int(np.median(chosen if len(chosen) else reach))


def sliding_mask(speed: np.ndarray, sigma_v: np.ndarray, floor: float,
                 reach: int | np.ndarray = 0, *, rest_band: float) -> np.ndarray:
    """(N, 6) True where a leg is known to slide.

    A pair (sample, leg) slides where ``|speed|`` exceeds ``rest_band`` sigma_v (and
    ``floor``; ``gsfric.evaluation.uncertainty.possibly_at_rest``, the rule ``simulate``'s
    ``rest`` column follows) and, with ``reach`` > 0, no rest lies within ``reach`` samples: no sample whose
    differentiator window reaches into a rest. A rest is a run of at least ``reach`` samples
    inside the band, with excursions out of the band shorter than ``reach`` samples (the
    differentiated noise is correlated over the window: such an excursion is one noise event,
    or the pull of the next move on the window, not a move). With a reach per sample (the
    differentiator's window varies along the record), each sample looks as far as its own
    window reaches, and a rest is a run at least as long as the median reach of the samples
    outside the band (``move_reach``).

    Why: the differentiator (a local polynomial fit over ``2 reach + 1`` samples) is unbiased
    where the motion is a polynomial over its window, as at a smooth reversal, whose passage
    through the band is short; at a rest's start and end the motion stops (a jump of the
    acceleration or jerk), the window mixes the rest with the move, and the estimate's bias,
    a fraction of the move's speed half a window away, is not covered by the noise band. A
    speed with the wrong sign there makes a Coulomb-type friction flip by twice its level.

    Parameters
    ----------
    speed : ndarray, shape (N, 6)
        Differentiated leg speeds, m/s.
    sigma_v : ndarray, shape (6,) or (N, 6)
        Their standard deviation due to pose noise, m/s.
    floor : float
        Smallest half-width of the band, m/s.
    reach : int or ndarray of int, shape (N,)
        Half-width of the differentiator's window, samples (0: no rest widening).
    rest_band : float
        Half-width of the band, in standard deviations of the speed estimate
        (``Settings.rest_band``).
    """
    speed = np.asarray(speed, float)
    inside = possibly_at_rest(speed, np.maximum(np.asarray(sigma_v, float), floor / rest_band),
                              rest_band)
    reach = np.asarray(reach, int)
    if not reach.any():
        return ~inside
    n = len(speed)
    reach = np.broadcast_to(reach, (n,))
    run = max(move_reach(reach, ~inside.all(axis=1)), 1)
    structure = np.ones((run, 1), bool)
    # a rest: in the band for at least `run` samples, excursions shorter than `run`
    # (one correlated noise event of the differentiator) included
    rests = binary_opening(binary_closing(inside, structure=structure), structure=structure)
    i = np.arange(n)
    counts = np.concatenate([np.zeros((1, speed.shape[1]), int),
                             np.cumsum(rests, axis=0)])
    lo, hi = np.clip(i - reach, 0, n), np.clip(i + reach + 1, 0, n)
    near = (counts[hi] - counts[lo]) > 0
    return ~(inside | near)


def poses_from_columns(columns) -> tuple[np.ndarray, np.ndarray]:
    """Recorded positions (N, 3) and rotations (N, 3, 3) from trajectory columns (a mapping or
    DataFrame with ``x, y, z`` and ``qw, qx, qy, qz`` or ``alpha, beta, gamma``)."""
    position = np.stack([np.asarray(columns[k], float) for k in ("x", "y", "z")], axis=1)
    if "qw" in columns:
        q = np.stack([np.asarray(columns[k], float) for k in ("qw", "qx", "qy", "qz")], axis=1)
        rotation = rotation_from_quaternion(q / np.linalg.norm(q, axis=1, keepdims=True))
    else:
        rotation = rotation_from_euler(*(np.asarray(columns[k], float)
                                         for k in ("alpha", "beta", "gamma")))
    return position, rotation
