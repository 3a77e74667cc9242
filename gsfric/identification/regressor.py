"""The model's actuator forces as functions of the estimated parameters, their Jacobian (the
regressor), and what the Jacobian's rank says can be identified.

The regressor's columns come from the compiled ``jacobian`` function where it has the
parameter (friction coefficients, effects, load-cell offsets), from the load cells' gains
directly (``d F_i / d g_i = F_i``), and otherwise from central differences of the compiled
forces (the inertial parameters): F is affine in those up to the friction they load, so a
central difference is exact for the rigid-body part and second-order accurate for the rest,
and it needs no derivative code beyond the compiled model (``settings.FD_RSTEP``).

``structure`` finds the identifiable directions from the singular values of the
column-normalised, noise-weighted regressor (``settings.RANK_RTOL``) and the base parameters
(the identifiable combinations) from a QR decomposition with column pivoting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsfric.evaluation.evaluator import Evaluator
from gsfric.identification.parameters import ParameterSet
from gsfric.identification.settings import FD_RSTEP, MIXED_TOL, RANK_RTOL, TYPICAL, ZERO_RTOL
from gsfric.platform.catalog import apply_sensor, sensor_parameters


class Model:
    """The actuator forces of a parameter set's platform along fixed states.

    Parameters
    ----------
    ps : ParameterSet
    x : ndarray, shape (N, 24)
        States (``gsfric.evaluation.state_array``).
    t : ndarray, shape (N,)
        Times, s (for a load cell's delay, ``time_offset``).
    """

    def __init__(self, ps: ParameterSet, x: np.ndarray, t: np.ndarray) -> None:
        self.ps, self.x, self.t = ps, np.ascontiguousarray(x, float), np.asarray(t, float)
        self.evaluator = Evaluator(ps.platform)
        self.delay = sensor_parameters(ps.platform.effects)[1]

    def forces(self, theta: np.ndarray) -> np.ndarray:
        """What the load cells read, (N, 6) N, for parameters theta (p,)."""
        P, Q, gains = self.ps.inputs(theta)
        F = self.evaluator.actuator_forces(self.x, P=P, Q=Q)
        return apply_sensor(self.t, F, gains, self.delay)

    def jacobian(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """F (N, 6) N and dF/dtheta (N, 6, p), each column in N per unit of its parameter."""
        ps = self.ps
        P, Q, gains = ps.inputs(theta)
        raw = apply_sensor(self.t, self.evaluator.actuator_forces(self.x, P=P, Q=Q),
                           np.zeros(6), self.delay)          # delayed, before the gains
        F = raw * (1.0 + gains)
        J = np.empty(F.shape + (len(theta),))
        compiled = [k for k, p in enumerate(ps.parameters) if p.jacobian is not None]
        if compiled:
            _, dF = self.evaluator.jacobian(self.x, Q=Q, P=P)
            for k in compiled:
                J[:, :, k] = apply_sensor(self.t, dF[:, :, ps.parameters[k].jacobian], gains,
                                          self.delay)
        for k, p in enumerate(ps.parameters):
            if p.kind == "gain":
                J[:, :, k] = 0.0
                J[:, p.key, k] = raw[:, p.key]
            elif p.jacobian is None:
                J[:, :, k] = self._difference(theta, k)
        return F, J

    def _difference(self, theta: np.ndarray, k: int) -> np.ndarray:
        """dF/dtheta_k by a central difference (one-sided at a lower bound), (N, 6)."""
        p = self.ps.parameters[k]
        h = FD_RSTEP * max(abs(theta[k]), TYPICAL.get(p.unit, 1.0))
        up, down = theta.copy(), theta.copy()
        up[k] += h
        if theta[k] - h >= p.lower:
            down[k] -= h
            return (self.forces(up) - self.forces(down)) / (2 * h)
        return (self.forces(up) - self.forces(theta)) / h


@dataclass
class Structure:
    """What a weighted regressor can identify.

    Attributes
    ----------
    rank : int
        Number of identifiable directions (base parameters).
    scales : ndarray, shape (p,)
        Norm of each weighted column (0 for a parameter that does not act).
    idle : ndarray of bool, shape (p,)
        Parameters that do not act on the forces along this motion (``ZERO_RTOL``).
    null : ndarray, shape (p, p - rank)
        Basis of the directions the data do not reach, in column-normalised coordinates.
    identifiable : ndarray of bool, shape (p,)
        Parameters identifiable on their own (``MIXED_TOL``).
    singular : ndarray, shape (p,)
        Singular values of the column-normalised regressor, descending.
    condition : float
        Condition number of the column-normalised regressor restricted to its rank (the base
        regressor's): largest over smallest kept singular value.
    independent : list of int
        Parameters chosen by the pivoted QR as the base parameters' leading ones.
    combinations : dict[int, ndarray]
        For an independent parameter that is not identifiable alone: the coefficients (p,),
        in each parameter's own unit per unit of the leading one, of the identifiable
        combination it leads (``theta @ coefficients``).
    """

    rank: int
    scales: np.ndarray
    idle: np.ndarray
    null: np.ndarray
    identifiable: np.ndarray
    singular: np.ndarray
    condition: float
    independent: list
    combinations: dict


def structure(J: np.ndarray, weights: np.ndarray, units: list[str]) -> Structure:
    """The identifiable directions of a regressor ``J`` (N, 6, p) whose rows of leg j are
    weighted by ``weights[j]`` (1/N, the inverse noise)."""
    from scipy.linalg import qr, solve_triangular

    A = (J * weights[None, :, None]).reshape(-1, J.shape[2])
    scales = np.linalg.norm(A, axis=0)
    typical = np.array([TYPICAL.get(u, 1.0) for u in units])
    idle = scales * typical <= ZERO_RTOL * max(float(np.max(scales * typical)), 1e-300)
    live = np.flatnonzero(~idle)
    R0 = np.linalg.qr(A[:, live] / scales[live], mode="r")
    _, s, Vt = np.linalg.svd(R0)
    rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size else 0
    p = J.shape[2]
    null = np.zeros((p, p - rank))
    null[live, : len(live) - rank] = Vt[rank:].T
    for n, k in enumerate(np.flatnonzero(idle)):
        null[k, len(live) - rank + n] = 1.0
    identifiable = ~idle & (np.linalg.norm(null, axis=1) < MIXED_TOL)
    _, R, piv = qr(R0, pivoting=True)
    independent = [int(live[i]) for i in piv[:rank]]
    combinations = {}
    if rank < len(live):
        B = solve_triangular(R[:rank, :rank], R[:rank, rank:])
        for row, i in enumerate(independent):
            if identifiable[i]:
                continue
            coef = np.zeros(p)
            coef[i] = 1.0
            for col, d in enumerate(piv[rank:]):
                coef[live[d]] = B[row, col] * scales[live[d]] / scales[i]
            combinations[i] = coef
    singular = np.zeros(p)
    singular[: s.size] = s
    condition = float(s[0] / s[rank - 1]) if rank else float("inf")
    return Structure(rank, scales, idle, null, identifiable, singular, condition, independent,
                     combinations)


def covariance(J: np.ndarray, weights: np.ndarray, st: Structure) -> np.ndarray:
    """Covariance (p, p) of theta on the identifiable directions (zero along the null space):
    ``(J^T W J)^+`` restricted to the row space, for rows weighted by ``weights`` (1/N)."""
    A = (J * weights[None, :, None]).reshape(-1, J.shape[2])
    scales = np.where(st.scales > 0, st.scales, 1.0)
    R0 = np.linalg.qr(A / scales, mode="r")
    _, s, Vt = np.linalg.svd(R0)
    V = Vt[: st.rank].T
    cov = (V / s[: st.rank] ** 2) @ V.T
    return cov / np.outer(scales, scales)
