"""Platform motions: poses with their velocities and accelerations, and rotation helpers.

Conventions (see docs/architecture.md): SI units, radians, the step as the leading axis.
The orientation ``R`` maps platform-frame vectors to the base frame. In ZXZ angles,
``R = Rz(gamma) Rx(beta) Rz(alpha)``, whose entries are the paper's b_ij; this is
``scipy.spatial.transform.Rotation.from_euler("zxz", [alpha, beta, gamma])`` (extrinsic).
Quaternions are unit and scalar-first, ``(qw, qx, qy, qz)``, Hamilton product, mapping the
platform frame to the base frame. Angular velocity ``omega`` and acceleration ``alpha`` are
expressed in the base frame: ``dR/dt = [omega]x R``.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gsfric._checks import as_array, as_float, fields_equal
from gsfric.errors import GsfricWarning, InputError

if TYPE_CHECKING:
    import pandas as pd

MIN_SAMPLES = 7
"""Fewest samples ``Motion.from_samples`` (and the trajectory readers) accept."""

DEFAULT_POLYORDER = 4
"""Polynomial order of the Savitzky-Golay filter."""

MAX_AUTO_WINDOW = 1601
"""Longest Savitzky-Golay window the automatic choice considers, samples: 0.8 s at 2 kHz, where
pose noise of 10-30 um still wants windows of more than 201 samples (on a 2 kHz multisine,
30 um: the force error of the motion estimate is 2.0 N with 201 samples at most, 0.44 N with
801 or 1601)."""

UNIFORM_RTOL = 1e-4
"""Sampling counts as uniform when every time step is within this fraction of the mean step."""

GIMBAL_SIN_BETA = 1e-3
GIMBAL_JUMP = 0.5
"""A ZXZ sample with |sin(beta)| < GIMBAL_SIN_BETA whose alpha or gamma jumps by more than
GIMBAL_JUMP rad from its neighbour triggers a warning."""

_ROTATION_TOL = 1e-6

SAMPLING_RATE_RANGE = (1.0, 1e6)
"""Sampling rates, Hz, outside which ``Motion.from_samples`` warns that t is probably not in
seconds (integer nanoseconds or milliseconds)."""

MAX_POSITION = 100.0
"""Positions farther than this from the base frame's origin, m, draw a warning (mm given as m)."""


# -- rotations ----------------------------------------------------------------------------------


def rotation_from_euler(alpha: np.ndarray | float, beta: np.ndarray | float,
                        gamma: np.ndarray | float) -> np.ndarray:
    """Rotation matrices ``Rz(gamma) Rx(beta) Rz(alpha)`` from ZXZ angles.

    Parameters
    ----------
    alpha, beta, gamma : array_like, shape (N,) (or broadcastable, or scalars)
        rad.

    Returns
    -------
    ndarray, shape (N, 3, 3)
        Entries are the paper's b_ij, e.g. ``b11 = cos(a)cos(g) - cos(b)sin(a)sin(g)``,
        ``b13 = sin(b)sin(g)``, ``b31 = sin(b)sin(a)``, ``b33 = cos(b)``.
    """
    a, b, g = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (alpha, beta, gamma)))
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    rows = [
        [ca * cg - cb * sa * sg, -sa * cg - cb * ca * sg, sb * sg],
        [ca * sg + cb * sa * cg, -sa * sg + cb * ca * cg, -sb * cg],
        [sb * sa, sb * ca, cb],
    ]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def euler_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """ZXZ angles ``(alpha, beta, gamma)`` of rotation matrices.

    Parameters
    ----------
    rotation : array_like, shape (N, 3, 3)

    Returns
    -------
    ndarray, shape (N, 3)
        alpha, gamma in (-pi, pi], beta in [0, pi], rad. Where sin(beta) vanishes (the level
        pose) only alpha + gamma (or alpha - gamma) is defined; there gamma = 0.
    """
    r = np.asarray(rotation, dtype=float)
    sin_beta = np.hypot(r[..., 0, 2], r[..., 1, 2])
    beta = np.arctan2(sin_beta, r[..., 2, 2])
    regular = sin_beta > 1e-12
    alpha = np.where(regular, np.arctan2(r[..., 2, 0], r[..., 2, 1]),
                     np.arctan2(np.sign(r[..., 2, 2]) * r[..., 1, 0], r[..., 0, 0]))
    gamma = np.where(regular, np.arctan2(r[..., 0, 2], -r[..., 1, 2]), 0.0)
    return np.stack([alpha, beta, gamma], axis=-1)


def quaternion_from_euler(alpha: np.ndarray | float, beta: np.ndarray | float,
                          gamma: np.ndarray | float) -> np.ndarray:
    """Unit quaternions ``(qw, qx, qy, qz)`` of ``Rz(gamma) Rx(beta) Rz(alpha)``, shape (N, 4)."""
    a, b, g = np.broadcast_arrays(*(np.asarray(v, dtype=float) / 2 for v in (alpha, beta, gamma)))
    zero = np.zeros_like(a)
    qa = np.stack([np.cos(a), zero, zero, np.sin(a)], axis=-1)
    qb = np.stack([np.cos(b), np.sin(b), zero, zero], axis=-1)
    qg = np.stack([np.cos(g), zero, zero, np.sin(g)], axis=-1)
    return quaternion_multiply(qg, quaternion_multiply(qb, qa))


