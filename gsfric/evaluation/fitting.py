"""Parameters of the compiled model fitted to measured forces: bounded, weighted (and, for
coloured noise, whitened) nonlinear least squares, the one fit of ``identify`` and of
``discover``'s refinement.

The fit minimises half the sum of squares of

* the data rows ``whiten(weight * (measured - F(theta)))``, (M', 6) flattened, and
* optionally rows holding directions of theta at a reference, ``held @ (theta - reference)``,

over the fit's coordinates z within their bounds, theta = ``to_theta(z)`` (by default z
itself), with ``scipy.optimize.least_squares`` (trust-region reflective, each coordinate scaled
by its Jacobian column's norm) and the analytic Jacobian from the compiled model,
``-whiten(weight * dF/dtheta) @ dtheta/dz``. Trial points evaluate the forces only; their
derivative is computed at the points the trust region accepts, and the last one is kept for
the result.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gsfric._optional import optional

COST_TOL = 1e-4
"""The fit stops at a step that lowers the cost (half the sum of squared residuals in units of
the noise) by less than ``COST_TOL``. Moving one parameter by a standard deviation changes the
cost by 0.5, so 0.01 would already be a hundredth of a standard deviation; the trust-region
method stops at the first such step, even one shortened by its region, so the tolerance is a
hundred times smaller still. It is passed to ``least_squares`` as ``ftol = COST_TOL / cost``,
the cost of rows of unit noise being about half their number (the rows of non-zero weight)."""

Forces = Callable[[np.ndarray], np.ndarray]
"""theta (p,) -> the model's forces F (M, 6), N, on the rows of the measured forces."""
Derivative = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
"""theta (p,) -> F (M, 6), N, and dF/dtheta (M, 6, p)."""


@dataclass
class Fit:
    """The solution of ``fit``.

    Attributes
    ----------
    z : ndarray, shape (k,)
        The fit's coordinates at the solution (theta itself without ``coordinates``).
    theta : ndarray, shape (p,)
        The model's parameters at the solution, ``to_theta(z)``.
    residual : ndarray, shape (M, 6)
        ``weight * (measured - F(theta))``: N times the weight's unit, before whitening.
    jacobian : ndarray, shape (M, 6, p)
        ``weight * dF/dtheta`` at theta (the derivative of minus ``residual``).
    cost : float
        Half the sum of squares of the fit's rows at the solution (whitened data rows and
        held rows).
    status : int
        ``least_squares``' status: 1-4 a tolerance was met (gtol, ftol, xtol, ftol and xtol);
        0 the evaluations ran out (also when none was allowed: the start is returned).
    nfev : int
        Evaluations of the forces (the derivative is evaluated at most as often).
    """

    z: np.ndarray
    theta: np.ndarray
    residual: np.ndarray
    jacobian: np.ndarray
    cost: float
    status: int
    nfev: int


