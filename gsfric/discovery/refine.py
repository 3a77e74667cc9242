"""Fitting a chosen model on the compiled model: the refinement within bounds, the global
profile of a delay, and the stability of a named effect across the record's halves."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsfric._optional import optional
from gsfric.discovery import statistics as st
from gsfric.discovery.evidence import Evidence, Rule, accept
from gsfric.discovery.pvalues import chi2_sf
from gsfric.discovery.residuals import DELAY, Problem
from gsfric.evaluation.fitting import fit
from gsfric.platform.catalog import shift

# -- refinement on the compiled model -----------------------------------------------------------


@dataclass(frozen=True)
class Refined:
    """Parameters fitted on the compiled model, and the residual and derivatives there.

    Attributes
    ----------
    theta : ndarray, shape (n_theta,)
        Every parameter of the compiled model (``ParametricModel.index``).
    names : tuple of str
        The parameters fitted (Jacobian parameters).
    r : ndarray, shape (M, 6)
        Residual ``F_measured - F_model`` at theta over the used samples, N; zero at the
        (sample, leg) pairs not known to slide.
    J : ndarray, shape (M, 6, len(names))
        Derivatives of F with respect to ``names`` at theta, times the sliding weight.
    """

    theta: np.ndarray
    names: tuple[str, ...]
    r: np.ndarray
    J: np.ndarray


def refine(problem: Problem, theta: np.ndarray, names: list[str], whitener: st.Whitener,
           start: tuple[np.ndarray, np.ndarray] | None = None
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The named parameters fitted within their bounds to the prewhitened residual
    (``evaluation.fitting.fit``: the sliding pairs weighted 1, the others 0; at most
    ``Settings.gauss_newton`` evaluations), after the delay's global profile when
    ``time_offset.delay`` is among them.

    ``start``, if given, is the residual (M, 6) and Jacobian (M, 6, k) at theta (which must
    lie within the bounds). Returns theta, the residual and the Jacobian at the result.
    """
    model = problem.model
    cols = [model.index[n] for n in names]
    lo = np.array([problem.bounds(n)[0] for n in names])
    hi = np.array([problem.bounds(n)[1] for n in names])
    theta = theta.copy()
    inside = bool(np.all((theta[cols] >= lo) & (theta[cols] <= hi)))
    theta[cols] = np.clip(theta[cols], lo, hi)
    if DELAY in names:
        profiled = delay_profile(problem, theta, names, whitener)
        if profiled.theta is not None:
            theta, inside = profiled.theta, False

    def at(x: np.ndarray) -> np.ndarray:
        full = theta.copy()
        full[cols] = x
        return full

    def derivative(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        F, J = model.jacobian(at(x), names, rows=problem.used)
        return F[problem.used], J

    result = fit(lambda x: model.forces(at(x))[problem.used], derivative, problem.y,
                 theta[cols], lo, hi, max_nfev=problem.settings.gauss_newton,
                 weight=problem.weight, whiten=whitener.apply,
                 at_start=start if start is not None and inside else None)
    return at(result.theta), result.residual, result.jacobian


@dataclass
class DelayProfile:
    """The global estimate of ``time_offset.delay`` (``delay_profile``).

    Attributes
    ----------
    theta : ndarray or None
        The parameters at the profile's minimum, the others stepped by their linear refit;
        None when the current delay is already best.
    delay : float
        The delay at the minimum (the current one when ``theta`` is None), s.
    sse, sse_current : float
        Prewhitened residual sums of squares at ``delay`` and at the current delay.
    delays, profile : ndarray, shape (n,)
        The coarse grid of delays, s, and its sums of squares.
    """

    theta: np.ndarray | None
    delay: float
    sse: float
    sse_current: float
    delays: np.ndarray
    profile: np.ndarray


def delay_profile(problem: Problem, theta: np.ndarray, names: list[str],
                  whitener: st.Whitener) -> DelayProfile:
    """The profile of the prewhitened residual sum of squares over ``time_offset.delay``, the
    other parameters of ``names`` refitted linearly at each delay.

    F depends on the delay only through a shift of the model's forces in time (``catalog``:
    linear interpolation), which moves friction steps and load peaks by whole samples: the
    sum of squares is a rough, many-valleyed function of the delay, and a Gauss-Newton step
    from a secant's estimate stops in the nearest valley while the refitted viscous friction
    and masses take over part of the shifted force. Here the forces and the derivatives of the
    other parameters are computed once at zero delay and shifted, so each point of the
    profile costs a shift and a small bounded least-squares fit: a coarse grid of
    ``Settings.delay_grid`` steps (at least one sample) over +-``Settings.delay_range``, then a
    bounded scalar search within one grid step either side of the best point; the current value
    is kept unless the profile's minimum is lower.
    """
    j = problem.model.index[DELAY]
    others = [n for n in names if n != DELAY]
    cols = [problem.model.index[n] for n in others]
    value = _refitted_sse(problem, theta, others, whitener)
    t = problem.model.t
    span = min(problem.settings.delay_range, 0.25 * float(t[-1] - t[0]))
    d_lo, d_hi = problem.bounds(DELAY)
    d_lo, d_hi = max(d_lo, -span), min(d_hi, span)
    dt = float(np.median(np.diff(t)))
    h = max(dt, (d_hi - d_lo) / problem.settings.delay_grid)
    delays = np.arange(d_lo, d_hi + 0.5 * h, h)
    current = float(theta[j])
    profile = np.array([value(float(d))[0] for d in delays])
    best = float(delays[int(np.argmin(profile))])
    minimize_scalar = optional("scipy.optimize").minimize_scalar   # only a delay needs it
    found = minimize_scalar(lambda d: value(d)[0], bounds=(max(d_lo, best - h),
                                                           min(d_hi, best + h)),
                            method="bounded", options={"xatol": 1e-3 * dt})
    candidates = [(float(profile.min()), best), (float(found.fun), float(found.x))]
    sse_current = value(current)[0]
    sse_best, delay = min(candidates)
    if not sse_best < sse_current:
        return DelayProfile(None, current, sse_current, sse_current, delays, profile)
    _, step = value(delay)
    new = theta.copy()
    new[j] = delay
    # within the bounds exactly (the step's bounds were relative to theta: rounding)
    bounds = np.array([problem.bounds(n) for n in others]).reshape(-1, 2)
    new[cols] = np.clip(theta[cols] + step, bounds[:, 0], bounds[:, 1])
    return DelayProfile(new, delay, sse_best, sse_current, delays, profile)


def _refitted_sse(problem: Problem, theta: np.ndarray, others: list[str],
                  whitener: st.Whitener):
    """``value(d)``: the prewhitened sum of squares at delay ``d`` with the ``others``
    refitted linearly within their bounds, and their step from ``theta``; the forces and
    derivatives at zero delay are computed once, then shifted."""
    model = problem.model
    cols = [model.index[n] for n in others]
    lo = np.array([problem.bounds(n)[0] for n in others]) - theta[cols]
    hi = np.array([problem.bounds(n)[1] for n in others]) - theta[cols]
    at_zero = theta.copy()
    at_zero[model.index[DELAY]] = 0.0
    F, J = model.jacobian(at_zero, others)
    n, k = len(model.t), len(others)
    FJ = np.concatenate([F[:, :, None], J], axis=2).reshape(n, -1)
    del F, J
    used, weight, t = problem.used, problem.weight, model.t
    ridge = problem.settings.ridge

    def value(d: float) -> tuple[float, np.ndarray]:
        moved = shift(t, FJ, d)[used].reshape(-1, 6, k + 1)
        r = problem.mask(problem.y - moved[:, :, 0])
        X = moved[:, :, 1:] * weight[:, :, None]
        A, b, c, _ = st.Blocks.whitened(whitener, X, r, 1, ridge=ridge).total()
        step = st.solve(A, b, lo, hi, ridge=ridge)
        return st.sse(A, b, c, step), step

    return value


# -- stability of a named effect across the halves of the record --------------------------------


@dataclass
class Stability:
    """A named effect across the halves of the record (``half_stability``).

    Attributes
    ----------
    p_value : float
        Wald test of the difference of the effect's parameters between the halves.
    change : float
        RMS change of F between the halves over the RMS of the final residual.
    half_steps : list of dict[str, float]
        The effect's parameters fitted on each half, as steps from the final values.
    stable : bool
        Not both significant and at least ``Settings.stability_min_change``.
    """

    p_value: float
    change: float
    half_steps: list[dict[str, float]]
    stable: bool


def half_stability(problem: Problem, J: np.ndarray, r: np.ndarray, names: list[str],
                   effect: str, whitener: st.Whitener) -> Stability:
    """Is the effect the same in both halves of the record?

    A physical effect has one value of its parameters over the record; a catalog term that
    imitates an error outside the catalog (per-leg offsets standing in for a nonlinear load
    cell, a delay standing in for a ringing mode) fits whatever that error looks like on each
    stretch of motion, and the stretches differ. The model, linearised at the final
    parameters (J (M, 6, k) with respect to ``names``, residual r (M, 6)), is fitted on the
    first and on the second half of the blocks separately, every parameter free; the
    difference of the effect's parameters is tested by a Wald test (chi-square, the two halves'
    prewhitened covariances summed), and its size is the RMS change of F it makes (N, plain,
    sliding pairs) over the RMS of the final residual.

    Returns
    -------
    Stability
    """
    s = problem.settings
    cols = [k for k, n in enumerate(names) if n.startswith(effect + ".")]
    if not cols or J.shape[2] == 0:
        return Stability(1.0, 0.0, [], True)
    blocks = st.Blocks.whitened(whitener, J, r, s.n_blocks, ridge=s.ridge)
    half = len(blocks.ztz) // 2
    k = J.shape[2]
    est = []
    for g in (slice(0, half), slice(half, None)):
        A, b, c = blocks.held(g)
        rows = float(blocks.rows[g].sum())
        inv = np.linalg.pinv(A)
        delta = inv @ b
        s2 = max(c - 2 * delta @ b + delta @ A @ delta, 0.0) / max(rows - k, 1.0)
        est.append((delta, s2 * inv))
    d = est[0][0][cols] - est[1][0][cols]
    V = est[0][1][np.ix_(cols, cols)] + est[1][1][np.ix_(cols, cols)]
    W = float(d @ np.linalg.pinv(V) @ d)
    p = chi2_sf(W, len(cols))
    sliding = problem.sliding
    change_f = J[:, :, cols] @ d
    left = float(np.sqrt(np.mean(r[sliding] ** 2)))
    change = float(np.sqrt(np.mean(change_f[sliding] ** 2))) / max(left, 1e-300)
    steps = [{names[j].split(".", 1)[1]: float(e[0][j]) for j in cols} for e in est]
    stable = not accept(Evidence(p, gap=change), Rule(s.alpha, min_gap=s.stability_min_change))
    return Stability(p, change, steps, bool(stable))