def quaternion_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(qw, qx, qy, qz)`` with qw >= 0 of rotation matrices.

    Parameters
    ----------
    rotation : array_like, shape (N, 3, 3)

    Returns
    -------
    ndarray, shape (N, 4)
    """
    from scipy.spatial.transform import Rotation

    r = np.asarray(rotation, dtype=float)
    xyzw = Rotation.from_matrix(r.reshape(-1, 3, 3)).as_quat()
    q = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(r.shape[:-2] + (4,))


def rotation_from_quaternion(quaternion: np.ndarray) -> np.ndarray:
    """Rotation matrices of quaternions ``(qw, qx, qy, qz)`` (normalized first).

    Parameters
    ----------
    quaternion : array_like, shape (N, 4)

    Returns
    -------
    ndarray, shape (N, 3, 3)
    """
    q = np.asarray(quaternion, dtype=float)
    w, x, y, z = np.moveaxis(q / np.linalg.norm(q, axis=-1, keepdims=True), -1, 0)
    rows = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def quaternion_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p q`` of scalar-first quaternions, shape (N, 4)."""
    pw, pv = p[..., :1], p[..., 1:]
    qw, qv = q[..., :1], q[..., 1:]
    w = pw * qw - np.sum(pv * qv, axis=-1, keepdims=True)
    v = pw * qv + qw * pv + np.cross(pv, qv)
    return np.concatenate([w, v], axis=-1)


def _conjugate(q: np.ndarray) -> np.ndarray:
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def _continuous(q: np.ndarray) -> np.ndarray:
    """Flip signs so that consecutive quaternions have a non-negative dot product."""
    dots = np.sum(q[1:] * q[:-1], axis=1)
    signs = np.concatenate([[1.0], np.cumprod(np.where(dots < 0, -1.0, 1.0))])
    return q * signs[:, None]


# -- differentiation ----------------------------------------------------------------------------


def _where(source: str | None, indices: np.ndarray | list[int]) -> str:
    """'rows 3, 4' (1-based, file given) or 'samples 2, 3' (0-based)."""
    indices = [int(i) for i in indices]
    numbers = [i + 1 for i in indices] if source else indices
    word = "row" if source else "sample"
    shown = ", ".join(str(n) for n in numbers[:10])
    more = f" and {len(numbers) - 10} more" if len(numbers) > 10 else ""
    return f"{word}{'s' if len(numbers) > 1 else ''} {shown}{more}"


def _check_euler(euler: np.ndarray, source: str | None) -> None:
    prefix = f"{source}: " if source else ""
    largest = np.abs(euler).max(axis=0)
    big = [f"|{name}| up to {value:.4g}"
           for name, value in zip(("alpha", "beta", "gamma"), largest) if value > 2 * np.pi]
    if big:
        warnings.warn(f"{prefix}angles look like degrees ({', '.join(big)} > 2*pi); "
                      "angles must be in radians", GsfricWarning, stacklevel=4)
    near_lock = np.abs(np.sin(euler[:, 1])) < GIMBAL_SIN_BETA
    near_lock = near_lock[1:] | near_lock[:-1]
    steps = np.abs((np.diff(euler[:, [0, 2]], axis=0) + np.pi) % (2 * np.pi) - np.pi)
    jumps = np.flatnonzero(near_lock & (steps.max(axis=1) > GIMBAL_JUMP)) + 1
    if len(jumps):
        warnings.warn(f"{prefix}ZXZ angles near beta = 0 (where alpha and gamma are ill-defined) "
                      f"jump by more than {GIMBAL_JUMP} rad in alpha or gamma at "
                      f"{_where(source, jumps)}; give the orientation as a quaternion "
                      "(qw, qx, qy, qz) instead", GsfricWarning, stacklevel=4)


def check_units(t: np.ndarray, position: np.ndarray, source: str | None = None,
                stacklevel: int = 4) -> None:
    """Warn (``GsfricWarning``) when times or positions look like the wrong unit.

    A mean time step outside 1 us .. 1 s (a sampling rate outside ``SAMPLING_RATE_RANGE``,
    1 Hz .. 1 MHz) suggests t in ns or ms rather than s; a position beyond ``MAX_POSITION``
    (100 m) suggests mm rather than m. Warnings, not errors: silence them with
    ``warnings.filterwarnings("ignore", category=GsfricWarning)`` where such values are meant.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Increasing times, s.
    position : ndarray, shape (N, 3)
        m.
    source : str, optional
        File name to start the message with.
    """
    prefix = f"{source}: " if source else ""
    if len(t) > 1 and np.isfinite(t[-1] - t[0]):
        step = (t[-1] - t[0]) / (len(t) - 1)
        low, high = SAMPLING_RATE_RANGE
        if step > 0 and not low <= 1.0 / step <= high:
            warnings.warn(f"{prefix}t: mean time step {step:.4g} s, a sampling rate of "
                          f"{1.0 / step:.4g} Hz, outside {low:g} Hz .. {high:g} Hz; t must be "
                          "in s (not ns or ms)", GsfricWarning, stacklevel=stacklevel)
    far = float(np.abs(position).max()) if len(position) else 0.0
    if far > MAX_POSITION:
        warnings.warn(f"{prefix}position: up to {far:.4g} m from the base frame's origin (more "
                      f"than {MAX_POSITION:g} m); positions must be in m, not mm",
                      GsfricWarning, stacklevel=stacklevel)


def is_uniform(t: np.ndarray) -> bool:
    """Whether the times t (N,), s, are uniformly sampled as ``Motion.from_samples`` takes
    them: every step within ``UNIFORM_RTOL`` of the mean step (time stamps rounded to less
    than that, a log's ms with four decimals, still are)."""
    t = np.asarray(t, float)
    steps = np.diff(t)
    mean_step = (t[-1] - t[0]) / (len(t) - 1)
    return bool(np.all(np.abs(steps - mean_step) <= UNIFORM_RTOL * mean_step))