@dataclass
class _Problem:
    """What ``fit`` evaluates, with the last derivative kept (see ``fit``)."""

    forces: Forces
    derivative: Derivative
    measured: np.ndarray
    weight: np.ndarray
    whiten: Callable[[np.ndarray], np.ndarray]
    to_theta: Callable[[np.ndarray], np.ndarray]
    dtheta: Callable[[np.ndarray], np.ndarray] | None
    held: tuple[np.ndarray, np.ndarray] | None
    z0: np.ndarray
    free: np.ndarray
    last: tuple[bytes, np.ndarray, np.ndarray] | None = None

    def coordinates(self, free_z: np.ndarray) -> np.ndarray:
        z = self.z0.copy()
        z[self.free] = free_z
        return z

    def at(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The weighted residual (M, 6) and weighted dF/dtheta (M, 6, p) at z."""
        key = z.tobytes()
        if self.last is None or self.last[0] != key:
            F, J = self.derivative(self.to_theta(z))
            self.last = (key, self.weight * (self.measured - F), J * self.weight[:, :, None])
        return self.last[1], self.last[2]

    def rows(self, free_z: np.ndarray) -> np.ndarray:
        z = self.coordinates(free_z)
        theta = self.to_theta(z)
        data = self.whiten((self.measured - self.forces(theta)) * self.weight).ravel()
        if self.held is None:
            return data
        matrix, reference = self.held
        return np.r_[data, matrix @ (theta - reference)]

    def rows_jacobian(self, free_z: np.ndarray) -> np.ndarray:
        z = self.coordinates(free_z)
        _, J = self.at(z)
        data = -self.whiten(J).reshape(-1, J.shape[2])
        D = None if self.dtheta is None else self.dtheta(z)
        if D is not None:
            data = data @ D
        if self.held is not None:
            data = np.vstack([data, self.held[0] if D is None else self.held[0] @ D])
        # row-major like the rows (a column selection would be column-major: another
        # rounding in least_squares' factorisations)
        return data if self.free.all() else np.ascontiguousarray(data[:, self.free])


def fit(forces: Forces, derivative: Derivative, measured: np.ndarray, start: np.ndarray,
        lower: np.ndarray, upper: np.ndarray, *, max_nfev: int, weight=1.0,
        whiten: Callable[[np.ndarray], np.ndarray] | None = None,
        coordinates: tuple[Callable, Callable] | None = None,
        held: tuple[np.ndarray, np.ndarray] | None = None,
        at_start: tuple[np.ndarray, np.ndarray] | None = None) -> Fit:
    """Fit the model's parameters to measured forces within bounds (see the module).

    Parameters
    ----------
    forces, derivative : callable
        The model on the measured rows: ``forces(theta)`` -> F (M, 6), N;
        ``derivative(theta)`` -> (F, dF/dtheta (M, 6, p)).
    measured : ndarray, shape (M, 6)
        Measured actuator forces, N.
    start, lower, upper : ndarray, shape (k,)
        The start and the bounds of the fit's coordinates; the start is clipped to the bounds
        and a coordinate whose bounds do not leave it room (lower >= upper) is held there.
    max_nfev : int
        Most evaluations of the forces; 0 returns the start.
    weight : float or ndarray broadcasting to (M, 6)
        Each row's weight (the inverse of its noise, or 0 to leave a row out).
    whiten : callable, optional
        A linear filter along time of arrays (M, 6, ...) -> (M', 6, ...), applied to the
        weighted residual and to each Jacobian column (default none).
    coordinates : (to_theta, dtheta), optional
        The fit's coordinates z when they are not theta: ``to_theta(z)`` -> theta (p,) and
        ``dtheta(z)`` -> dtheta/dz (p, k).
    held : (matrix (q, p), reference (p,)), optional
        Extra rows ``matrix @ (theta - reference)`` holding directions at the reference.
    at_start : (residual, jacobian), optional
        ``Fit.residual`` and ``Fit.jacobian`` at the start when known (spares an evaluation).

    Returns
    -------
    Fit
    """
    measured = np.asarray(measured, float)
    weight = np.broadcast_to(np.asarray(weight, float), measured.shape)
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    z0 = np.clip(np.asarray(start, float), lower, upper)
    to_theta, dtheta = coordinates if coordinates is not None else (lambda z: z, None)
    problem = _Problem(forces, derivative, measured, weight, whiten or (lambda a: a), to_theta,
                       dtheta, held, z0, lower < upper)
    if at_start is not None and np.array_equal(z0, start):
        problem.last = (z0.tobytes(), *at_start)
    if max_nfev == 0 or not problem.free.any():
        return _result(problem, z0, None, 0, 0)
    least_squares = optional("scipy.optimize").least_squares
    rows = max(0.5 * np.count_nonzero(weight), 1.0)
    free = problem.free
    sol = least_squares(problem.rows, z0[free], jac=problem.rows_jacobian,
                        bounds=(lower[free], upper[free]), method="trf", x_scale="jac",
                        max_nfev=max_nfev, ftol=COST_TOL / rows)
    return _result(problem, problem.coordinates(sol.x), float(sol.cost), int(sol.status),
                   int(sol.nfev))


def _result(problem: _Problem, z: np.ndarray, cost: float | None, status: int, nfev: int
            ) -> Fit:
    """The Fit at z (its cost computed when not given); the residual and Jacobian are the
    last derivative's when it was at z."""
    residual, jacobian = problem.at(z)
    theta = np.array(problem.to_theta(z), float)
    if cost is None:
        rows = problem.whiten(residual).ravel()
        if problem.held is not None:
            rows = np.r_[rows, problem.held[0] @ (theta - problem.held[1])]
        cost = 0.5 * float(rows @ rows)
    return Fit(z=z, theta=theta, residual=residual, jacobian=jacobian, cost=cost,
               status=status, nfev=nfev)
