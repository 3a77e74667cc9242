"""The uncertainty the differentiation of recorded poses leaves in the forces, and the steps
where a joint is possibly at rest.

Force uncertainty (``force_sigma``). The rates of a motion made from sampled poses carry one
standard deviation each (``Motion.rate_uncertainty``: velocity, omega, acceleration, alpha per
axis). F is linearised in them by central differences of the compiled actuator forces, one
rate at a time, over plus and minus its own standard deviation (at that scale, so that a
friction force that changes sign within it counts), and the contributions are added in
quadrature: the twelve rate errors are taken as independent (the pose noise as white and
independent between axes; a centred smoothing filter's first and second derivatives are
uncorrelated). The sensitivities change with the pose and the speed over the motion's own time
scale, not from step to step: they are computed every ``SIGMA_GRID_TIME`` of motion time (every
step of a log sampled more slowly) and interpolated linearly between, which keeps the cost a
fraction of the evaluation's.

Rest (``possibly_at_rest``). A leg whose differentiated speed is within ``REST_BAND`` standard
deviations of zero may be at rest: its friction is then static, anything between minus and
plus its Coulomb level, not the sliding value that the model applies with the speed's sign.
Such steps are marked per leg (the ``rest`` column of ``gsfric simulate``), not changed: the
forces stay the model's sliding values, and the mark says that the friction part of F may lie
anywhere within the Coulomb bound. The one rule for simulate, sweep and discover.
"""

from __future__ import annotations

import numpy as np

from gsfric.compiled.state import state_layout, state_of
from gsfric.trajectory import Motion

SIGMA_GRID_TIME = 0.1
"""Motion time, s, between the steps where F's sensitivities to the rates are computed
(``force_sigma``): a platform's motions (below about 2 Hz) change pose and speed little over
it, and at 1 kHz it costs a quarter of an evaluation of F per step."""

REST_BAND = 2.0
"""A leg whose speed is within this many standard deviations of zero is possibly at rest
(``possibly_at_rest``): a speed that is truly zero lies within it 95 % of the time."""


SPEED_ROUNDOFF = 100.0
"""Floor of a leg speed's standard deviation, in units of ``eps * reach / dt`` (float64's
relative resolution times the farthest platform joint from the base frame's origin, over the
median sample interval): the smallest speed that differentiated poses can resolve, with the
smoother's gain on round-off below this factor. A record free of noise (poses written exactly,
a platform held still) has a rate uncertainty of 0; without the floor its legs at rest, whose
speeds come out as round-off of about 1e-16 m/s, would not count as possibly at rest."""


def force_sigma(evaluator, motion: Motion, start: int = 0) -> np.ndarray | None:
    """One standard deviation of each actuator force from the differentiation, (N, 6), N (see
    the module's docstring); None for a motion without ``rate_uncertainty`` or an evaluator in
    paper mode (whose accelerations are constants).

    The sensitivities are computed at the steps whose index in the record (``start`` + the
    index in ``motion``: a piece of a longer record) is a multiple of the grid's stride, and at
    every step before the first and after the last of them: a record evaluated in pieces gets
    the values of the whole, but for the steps between a piece's last grid step and its end,
    computed there rather than interpolated (they differ by the interpolation's error)."""
    uncertainty = motion.rate_uncertainty()
    n = len(motion)
    if uncertainty is None or evaluator.mode != "kinematic" or n == 0:
        return None
    t = np.asarray(motion.t, float)
    step = (t[-1] - t[0]) / (n - 1) if n > 1 else SIGMA_GRID_TIME
    stride = max(1, int(SIGMA_GRID_TIME / step)) if step > 0 else 1
    grid = np.arange((-int(start)) % stride, n, stride)
    if len(grid):
        grid = np.r_[np.arange(grid[0]), grid, np.arange(grid[-1] + 1, n)]
    else:
        grid = np.arange(n)
    x = state_of((motion.position[grid], motion.rotation[grid], motion.velocity[grid],
                  motion.omega[grid], motion.acceleration[grid], motion.alpha[grid]))
    sigma = uncertainty.slice(grid).stacked()                              # (G, 12)
    g, layout = len(grid), state_layout()
    columns = np.concatenate([np.arange(layout.size)[part] for part in (
        layout.velocity, layout.omega, layout.acceleration, layout.alpha)])   # sigma's order
    states = np.repeat(x[None], 2 * len(columns), axis=0)                  # (24, G, 24)
    for k, column in enumerate(columns):
        states[2 * k, :, column] += sigma[:, k]
        states[2 * k + 1, :, column] -= sigma[:, k]
    F = evaluator.actuator_forces(states.reshape(-1, layout.size), out=np.empty((24 * g, 6)))
    F = F.reshape(12, 2, g, 6)
    at_grid = np.sqrt(np.sum(((F[:, 0] - F[:, 1]) / 2.0) ** 2, axis=0))  # (G, 6)
    return at_grid if g == n else _interpolated(grid, at_grid, stride, n)


