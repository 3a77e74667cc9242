"""The shared fit of parameters to measured forces (``gsfric.evaluation.fitting``): closed forms
of weighted, whitened and bounded linear least squares, a nonlinear model recovered exactly,
coordinates and held rows, the start kept when no evaluation is allowed."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from gsfric.evaluation.fitting import fit

M = 400


def _linear(seed: int, k: int = 3):
    """F(theta) = X theta, X (M, 6, k), and measured forces with noise."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(M, 6, k))
    truth = rng.normal(size=k)
    measured = X @ truth + 0.1 * rng.normal(size=(M, 6))
    return X, measured, (lambda th: X @ th), (lambda th: (X @ th, X.copy()))


def _difference(a: np.ndarray) -> np.ndarray:
    """A whitening filter along time: first differences, (M - 1, 6, ...)."""
    return a[1:] - 0.6 * a[:-1]


def test_weighted_whitened_linear_fit_is_the_generalised_least_squares_solution():
    X, measured, forces, derivative = _linear(0)
    weight = np.random.default_rng(1).uniform(0.5, 2.0, (M, 6))
    result = fit(forces, derivative, measured, np.zeros(3), np.full(3, -np.inf),
                 np.full(3, np.inf), max_nfev=50, weight=weight, whiten=_difference)
    A = _difference(X * weight[:, :, None]).reshape(-1, 3)
    b = _difference(measured * weight).ravel()
    expected = np.linalg.lstsq(A, b, rcond=None)[0]
    np.testing.assert_allclose(result.theta, expected, rtol=1e-7)
    np.testing.assert_allclose(result.residual, weight * (measured - X @ result.theta))
    np.testing.assert_allclose(result.jacobian, X * weight[:, :, None])
    r = b - A @ result.theta
    assert result.cost == pytest.approx(0.5 * r @ r, rel=1e-12)
    assert result.status > 0


def test_bounds_give_the_bounded_linear_solution():
    X, measured, forces, derivative = _linear(2)
    free = np.linalg.lstsq(X.reshape(-1, 3), measured.ravel(), rcond=None)[0]
    lower, upper = free - 1.0, free.copy()
    lower[0] = upper[0] = free[0] + 0.5              # no room: held there
    upper[1] = free[1] - 0.3                          # the solution presses on this bound
    result = fit(forces, derivative, measured, free, lower, upper, max_nfev=50)
    rest = slice(1, 3)
    expected = lsq_linear(X[:, :, rest].reshape(-1, 2),
                          (measured - X[:, :, 0] * lower[0]).ravel(),
                          bounds=(lower[rest], upper[rest])).x
    assert result.theta[0] == lower[0]
    np.testing.assert_allclose(result.theta[rest], expected, atol=1e-8)
    assert result.theta[1] == pytest.approx(upper[1], abs=1e-8)


def test_a_nonlinear_model_in_its_own_coordinates_is_recovered_exactly():
    """F = a exp(-t / tau) per leg, fitted in z = log(a, tau): noise-free data give the truth;
    rows holding tau at a reference pull it there with stiffness that grows without bound."""
    t = np.linspace(0.0, 2.0, M)[:, None] * np.ones(6)
    truth = np.array([3.0, 0.4])

    def derivative(theta):
        a, tau = theta
        e = np.exp(-t / tau)
        return a * e, np.stack([e, a * e * t / tau ** 2], axis=2)

    def dtheta(z):
        return np.diag(np.exp(z))

    to_theta = np.exp
    measured = derivative(truth)[0]
    result = fit(lambda th: derivative(th)[0], derivative, measured, np.log([1.0, 1.0]),
                 np.full(2, -5.0), np.full(2, 5.0), max_nfev=100,
                 coordinates=(to_theta, dtheta))
    np.testing.assert_allclose(result.theta, truth, rtol=1e-8)
    np.testing.assert_allclose(result.z, np.log(truth), atol=1e-8)
    held = fit(lambda th: derivative(th)[0], derivative, measured, np.log([1.0, 1.0]),
               np.full(2, -5.0), np.full(2, 5.0), max_nfev=100,
               coordinates=(to_theta, dtheta), held=(np.array([[0.0, 1e6]]), np.array([0, 0.5])))
    assert held.theta[1] == pytest.approx(0.5, abs=1e-4)
    assert held.cost > result.cost


def test_no_evaluation_keeps_the_start_and_its_given_residual():
    X, measured, _, _ = _linear(3)
    start = np.array([0.1, 0.2, 0.3])
    residual, jacobian = measured - X @ start, X.copy()

    def never(theta):
        raise AssertionError("evaluated")

    result = fit(never, never, measured, start, np.full(3, -1.0), np.full(3, 1.0), max_nfev=0,
                 at_start=(residual, jacobian))
    assert np.array_equal(result.theta, start)
    assert result.residual is residual and result.nfev == 0 and result.status == 0
    assert result.cost == pytest.approx(0.5 * np.sum(residual ** 2))