def _candidate_windows(n: int, polyorder: int) -> list[int]:
    smallest = polyorder + 2 if polyorder % 2 else polyorder + 3
    largest = min(n, MAX_AUTO_WINDOW)
    windows = []
    w = smallest
    while w <= largest:
        windows.append(w)
        w = max(w + 2, int(w * 1.25) | 1)
    return windows


def _gcv_window(y: np.ndarray, polyorder: int) -> int:
    """The Savitzky-Golay window minimizing the generalized cross-validation score.

    ``GCV(w) = RSS(w) / (1 - h(w))^2`` with RSS the squared residual of the smoothed signal and
    h the filter's central weight (the hat matrix's diagonal).
    """
    windows = _candidate_windows(len(y), polyorder)
    scores = []
    for w in windows:
        smooth = savgol_filter(y, w, polyorder)
        centre = savgol_weights(w, polyorder)[w // 2]
        scores.append(np.sum((y - smooth) ** 2) / (1.0 - centre) ** 2)
    return windows[int(np.argmin(scores))]


@functools.lru_cache(maxsize=256)
def _polynomial_fit(window: int, polyorder: int) -> np.ndarray:
    """The least-squares polynomial of order ``polyorder`` through a window's samples: the
    matrix (p + 1, window) that maps the samples to its coefficients in Legendre polynomials
    of the abscissa scaled to [-1, 1] (``_polynomial_derivative`` evaluates them). Read-only.

    Legendre polynomials keep the least-squares problem well conditioned for any window:
    ``scipy.signal.savgol_coeffs`` fits powers of the sample index, and at order 6 its weights
    are wrong beyond about 300 samples (those of the value are all zero at 401).
    """
    from numpy.polynomial import legendre

    fit = np.linalg.pinv(legendre.legvander(_abscissa(window)[0], polyorder))
    fit.flags.writeable = False
    return fit


@functools.lru_cache(maxsize=256)
def _polynomial_derivative(window: int, polyorder: int, deriv: int) -> np.ndarray:
    """The matrix (window, p + 1) that maps the coefficients of ``_polynomial_fit`` to the
    polynomial's ``deriv``-th derivative (unit sample step) at each sample of the window.
    Read-only."""
    from numpy.polynomial import legendre

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
    computed as ``_polynomial_fit``)."""
    weights = _polynomial_derivative(window, polyorder, deriv)[window // 2] \
        @ _polynomial_fit(window, polyorder)
    weights.flags.writeable = False
    return weights


def savgol_filter(y: np.ndarray, window: int, polyorder: int, deriv: int = 0) -> np.ndarray:
    """``scipy.signal.savgol_filter(y, window, polyorder, deriv, axis=0, mode="interp")``
    (unit sample step) with the well-conditioned fit of ``_polynomial_fit``: the centred
    weights inside, the polynomial through the first and last ``window`` samples at the ends.

    Parameters
    ----------
    y : ndarray, shape (N, k)
        Uniformly sampled, N >= window.

    Returns
    -------
    ndarray, shape (N, k)
    """
    from scipy.ndimage import correlate1d

    y = np.asarray(y, float)
    window, polyorder, deriv = int(window), int(polyorder), int(deriv)
    derivative = _polynomial_derivative(window, polyorder, deriv)
    fit = _polynomial_fit(window, polyorder)
    half, n = window // 2, len(y)
    out = correlate1d(y, savgol_weights(window, polyorder, deriv), axis=0, mode="constant")
    out[:half] = derivative[:half] @ (fit @ y[:window])
    out[n - half:] = derivative[half + 1:] @ (fit @ y[n - window:])
    return out


def _savgol(y: np.ndarray, window: int, polyorder: int, step: float) -> list[np.ndarray]:
    return [savgol_filter(y, window, polyorder, deriv=k) / step**k for k in (0, 1, 2)]


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
    from numpy.lib.stride_tricks import sliding_window_view
    from scipy.special import comb

    y = np.asarray(y, float)
    m = NOISE_DIFFERENCE_ORDER
    if len(y) <= m:
        return np.zeros(y.shape[1:])
    differences = np.diff(y, n=m, axis=0)
    changing = np.ptp(sliding_window_view(y, m + 1, axis=0), axis=-1) > 0.0
    return np.array([robust_std(d[c]) if c.any() else 0.0
                     for d, c in zip(differences.T, changing.T)]) / np.sqrt(comb(2 * m, m))


def _bias_degree(polyorder: int, deriv: int) -> int:
    """Lowest power of the time whose ``deriv``-th derivative a symmetric Savitzky-Golay filter
    of ``polyorder`` does not reproduce: the first power above ``polyorder`` of the parity of
    ``deriv`` (the filter is symmetric for even derivatives, antisymmetric for odd ones, so
    the powers of the other parity give the true value, zero)."""
    return polyorder + 1 if (polyorder + 1 - deriv) % 2 == 0 else polyorder + 2


BIAS_WEIGHT = 4.0

DETECTED_BIAS = 5.0
"""A filter's estimated bias at a sample counts as detected when it exceeds this many times
the filter's noise (standard deviation): on white noise alone the estimate stays below 1.2
times the noise (20,000 samples, every candidate filter)."""


def adaptive_filters(y: np.ndarray, polyorder: int = DEFAULT_POLYORDER,
                     sigma: np.ndarray | None = None, deriv: int = 2
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The Savitzky-Golay filter (polynomial order and window) of every sample for the
    ``deriv``-th derivative: the one minimizing a local estimate of that derivative's mean
    squared error (bias squared plus noise variance).

    Candidates: the orders ``polyorder`` and ``polyorder + 2``, each with the windows
    w_1 < w_2 < ... of ``_candidate_windows`` (ratio about 1.25). For the estimate a_w of
    order p and window w (filter coefficients h_w):

    * its noise variance is ``sigma^2 ||h_w||^2`` (sigma the white pose noise,
      ``white_noise_std``);
    * its bias is, to leading order, ``c_w y^(m)`` with m = ``_bias_degree(p, deriv)`` (5 for
      the velocity, 6 for the acceleration with order 4) and ``c_w = sum_j h_w[j] j^m / m!``
      known exactly. So the next window's bias is ``g = c_{w'} / c_w`` (about 1.25^(m - deriv))
      times as large, and the difference ``a_w - a_{w'}`` has the mean ``(1 - g) bias_w`` and
      the exactly known noise variance ``sigma^2 ||h_w - h_{w'}||^2``. Its square averaged
      over the span of w', minus that variance, divided by ``(1 - g)^2``, estimates
      ``bias_w^2`` there without a pilot estimate of y^(m).
    * The bias grows with the window: once a window's estimated bias exceeds
      ``DETECTED_BIAS`` (5) times its noise (it is detected), no longer window of that order
      at that sample is credited with less. The
      estimate compares two windows, and where both span a whole feature of the motion (a
      triangle's period, a move with its rests) they are wrong alike and differ little: left
      to itself it would choose such a window (at 480 Hz, 583 samples across the corners of a
      0.6 Hz triangle wave, ten times the error of the 63 samples chosen with the rule).

    Each sample takes the filter of least estimated error summed over the columns (the mean
    squared error of the vector's derivative). The choice is local, so a motion whose
    frequency content changes along the record (a chirp, moves and rests) gets long windows
    where it is slow and short ones where it is fast; noise-free samples get the shortest.
    The higher order has a smaller bias for a given window and a larger noise: it wins on
    fast smooth motion. The velocity's variance falls more slowly with the window than the
    acceleration's (w^-3 against w^-5) while their biases grow alike, so the velocity's
    windows are the shorter.

    Parameters
    ----------
    y : ndarray, shape (N, k)
        Uniformly sampled signal.
    polyorder : int
        The lower of the two orders.
    sigma : ndarray, shape (k,), optional
        White-noise standard deviation of each column (default: ``white_noise_std``).
    deriv : int
        1 (velocity) or 2 (acceleration).

    Returns
    -------
    orders, windows : ndarray of int, shape (N,) each
        Odd windows, ``order < w <= min(N, MAX_AUTO_WINDOW)``.
    """
    from scipy.ndimage import uniform_filter1d

    y = np.asarray(y, float)
    n = len(y)
    if sigma is None:
        sigma = white_noise_std(y)
    scale = np.maximum(np.abs(y).max(axis=0), 1.0)
    variance = np.maximum(np.asarray(sigma, float), 1e-13 * scale) ** 2
    first = _candidate_windows(n, polyorder)
    best = np.full(n, np.inf)
    orders = np.full(n, polyorder)
    windows = np.full(n, first[0])
    for p in (polyorder, polyorder + 2):
        candidates = _candidate_windows(n, p)
        if len(candidates) < 2:
            continue
        m = _bias_degree(p, deriv)
        width = candidates[-1]

        def coefficients(w: int) -> np.ndarray:
            h = np.zeros(width)
            h[(width - w) // 2:(width + w) // 2] = savgol_weights(w, p, deriv)
            return h

        j = (np.arange(width) - width // 2).astype(float)
        previous = savgol_filter(y, candidates[0], p, deriv)
        detected = np.zeros_like(y)
        for w, w_next in zip(candidates[:-1], candidates[1:]):
            h, h_next = coefficients(w), coefficients(w_next)
            following = savgol_filter(y, w_next, p, deriv)
            growth = float(np.sum(h_next * j ** m) / np.sum(h * j ** m))
            spread = uniform_filter1d((previous - following) ** 2, size=w_next, axis=0,
                                      mode="nearest")
            bias2 = np.maximum(spread - variance * float(np.sum((h - h_next) ** 2)), 0.0) \
                / (1.0 - growth) ** 2
            noise2 = variance * float(np.sum(h ** 2))
            bias2 = np.maximum(bias2, detected)
            detected = np.where(bias2 > DETECTED_BIAS**2 * noise2, bias2, detected)
            risk = np.sum(BIAS_WEIGHT * bias2 + noise2, axis=1)
            better = risk < best
            best[better] = risk[better]
            orders[better] = p
            windows[better] = w
            previous = following
    return orders, windows


def motion_filters(y: np.ndarray, polyorder: int = DEFAULT_POLYORDER
                   ) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The filters ``Motion.from_samples`` uses at each sample of a uniformly sampled signal
    (N, k) when it chooses them (``adaptive_filters``): ((orders, windows) for the value and
    the first derivative, (orders, windows) for the second derivative), each array (N,)."""
    sigma = white_noise_std(y)
    return (adaptive_filters(y, polyorder, sigma, deriv=1),
            adaptive_filters(y, polyorder, sigma, deriv=2))


def _savgol_adaptive(y: np.ndarray, filters, step: float) -> list[np.ndarray]:
    """``_savgol`` with each sample's own filters (``motion_filters``)."""
    out = [np.empty_like(y, dtype=float) for _ in range(3)]
    for derivatives, (orders, windows) in (((0, 1), filters[0]), ((2,), filters[1])):
        pairs = np.unique(np.stack([orders, windows], axis=1), axis=0)
        for p, w in pairs:
            rows = (orders == p) & (windows == w)
            for k in derivatives:
                values = savgol_filter(y, int(w), int(p), k)
                out[k][rows] = values[rows] / step**k
    return out


SPLINE_GCV_ROWS = 500
"""Non-uniform motions of more than this many samples choose each component's smoothing-spline
penalty for its derivatives (``spline_penalties``); shorter ones by SciPy's generalized
cross-validation (``make_smoothing_spline``)."""

SPLINE_PENALTIES = np.geomspace(0.5, 200.0, 33) ** 4
"""Penalties tried, over h^3 (h the mean step): ``h^3 s^4`` smooths over about s samples
(the half-width of the spline's equivalent kernel)."""


def _divided_difference_coefficients(x: np.ndarray, width: int) -> np.ndarray:
    """1 / prod_{k != i} (x_i - x_k) over every window of ``width`` consecutive samples."""
    from numpy.lib.stride_tricks import sliding_window_view

    windows = sliding_window_view(x, width)
    diffs = windows[:, :, None] - windows[:, None, :]
    diffs[:, np.arange(width), np.arange(width)] = 1.0
    return 1.0 / diffs.prod(axis=2)


def _natural_spline_system(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The banded design matrix X and penalty E (5, n) of ``make_smoothing_spline`` (unit
    weights) in the basis of natural cubic splines, built without a loop over samples."""
    from scipy.interpolate import BSpline

    n = len(x)
    knots = np.r_[[x[0]] * 3, x, [x[-1]] * 3]
    b = BSpline.design_matrix(x, knots, 3)
    X = np.zeros((5, n))
    for i in range(1, 4):
        X[i, 2:-2] = b[i: i - 4, 3: -3][np.diag_indices(n - 4)]
    X[1, 1] = b[0, 0]
    X[2, :2] = ((x[2] + x[1] - 2 * x[0]) * b[0, 0], b[1, 1] + b[1, 2])
    X[3, :2] = ((x[2] - x[0]) * b[1, 1], b[2, 2])
    X[1, -2:] = (b[-3, -3], (x[-1] - x[-3]) * b[-2, -2])
    X[2, -2:] = (b[-2, -3] + b[-2, -2], (2 * x[-1] - x[-2] - x[-3]) * b[-1, -1])
    X[3, -2] = b[-1, -1]
    E = np.zeros((5, n))
    E[2:, 0] = _divided_difference_coefficients(x[:3], 3)[0]
    E[1:, 1] = _divided_difference_coefficients(x[:4], 4)[0]
    E[:, 2:-2] = ((x[4:] - x[:-4])[:, None] * _divided_difference_coefficients(x, 5)).T
    E[:-1, -2] = -_divided_difference_coefficients(x[-4:], 4)[0]
    E[:-2, -1] = _divided_difference_coefficients(x[-3:], 3)[0]
    return X, 6 * E


def _smoothing_splines(t: np.ndarray, y: np.ndarray, penalties: list[float]):
    """``make_smoothing_spline(t, y[:, j], lam=penalties[j])`` for every column at once (one
    set-up of the banded system), as one BSpline with a trailing axis of columns."""
    from scipy.interpolate import BSpline
    from scipy.linalg import solve_banded

    X, E = _natural_spline_system(t)
    c = np.stack([solve_banded((2, 2), X + lam * E, y[:, j])
                  for j, lam in enumerate(penalties)], axis=1)
    k = np.r_[[t[0]] * 3, t, [t[-1]] * 3]
    c0, c1, cm0, cm1 = c[0:1], c[1:2], c[-1:], c[-2:-1]
    coefficients = np.r_[c0 * (k[5] + k[4] - 2 * k[3]) + c1, c0 * (k[5] - k[3]) + c1,
                         c[1:-1], cm0 * (k[-4] - k[-6]) + cm1,
                         cm0 * (2 * k[-4] - k[-5] - k[-6]) + cm1]
    return BSpline.construct_fast(k, coefficients, 3, axis=0)


def _divided_noise_std(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """White-noise standard deviation of each column of y (N, k) at the non-uniform times t
    (N,), from the 6th divided differences (noise variance ``sigma^2 sum w^2``, w their
    weights; the motion's part ``y^(6) / 6!`` does not grow with a jitter of the times);
    robust scale (median of the normalised squares), over the windows whose readings change."""
    from numpy.lib.stride_tricks import sliding_window_view

    m = NOISE_DIFFERENCE_ORDER
    scale = (t[-1] - t[0]) / (len(t) - 1)
    w = _divided_difference_coefficients((t - t[0]) / scale, m + 1)
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


def spline_penalties(t: np.ndarray, y: np.ndarray, lam: float | None = None
                     ) -> list[float] | None:
    """The smoothing-spline penalty of each column of y (N, k) that ``Motion.from_samples``
    uses on a non-uniform time base t (N,) of more than ``SPLINE_GCV_ROWS`` samples (None for
    shorter ones: ``make_smoothing_spline``'s own choice).

    One penalty for all the columns of a signal (the position's x, y, z; the quaternion's
    four components), so that the estimate does not depend on the axes of the base frame:
    the penalty of least estimated mean squared error of the second derivative (the
    acceleration, which the inertial forces scale), over ``SPLINE_PENALTIES``, as the uniform
    time base's filters are chosen (``adaptive_filters``): the noise part is ``sigma^2 g^2``,
    sigma the white pose noise (``_divided_noise_std``) and g the gain of the spline's second
    derivative for unit white noise on this time base (measured on one draw); the bias of a
    cubic smoothing spline grows in proportion to its penalty, so the bias at ``lam_j`` is
    ``(a_j - a_{j-1}) / (1 - lam_{j-1} / lam_j)`` (a the second derivatives), less the noise
    that difference carries; the search ends where the error has grown tenfold over its
    least (beyond, a spline that has flattened the motion shows no bias in these
    differences). Summed over the columns, averaged over the record without its first and
    last 5 %.
    (Generalized cross-validation of the positions, the earlier choice, minimises the error of
    the position, not of its second derivative; and SciPy's search for it over a linear range
    of penalties smoothed a 1 Hz motion flat on a 1 kHz log.)"""
    n = len(t)
    if n <= SPLINE_GCV_ROWS:
        return None
    if lam is not None:
        return [lam] * y.shape[1]
    t, y = np.asarray(t, float), np.asarray(y, float)
    h = (t[-1] - t[0]) / (n - 1)
    sigma = _divided_noise_std(t, y)                                     # (k,)
    inner = slice(n // 20, n - n // 20)
    w = np.random.default_rng(0).standard_normal((n, 1))
    lams = h ** 3 * SPLINE_PENALTIES
    best, chosen, previous = np.inf, lams[0], None
    for lam_j in lams:
        both = _smoothing_splines(t, np.concatenate([y, w], axis=1),
                                  [lam_j] * (y.shape[1] + 1)).derivative(2)(t)[inner]
        a, g = both[:, :-1], both[:, -1]
        noise = sigma ** 2 * float(np.mean(g ** 2))
        if previous is None:
            mse = float(noise.sum())
        else:
            a0, g0, lam0 = previous
            k = 1.0 / (1.0 - lam0 / lam_j)
            bias2 = np.mean((k * (a - a0)) ** 2, axis=0)
            bias2 = np.maximum(bias2 - sigma ** 2 * float(np.mean((k * (g - g0)) ** 2)), 0.0)
            mse = float(np.sum(bias2 + noise))
        # past the least error the error grows; once the spline has flattened the motion,
        # larger penalties change nothing and their differences no longer show the bias:
        # the search ends where the error has grown tenfold over its least
        if mse > 10.0 * best:
            break
        if mse < best:
            best, chosen = mse, lam_j
        previous = (a, g, lam_j)
    return [float(chosen)] * y.shape[1]


def _spline(t: np.ndarray, y: np.ndarray, lam: float | None) -> list[np.ndarray]:
    from scipy.interpolate import make_smoothing_spline

    n = len(t)
    if n > SPLINE_GCV_ROWS:
        penalties = spline_penalties(t, y, lam)
        if penalties is not None:
            spline = _smoothing_splines(t, y, penalties)
            return [spline.derivative(k)(t) if k else spline(t) for k in (0, 1, 2)]
    columns = [make_smoothing_spline(t, y[:, j], lam=lam) for j in range(y.shape[1])]
    return [np.stack([c.derivative(k)(t) if k else c(t) for c in columns], axis=1)
            for k in (0, 1, 2)]


# -- Motion -------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Motion:
    """A platform motion sampled at N steps; all arrays read-only float64.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time, s.
    position : ndarray, shape (N, 3)
        Platform frame origin in the base frame, m.
    rotation : ndarray, shape (N, 3, 3)
        Orientation: maps platform-frame vectors to the base frame.
    velocity : ndarray, shape (N, 3)
        Of the platform frame origin, base frame, m/s.
    omega : ndarray, shape (N, 3)
        Angular velocity, base frame, rad/s.
    acceleration : ndarray, shape (N, 3)
        Of the platform frame origin, base frame, m/s^2.
    alpha : ndarray, shape (N, 3)
        Angular acceleration, base frame, rad/s^2.

    Every array must be finite and ``rotation`` orthonormal with determinant +1 (to 1e-6).
    ``t`` need not increase (a set of unrelated poses is a valid Motion); ``from_samples``
    requires it to.
    """

    t: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    acceleration: np.ndarray
    alpha: np.ndarray

    def __post_init__(self) -> None:
        t = as_array(self.t, (None,), "Motion.t")
        n = len(t)
        if n == 0:
            raise InputError("Motion.t: a motion needs at least one step")
        object.__setattr__(self, "t", t)
        for name in ("position", "velocity", "omega", "acceleration", "alpha"):
            object.__setattr__(self, name, as_array(getattr(self, name), (n, 3), f"Motion.{name}"))
        rotation = as_array(self.rotation, (n, 3, 3), "Motion.rotation")
        error = np.abs(np.einsum("nji,njk->nik", rotation, rotation) - np.eye(3)).max(axis=(1, 2))
        bad = np.flatnonzero((error > _ROTATION_TOL) | (np.linalg.det(rotation) < 0))
        if len(bad):
            raise InputError(f"Motion.rotation[{bad[0]}]: not a rotation matrix "
                             f"(|R^T R - I| = {error[bad[0]]:.3g}, det = "
                             f"{np.linalg.det(rotation[bad[0]]):.3g})")
        object.__setattr__(self, "rotation", rotation)

    __eq__ = fields_equal
    __hash__ = None  # type: ignore[assignment]

    def __len__(self) -> int:
        return len(self.t)

    @classmethod
    def from_arrays(cls, t: np.ndarray, position: np.ndarray, rotation: np.ndarray,
                    velocity: np.ndarray, omega: np.ndarray, acceleration: np.ndarray,
                    alpha: np.ndarray) -> Motion:
        """A motion from its arrays (shapes as the attributes), validated."""
        return cls(t, position, rotation, velocity, omega, acceleration, alpha)

    @classmethod
    def _trusted(cls, t, position, rotation, velocity, omega, acceleration, alpha) -> Motion:
        """A motion from float64 arrays of the attributes' shapes that the caller has already
        checked (finite; rotations built from unit quaternions): no validation pass. Private:
        for the streamed reader, which checks every value once as it builds them."""
        motion = object.__new__(cls)
        for name, value in zip(("t", "position", "rotation", "velocity", "omega",
                                "acceleration", "alpha"),
                               (t, position, rotation, velocity, omega, acceleration, alpha)):
            value = np.ascontiguousarray(value, dtype=np.float64)
            value.flags.writeable = False
            object.__setattr__(motion, name, value)
        return motion

    @classmethod
    def from_samples(cls, t: np.ndarray, position: np.ndarray, *,
                     euler: np.ndarray | None = None, quaternion: np.ndarray | None = None,
                     window: int | None = None, polyorder: int = DEFAULT_POLYORDER,
                     lam: float | None = None, source: str | None = None) -> Motion:
        """A motion from sampled poses, by smoothing differentiation.

        The orientation is converted to unit quaternions (never are angles differentiated),
        made sign-continuous, and position and quaternion are smoothed and differentiated
        twice:

        * Uniform sampling (every step within ``UNIFORM_RTOL`` of the mean step): a
          Savitzky-Golay filter (``savgol_filter``: SciPy's with ``mode="interp"``, on
          well-conditioned weights; orders 0, 1 and 2) of ``window`` samples and polynomial
          order ``polyorder``. With
          ``window=None`` the filter (order ``polyorder`` or ``polyorder + 2``, odd window up
          to ``MAX_AUTO_WINDOW`` samples) is chosen per sample, separately for position and
          quaternion and for the velocity (which position and velocity use) and the
          acceleration, as the one of least estimated mean squared error
          (``adaptive_filters``): short filters where the motion is fast or the pose
          noise-free, long ones where it is slow or noisy.
        * Non-uniform sampling: a cubic smoothing spline of every component
          (``scipy.interpolate.make_smoothing_spline``) with penalty ``lam``, chosen by
          generalized cross-validation when None. Being natural splines, their second
          derivative vanishes at both ends, so the accelerations of the first and last few
          samples are biased towards zero.

        With p the smoothed (not exactly unit) quaternion and dots time derivatives,
        ``omega = 2 vec(pdot p*) / |p|^2`` and
        ``alpha = 2 vec(pddot p*) / |p|^2 - omega 2 (p . pdot) / |p|^2``, which for a unit
        quaternion are ``omega = 2 vec(qdot q*)`` and ``alpha = 2 vec(qddot q*)``, in the base
        frame. Position and rotation of the result are the smoothed ones.

        Parameters
        ----------
        t : array_like, shape (N,)
            Strictly increasing times, s; N >= ``MIN_SAMPLES``.
        position : array_like, shape (N, 3)
            Platform frame origin in the base frame, m.
        euler : array_like, shape (N, 3), optional
            ZXZ angles (alpha, beta, gamma), rad. Warns (``GsfricWarning``) if any exceeds
            2 pi in magnitude (degrees?) or if, where |sin(beta)| < ``GIMBAL_SIN_BETA``, alpha
            or gamma jump by more than ``GIMBAL_JUMP`` between samples.
        quaternion : array_like, shape (N, 4), optional
            ``(qw, qx, qy, qz)``, platform frame to base frame; normalized here. Give exactly
            one of ``euler`` and ``quaternion``.
        window : int, optional
            Odd Savitzky-Golay window, ``polyorder < window <= N`` (uniform sampling only).
        polyorder : int
            Savitzky-Golay polynomial order, >= 2.
        lam : float, optional
            Smoothing-spline penalty (non-uniform sampling only).
        source : str, optional
            File name for messages; when given, messages start with it and name 1-based rows,
            otherwise they name 0-based sample indices.

        Returns
        -------
        Motion

        Raises
        ------
        InputError
            Bad shapes, non-finite values, times that do not increase, a zero quaternion, too
            few samples, an invalid window or polyorder.
        """
        prefix = f"{source}: " if source else ""
        try:
            with np.errstate(all="ignore"):
                return cls._from_samples(t, position, euler, quaternion, window, polyorder,
                                         lam, source)
        except InputError as error:
            if prefix and not str(error).startswith(prefix):
                raise InputError(prefix + str(error)) from None
            raise

    @classmethod
    def _from_samples(cls, t, position, euler, quaternion, window, polyorder, lam,
                      source) -> Motion:
        t = as_array(t, (None,), "t")
        n = len(t)
        if n < MIN_SAMPLES:
            raise InputError(f"{n} samples; at least {MIN_SAMPLES} are needed to differentiate")
        position = as_array(position, (n, 3), "position")
        if (euler is None) == (quaternion is None):
            raise InputError("give the orientation as exactly one of euler= or quaternion=")
        steps = np.diff(t)
        bad = np.flatnonzero(steps <= 0)
        if len(bad):
            raise InputError(f"{_where(source, bad[:1] + 1)}: t does not increase")
        if not np.isfinite(t[-1] - t[0]):
            raise InputError("t spans too large a range")
        check_units(t, position, source, stacklevel=5)

        if euler is not None:
            euler = as_array(euler, (n, 3), "euler")
            _check_euler(euler, source)
            q = quaternion_from_euler(euler[:, 0], euler[:, 1], euler[:, 2])
        else:
            q = as_array(quaternion, (n, 4), "quaternion")
            norms = np.linalg.norm(q, axis=1)
            zero = np.flatnonzero(norms < 1e-12)
            if len(zero):
                raise InputError(f"{_where(source, zero[:1])}: quaternion of zero length")
            q = q / norms[:, None]
        q = _continuous(q)

        if isinstance(polyorder, bool) or not isinstance(polyorder, (int, np.integer)) \
                or polyorder < 2:
            raise InputError(f"polyorder must be an integer >= 2, got {polyorder!r}")
        if polyorder + 1 >= n:
            raise InputError(f"polyorder = {polyorder} needs more than {polyorder + 1} samples, "
                             f"got {n}")
        if lam is not None:
            lam = as_float(lam, "lam", minimum=0.0)
        mean_step = (t[-1] - t[0]) / (n - 1)
        uniform = is_uniform(t)
        if uniform:
            if window is None:
                filters = (motion_filters(position, polyorder), motion_filters(q, polyorder))
                p0, p1, p2 = _savgol_adaptive(position, filters[0], mean_step)
                q0, q1, q2 = _savgol_adaptive(q, filters[1], mean_step)
            else:
                _check_window(window, polyorder, n)
                p0, p1, p2 = _savgol(position, window, polyorder, mean_step)
                q0, q1, q2 = _savgol(q, window, polyorder, mean_step)
        else:
            if window is not None:
                warnings.warn(f"{source + ': ' if source else ''}t is not uniformly "
                              "sampled: window is ignored, a smoothing spline is used",
                              GsfricWarning, stacklevel=3)
            try:
                p0, p1, p2 = _spline(t, position, lam)
                q0, q1, q2 = _spline(t, q, lam)
            except ValueError as error:
                raise InputError(f"smoothing spline failed: {error}") from None
        squared = np.sum(q0 * q0, axis=1, keepdims=True)
        omega = 2 * quaternion_multiply(q1, _conjugate(q0))[:, 1:] / squared
        alpha = (2 * quaternion_multiply(q2, _conjugate(q0))[:, 1:] / squared
                 - omega * 2 * np.sum(q0 * q1, axis=1, keepdims=True) / squared)
        rotation = rotation_from_quaternion(q0)
        results = (p0, p1, p2, rotation, omega, alpha)
        if not all(np.isfinite(r).all() for r in results):
            raise InputError("differentiation gave non-finite values (values or time steps "
                             "out of range)")
        motion = cls(t, p0, rotation, p1, omega, p2, alpha)
        if uniform and window is None:
            object.__setattr__(motion, "_filters", (int(polyorder), filters))
        object.__setattr__(motion, "_recorded", (position, q))
        return motion

    def recorded_poses(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The samples ``from_samples`` differentiated: positions (N, 3), m, and rotations
        (N, 3, 3), unsmoothed; None for a motion not made by ``from_samples``, or a slice.
        The pose noise, and from it the uncertainty of the differentiated speed, is measured
        on them (``gsfric.discovery``); the smoothed poses hide most of it."""
        recorded = getattr(self, "_recorded", None)
        if recorded is None:
            return None
        position, q = recorded
        return position, rotation_from_quaternion(q)

    def sample_filters(self, polyorder: int = DEFAULT_POLYORDER):
        """The per-sample Savitzky-Golay filters ``from_samples`` chose for this motion
        (``motion_filters`` of the position and of the quaternion: ``(position, quaternion)``,
        each ``((orders, windows), (orders, windows))`` of arrays (N,)), or None: a motion not
        made by ``from_samples`` with chosen filters of order ``polyorder``, or a slice."""
        chosen = getattr(self, "_filters", None)
        if chosen is None or chosen[0] != int(polyorder):
            return None
        return chosen[1]

    def slice(self, start: int | None = None, stop: int | None = None) -> Motion:
        """Steps ``start:stop`` (Python slice semantics) as a new Motion (at least one step)."""
        part = slice(start, stop)
        if len(self.t[part]) == 0:
            raise InputError(f"Motion.slice({start}, {stop}): no steps in a motion of {len(self)}")
        return Motion(self.t[part], self.position[part], self.rotation[part],
                      self.velocity[part], self.omega[part], self.acceleration[part],
                      self.alpha[part])

    def quaternion(self) -> np.ndarray:
        """The orientation as sign-continuous unit quaternions ``(qw, qx, qy, qz)``, (N, 4)."""
        return _continuous(quaternion_from_rotation(self.rotation))

    def euler(self) -> np.ndarray:
        """The orientation as ZXZ angles ``(alpha, beta, gamma)``, (N, 3), rad."""
        return euler_from_rotation(self.rotation)

    def to_frame(self, derivatives: bool = False) -> pd.DataFrame:
        """The motion as a table.

        Columns ``t, x, y, z, qw, qx, qy, qz, alpha, beta, gamma`` (a valid trajectory file:
        the reader uses the quaternion when both orientations are present); with
        ``derivatives``, also ``vx, vy, vz, omega_x, omega_y, omega_z, ax, ay, az,
        alpha_x, alpha_y, alpha_z``.
        """
        import pandas as pd

        columns: dict[str, np.ndarray] = {"t": self.t}
        columns.update(zip(("x", "y", "z"), self.position.T))
        columns.update(zip(("qw", "qx", "qy", "qz"), self.quaternion().T))
        columns.update(zip(("alpha", "beta", "gamma"), self.euler().T))
        if derivatives:
            for prefix, values in (("v", self.velocity), ("omega_", self.omega),
                                   ("a", self.acceleration), ("alpha_", self.alpha)):
                columns.update(zip((prefix + c for c in "xyz"), values.T))
        return pd.DataFrame(columns)


def _check_window(window: object, polyorder: int, n: int) -> None:
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)):
        raise InputError(f"window must be an odd integer, got {window!r}")
    if window % 2 == 0:
        raise InputError(f"window must be odd, got {window}")
    if window <= polyorder:
        raise InputError(f"window = {window} must exceed polyorder = {polyorder}")
    if window > n:
        raise InputError(f"window = {window} is longer than the {n} samples")