def _interpolated(grid: np.ndarray, values: np.ndarray, stride: int, n: int) -> np.ndarray:
    """``values`` (G, 6) at the steps ``grid`` (every step up to the first multiple of
    ``stride``, every ``stride``-th step, every step after the last) linearly interpolated at
    the steps 0..n-1, (n, 6): the evenly strided part in one broadcast."""
    out = np.empty((n, values.shape[1]))
    out[grid] = values
    strided = np.flatnonzero(np.diff(grid) == stride)
    if len(strided):
        first, last = strided[0], strided[-1] + 1         # grid indices of the strided run
        lo, hi = grid[first], grid[last]
        left, right = values[first:last], values[first + 1:last + 1]    # (K, 6) each
        weight = (np.arange(stride) / stride)[None, :, None]            # (1, stride, 1)
        block = out[lo:hi].reshape(last - first, stride, -1)
        np.multiply(right[:, None, :] - left[:, None, :], weight, out=block)
        block += left[:, None, :]
    return out


def leg_speed_sigma(platform, motion: Motion) -> np.ndarray | None:
    """An upper bound of one standard deviation of each leg's speed from the differentiation,
    (N, 6), m/s, or None (no ``rate_uncertainty``).

    The leg speed is ``u . v + (r x u) . omega`` (u the leg's unit vector, r its platform
    joint from the platform's origin, base frame); with |u| = 1 and |r x u| <= |r|, its
    variance is at most ``max_k sigma_v,k^2 + |r|^2 max_k sigma_omega,k^2``."""
    uncertainty = motion.rate_uncertainty()
    if uncertainty is None:
        return None
    radius = np.linalg.norm(np.asarray(platform.geometry.platform_joints, float), axis=1)
    v, w = uncertainty.velocity, uncertainty.omega
    v2 = np.maximum(np.maximum(v[:, 0], v[:, 1]), v[:, 2]) ** 2
    w2 = np.maximum(np.maximum(w[:, 0], w[:, 1]), w[:, 2]) ** 2
    sigma = np.sqrt(v2[:, None] + radius[None, :] ** 2 * w2[:, None])
    return np.maximum(sigma, _speed_floor(radius, motion))


def _speed_floor(radius: np.ndarray, motion: Motion) -> float:
    """The smallest leg speed, m/s, that the motion's differentiated poses resolve
    (``SPEED_ROUNDOFF``)."""
    t = np.asarray(motion.t, float)
    if len(t) < 2:
        return 0.0
    reach = float(np.max(np.linalg.norm(motion.position, axis=1)) + np.max(radius))
    return SPEED_ROUNDOFF * np.finfo(float).eps * reach / float(np.median(np.diff(t)))


def possibly_at_rest(speed: np.ndarray, sigma: np.ndarray, band: float = REST_BAND
                     ) -> np.ndarray:
    """(N, 6) True where a joint's speed (N, 6) is within ``band`` of its standard deviations
    ``sigma`` ((N, 6) or (6,)) of zero: possibly at rest, its friction bounded by the Coulomb
    level rather than the sliding value."""
    speed = np.asarray(speed, float)
    return np.abs(speed) <= band * np.broadcast_to(np.asarray(sigma, float), speed.shape)


def rest_legs(at_rest: np.ndarray) -> np.ndarray:
    """The legs possibly at rest (N, 6) bool as one number per step (N,) uint8: the sum of
    ``2**(i - 1)`` over the legs i (1..6) possibly at rest (0: every leg slides)."""
    return np.packbits(np.asarray(at_rest, bool), axis=1, bitorder="little")[:, 0]



def leg_speeds(platform, motion: Motion) -> np.ndarray:
    """Each leg's speed (N, 6), m/s: ``u . (v + omega x r)``, r = R e_i the platform joint from
    the platform's origin and u the unit vector from the base joint c_i to it (base frame): the
    ``D_dot`` of an evaluation, without one."""
    e = np.asarray(platform.geometry.platform_joints, float)
    c = np.asarray(platform.geometry.base_joints, float)
    r = np.einsum("njk,ik->nij", motion.rotation, e)                       # (N, 6, 3)
    leg = r + motion.position[:, None, :] - c[None]
    u = leg / np.linalg.norm(leg, axis=2, keepdims=True)
    joint = motion.velocity[:, None, :] + np.cross(motion.omega[:, None, :], r)
    return np.einsum("nij,nij->ni", u, joint)


def steps_at_rest(platform, motion: Motion) -> int:
    """Steps of ``motion`` with a leg possibly at rest (``possibly_at_rest``), 0 for a motion
    without ``rate_uncertainty``."""
    sigma = leg_speed_sigma(platform, motion)
    if sigma is None:
        return 0
    return int(np.count_nonzero(possibly_at_rest(leg_speeds(platform, motion), sigma)
                                .any(axis=1)))
