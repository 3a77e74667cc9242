"""Smoothing splines for non-uniformly sampled signals, with the penalty chosen for the second
derivative."""

from __future__ import annotations

import numpy as np

from gsfric._optional import optional
from gsfric.signal.noise import divided_difference_coefficients, divided_noise_std

SPLINE_GCV_ROWS = 500
"""Non-uniform motions of more than this many samples choose each component's smoothing-spline
penalty for its derivatives (``spline_penalties``); shorter ones by SciPy's generalized
cross-validation (``make_smoothing_spline``)."""


SPLINE_PENALTIES = np.geomspace(0.5, 200.0, 33) ** 4
"""Penalties tried, over h^3 (h the mean step): ``h^3 s^4`` smooths over about s samples
(the half-width of the spline's equivalent kernel)."""


def _natural_spline_system(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The banded design matrix X and penalty E (5, n) of ``make_smoothing_spline`` (unit
    weights) in the basis of natural cubic splines, built without a loop over samples."""

    n = len(x)
    knots = np.r_[[x[0]] * 3, x, [x[-1]] * 3]
    b = optional("scipy.interpolate").BSpline.design_matrix(x, knots, 3)
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
    E[2:, 0] = divided_difference_coefficients(x[:3], 3)[0]
    E[1:, 1] = divided_difference_coefficients(x[:4], 4)[0]
    E[:, 2:-2] = ((x[4:] - x[:-4])[:, None] * divided_difference_coefficients(x, 5)).T
    E[:-1, -2] = -divided_difference_coefficients(x[-4:], 4)[0]
    E[:-2, -1] = divided_difference_coefficients(x[-3:], 3)[0]
    return X, 6 * E


def smoothing_splines(t: np.ndarray, y: np.ndarray, penalties: list[float]):
    """``make_smoothing_spline(t, y[:, j], lam=penalties[j])`` for every column at once (one
    set-up of the banded system), as one BSpline with a trailing axis of columns."""

    X, E = _natural_spline_system(t)
    solve_banded = optional("scipy.linalg").solve_banded
    c = np.stack([solve_banded((2, 2), X + lam * E, y[:, j])
                  for j, lam in enumerate(penalties)], axis=1)
    k = np.r_[[t[0]] * 3, t, [t[-1]] * 3]
    c0, c1, cm0, cm1 = c[0:1], c[1:2], c[-1:], c[-2:-1]
    coefficients = np.r_[c0 * (k[5] + k[4] - 2 * k[3]) + c1, c0 * (k[5] - k[3]) + c1,
                         c[1:-1], cm0 * (k[-4] - k[-6]) + cm1,
                         cm0 * (2 * k[-4] - k[-5] - k[-6]) + cm1]
    return optional("scipy.interpolate").BSpline.construct_fast(k, coefficients, 3, axis=0)


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
    sigma the white pose noise (``divided_noise_std``) and g the gain of the spline's second
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
    sigma = divided_noise_std(t, y)                                     # (k,)
    inner = slice(n // 20, n - n // 20)
    w = np.random.default_rng(0).standard_normal((n, 1))
    lams = h ** 3 * SPLINE_PENALTIES
    best, chosen, previous = np.inf, lams[0], None
    for lam_j in lams:
        both = smoothing_splines(t, np.concatenate([y, w], axis=1),
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


def spline_fit(t: np.ndarray, y: np.ndarray, lam: float | None
               ) -> tuple[list[np.ndarray], list[float] | None]:
    """The smoothed y (N, k) and its first two derivatives at the times t (N,) (three arrays
    (N, k)), with the penalties used (``spline_penalties``; None for a record of at most
    ``SPLINE_GCV_ROWS`` samples, where ``make_smoothing_spline`` chooses each column's own)."""
    n = len(t)
    if n > SPLINE_GCV_ROWS:
        penalties = spline_penalties(t, y, lam)
        if penalties is not None:
            spline = smoothing_splines(t, y, penalties)
            return [spline.derivative(k)(t) if k else spline(t) for k in (0, 1, 2)], penalties
    make = optional("scipy.interpolate").make_smoothing_spline
    columns = [make(t, y[:, j], lam=lam) for j in range(y.shape[1])]
    return [np.stack([c.derivative(k)(t) if k else c(t) for c in columns], axis=1)
            for k in (0, 1, 2)], None


SPLINE_NOISE_DRAWS = 8
"""Unit white-noise signals passed through a smoothing spline to measure its noise gains
(``spline_noise_gains``)."""

SPLINE_GAIN_SMOOTHING = 51
"""Samples over which the measured squared gains are averaged: a few draws give each
sample's gain to a few percent after it."""


def spline_noise_gains(t: np.ndarray, penalty: float, draws: int = SPLINE_NOISE_DRAWS
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The noise gains (N,) of the first and second derivatives of the smoothing spline of
    penalty ``penalty`` at the times t (N,), 1/s and 1/s^2: white noise of standard deviation
    sigma becomes ``sigma * gain`` on the derivative. Measured on ``draws`` draws of unit
    white noise (seeded: the same times give the same gains), their squares averaged over
    ``SPLINE_GAIN_SMOOTHING`` samples."""
    t = np.asarray(t, float)
    noise = np.random.default_rng(0).standard_normal((len(t), draws))
    spline = smoothing_splines(t, noise, [penalty] * draws)
    uniform_filter1d = optional("scipy.ndimage").uniform_filter1d
    gains = []
    for k in (1, 2):
        power = np.mean(spline.derivative(k)(t) ** 2, axis=1)
        gains.append(np.sqrt(uniform_filter1d(power, SPLINE_GAIN_SMOOTHING, mode="nearest")))
    return gains[0], gains[1]
