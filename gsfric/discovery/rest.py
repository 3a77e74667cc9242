"""Rests and reversals: where the leg speed obtained from noisy poses does not say whether a leg
slides, and an independent estimate of the force noise.

Why: the leg speed comes from differentiating recorded poses. At rest the true speed is zero and
the estimate is the pose noise passed through the differentiator, sigma_v = sigma_D ||h||, with
sigma_D the noise of the leg length and h the Savitzky-Golay derivative filter used by
``Motion.from_samples``. A Coulomb-type friction evaluated as ``sgn(v)`` there flips with the
noise; physically, friction at rest (static friction) holds whatever force is needed, up to its
static level, and is not a function of the speed at all. So a (sample, leg) pair whose speed
lies within ``REST_BAND`` sigma_v of zero is treated as *not sliding*: its friction is only
bounded, and it carries no information about any friction law. So is every pair whose
differentiator window reaches into a rest (``sliding_mask``): there the differentiated speed
is biased by the stop. The workflow leaves those pairs out of every fit and statistic (they
are masked: residual and derivative columns set to zero, which is the least-squares solution
of the bound when the bound is not active).
The model's own evaluation keeps its documented regularisation of the sign (PRISMATIC_EPS).

``force_noise`` estimates the force noise from the force channels alone, without the model:
the high-frequency part of each channel after removing its smooth part with a local cubic fit
(robust scale), corrected for the smoother. It measures the white (innovation) part of the
noise; strongly correlated noise has more power at low frequencies than this sees.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import savgol_coeffs, savgol_filter

REST_BAND = 5.0
"""Half-width of the not-sliding band, in standard deviations of the speed estimate."""

NOISE_WINDOW = 15
"""Window (samples) of the local cubic fit whose residual measures the noise."""


def _robust_std(e: np.ndarray) -> np.ndarray:
    med = np.median(e, axis=0)
    return 1.4826 * np.median(np.abs(e - med), axis=0)


def high_frequency_std(y: np.ndarray, window: int = NOISE_WINDOW) -> np.ndarray:
    """Standard deviation of white noise in each column of y (N, k), from the residual of a
    local cubic fit (corrected by ``1 - h0``, h0 the fit's centre weight).

    Parameters
    ----------
    y : ndarray, shape (N, k)

    Returns
    -------
    ndarray, shape (k,)
    """
    y = np.asarray(y, float)
    window = int(min(window, len(y) - (1 - len(y) % 2)))
    if window < 5:
        return np.zeros(y.shape[1])
    smooth = savgol_filter(y, window, 3, axis=0, mode="interp")
    h0 = savgol_coeffs(window, 3)[window // 2]
    core = slice(window, len(y) - window) if len(y) > 3 * window else slice(None)
    return _robust_std((y - smooth)[core]) / np.sqrt(1.0 - h0)


def leg_lengths(platform, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Leg lengths |p + R e_i - c_i| (N, 6), m, of poses (N, 3) and rotations (N, 3, 3)."""
    g = platform.geometry
    E = np.einsum("nij,kj->nki", rotation, np.asarray(g.platform_joints, float))
    return np.linalg.norm(position[:, None, :] + E - np.asarray(g.base_joints, float)[None],
                          axis=2)


def differentiator_windows(position: np.ndarray, rotation: np.ndarray,
                           polyorder: int | None = None) -> tuple[int, int]:
    """The Savitzky-Golay windows (samples) that ``Motion.from_samples`` chooses for the
    recorded positions (N, 3) and orientations (N, 3, 3): (shorter, longer)."""
    from gsfric.trajectory import (DEFAULT_POLYORDER, _continuous, _gcv_window,
                                   quaternion_from_rotation)

    polyorder = DEFAULT_POLYORDER if polyorder is None else int(polyorder)
    q = _continuous(quaternion_from_rotation(np.asarray(rotation, float)))
    a = _gcv_window(np.asarray(position, float), polyorder)
    b = _gcv_window(q, polyorder)
    return min(a, b), max(a, b)


def speed_uncertainty(platform, t: np.ndarray, position: np.ndarray, rotation: np.ndarray,
                      window: int | None = None, polyorder: int | None = None) -> np.ndarray:
    """Standard deviation of each leg's differentiated speed due to pose noise (6,), m/s.

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
        The Savitzky-Golay differentiator (default: the shorter of the windows
        ``Motion.from_samples`` chooses for positions and orientations: the larger gain).
    """
    from gsfric.trajectory import DEFAULT_POLYORDER

    polyorder = DEFAULT_POLYORDER if polyorder is None else int(polyorder)
    D = leg_lengths(platform, np.asarray(position, float), np.asarray(rotation, float))
    sigma_D = high_frequency_std(D)
    if window is None:
        window = differentiator_windows(position, rotation, polyorder)[0]
    step = float(np.mean(np.diff(t)))
    h = savgol_coeffs(int(window), polyorder, deriv=1, delta=step)
    return sigma_D * float(np.sqrt(np.sum(h ** 2)))


def sliding_mask(speed: np.ndarray, sigma_v: np.ndarray, floor: float,
                 reach: int = 0) -> np.ndarray:
    """(N, 6) True where a leg is known to slide.

    A pair (sample, leg) slides where ``|speed|`` exceeds ``REST_BAND`` sigma_v (and
    ``floor``) and, with ``reach`` > 0, no rest lies within ``reach`` samples: no sample whose
    differentiator window reaches into a rest. A rest is a run of at least ``reach`` samples
    inside the band, with excursions out of the band shorter than ``reach`` samples (the
    differentiated noise is correlated over the window: such an excursion is one noise event,
    or the pull of the next move on the window, not a move).

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
    sigma_v : ndarray, shape (6,)
        Their standard deviation due to pose noise, m/s.
    floor : float
        Smallest half-width of the band, m/s.
    reach : int
        Half-width of the differentiator's window, samples (0: no rest widening).
    """
    band = np.maximum(REST_BAND * np.asarray(sigma_v, float), floor)
    inside = np.abs(speed) <= band[None, :]
    if reach <= 0:
        return ~inside
    from scipy.ndimage import binary_closing, binary_dilation, binary_opening

    reach = int(reach)
    structure = np.ones((reach, 1), bool)
    # a rest: in the band for at least `reach` samples, excursions shorter than `reach`
    # (one correlated noise event of the differentiator) included
    rests = binary_opening(binary_closing(inside, structure=structure), structure=structure)
    widened = binary_dilation(rests, structure=np.ones((2 * reach + 1, 1), bool))
    return ~(inside | widened)


def force_noise(forces: np.ndarray) -> np.ndarray:
    """Independent estimate of each force channel's white noise (6,), N (see module doc)."""
    return high_frequency_std(forces)


def poses_from_columns(columns) -> tuple[np.ndarray, np.ndarray]:
    """Recorded positions (N, 3) and rotations (N, 3, 3) from trajectory columns (a mapping or
    DataFrame with ``x, y, z`` and ``qw, qx, qy, qz`` or ``alpha, beta, gamma``)."""
    from gsfric.trajectory import rotation_from_euler, rotation_from_quaternion

    position = np.stack([np.asarray(columns[k], float) for k in ("x", "y", "z")], axis=1)
    if "qw" in columns:
        q = np.stack([np.asarray(columns[k], float) for k in ("qw", "qx", "qy", "qz")], axis=1)
        rotation = rotation_from_quaternion(q / np.linalg.norm(q, axis=1, keepdims=True))
    else:
        rotation = rotation_from_euler(*(np.asarray(columns[k], float)
                                         for k in ("alpha", "beta", "gamma")))
    return position, rotation


HELD_RUN = 5
"""Consecutive equal values of a force channel that make a dropout (``data_problems``)."""


def _held_run(f: np.ndarray) -> tuple[int, int] | None:
    """The longest run (first index, length) of at least ``HELD_RUN`` equal consecutive values
    of a channel whose neighbouring samples otherwise differ (a noisy load cell: fewer than 1%
    equal neighbours; a coarsely quantised channel repeats values and is not judged)."""
    same = np.diff(f) == 0
    edges = np.diff(np.r_[0, same.astype(np.int8), 0])
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    if starts.size == 0:
        return None
    runs = stops - starts + 1                     # samples in each run of equal values
    short = runs < HELD_RUN
    if np.sum(runs[short] - 1) > 0.01 * same.size or short.all():
        return None                               # quantised, or nothing held
    k = int(np.argmax(runs))
    return int(starts[k]), int(runs[k])


def data_problems(t: np.ndarray, forces: np.ndarray) -> list[str]:
    """Problems of measured force data that no model effect can explain, one line each.

    A channel that is constant, or that sits at its extreme value on a run of samples
    (saturation), or that repeats one value on a run of samples where it otherwise never
    does (a dropout recorded as held or zeroed samples), or a gap in the sample times
    (dropout: a step above 1.5 times the median).
    """
    out = []
    forces = np.asarray(forces, float)
    for i in range(forces.shape[1]):
        f = forces[:, i]
        name = f"F{i + 1}"
        if not np.isfinite(f).any():
            out.append(f"{name}: no finite value (a column of NaN)")
            continue
        spread = float(np.ptp(f))
        if spread <= 1e-12 * max(1.0, float(np.abs(f).max())):
            out.append(f"{name}: constant ({f[0]:.6g} N in every row): a dead channel")
            continue
        saturated = False
        for edge in (f.max(), f.min()):
            at = f == edge
            if at.sum() >= max(5, len(f) // 200):
                runs = np.diff(np.flatnonzero(np.diff(np.r_[0, at.astype(int), 0])))[::2]
                if runs.size and runs.max() >= 5:
                    row = int(np.flatnonzero(at)[0]) + 1
                    out.append(f"{name}: saturated at {edge:.6g} N ({int(at.sum())} rows, "
                               f"first row {row})")
                    saturated = True
                    break
        held = None if saturated else _held_run(f)
        if held is not None:
            row, length = held
            out.append(f"{name}: the same value ({f[row]:.6g} N) in {length} rows from row "
                       f"{row + 1}: a dropout (held or zeroed samples)")
    steps = np.diff(np.asarray(t, float))
    if steps.size:
        median = float(np.median(steps))
        gaps = np.flatnonzero(steps > 1.5 * median)
        if gaps.size:
            missing = int(np.round(np.sum(steps[gaps]) / median)) - gaps.size
            out.append(f"t: dropout of about {missing} samples at {gaps.size} place(s), first "
                       f"after row {int(gaps[0]) + 1} (t = {float(t[gaps[0]]):.6g} s)")
    return out
