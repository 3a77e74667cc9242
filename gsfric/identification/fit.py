"""Weighted nonlinear least squares of the parameters on measured actuator forces.

The residual is the measured minus the model's forces, each leg's rows weighted by the inverse
of its noise (given, or estimated from the first fit's residual and the fit repeated). The fit
starts from the linear weighted least-squares estimate on the regressor at the prior. The
unknowns are the body's log-Cholesky coordinates (``parameters.body_from_factor``: consistent
by construction) and every other parameter within its bounds (``evaluation.fitting.fit``:
``scipy.optimize.least_squares``, trust-region reflective, on the regressor of
``regressor.Model``). Directions the data do not reach (the regressor's null space at the
prior, ``regressor.structure``) are held at the prior's values by extra residual rows as stiff
as the best-determined direction: they leave the identifiable directions free and make the
solution unique.
"""

from __future__ import annotations

import warnings
from functools import partial

import numpy as np

from gsfric._checks import as_array, as_flag, short
from gsfric.errors import GsfricWarning, InputError, InputTypeError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import check_flagged, flag_counts
from gsfric.evaluation.fitting import fit
from gsfric.identification.parameters import (ParameterSet, body_from_factor, consistent,
                                              factor_bounds, factor_of_body,
                                              nearest_consistent, parameter_set)
from gsfric.identification.regressor import Model, Structure, covariance, structure
from gsfric.identification.results import (Combination, Estimate, Identification, Validation,
                                           moved)
from gsfric.identification.settings import (IMPLAUSIBLE_SIGMA, MAX_NFEV, MISFIT_RATIO,
                                            PRIOR_LOAD_RATIO, TYPICAL, WEAK_RELATIVE_STD)
from gsfric.models import check_measured_forces, platform_from
from gsfric.platform.description import Platform
from gsfric.platform.usable import check_force_channels, check_force_sign
from gsfric.signal.noise import (HIGH_FREQUENCY_WINDOW, PLAUSIBLE_SPREAD, ForceNoise,
                                 high_frequency_std)
from gsfric.trajectory import Motion

HINTS = (
    ("platform.inertia_origin", "rotations with angular accelerations about all three axes "
                                "(roll, pitch and yaw)"),
    ("platform.first_moment", "tilts (roll, pitch) and angular accelerations, so that the "
                              "centre of mass's offset changes the legs' loads"),
    ("platform.mass", "vertical accelerations (heave) or poses that load the legs differently"),
    ("legs.", "leg-length changes at varying speeds and accelerations, and tilts"),
    ("friction.prismatic_viscous", "faster leg motion: the viscous force grows with the leg "
                                   "speed (excite --max-speed, within the actuators' limit)"),
    ("friction.joint_viscous", "faster rotations of the joints: the viscous moment grows with "
                               "the joint rate (excite --max-speed, within the actuators' "
                               "limit)"),
    ("friction.", "every leg moving in both directions at several speeds, under varying load"),
    ("effects.sensor_bias", "poses that change each leg's load"),
    ("effects.force_scale", "poses and accelerations that change each leg's load by a large "
                            "fraction of it"),
    ("effects.", "motion over the range where the effect acts (its speeds, strokes, loads)"),
)
"""What motion reaches a parameter, by the start of its name."""

MASSES = ("platform.mass", "legs.lower_mass", "legs.upper_mass")


def identify(motion: Motion, forces: np.ndarray, platform: Platform | str | None = None, *,
             sensors: bool = False, force_noise=None) -> Identification:
    """Identify a platform's parameters from a motion and the actuator forces measured along it.

    Parameters
    ----------
    motion : Motion
        N steps (``gsfric.read_measured``).
    forces : ndarray, shape (N, 6)
        Measured actuator forces F1..F6, N.
    platform : Platform, path or None
        The prior: its values start the fit and hold what the data cannot reach (default the
        reference platform).
    sensors : bool
        Also estimate the load cells' offsets (``effects.sensor_bias``) and gains
        (``effects.force_scale``).
    force_noise : float, sequence of 6 floats or ForceNoise, optional
        The load cells' noise (standard deviation, N; ``--force-noise``), plausible against
        each measured channel's spread (``gsfric.signal.noise.PLAUSIBLE_SPREAD``, as
        ``discover`` checks it); default: estimated from the residual.

    Returns
    -------
    Identification

    Raises
    ------
    InputError
        Forces of the wrong shape or not finite; a motion that identifies nothing.

    Examples
    --------
    >>> import gsfric
    >>> from gsfric.synth import synthesize
    >>> data = synthesize(samples=1000, rate=200.0, noise=0.5, seed=1)
    >>> result = gsfric.identify(data.motion, data.frame.filter(regex="^F").to_numpy())
    >>> result.rank == len(result.parameters), result.platform.platform.mass > 0
    (True, True)
    """
    if not isinstance(motion, Motion):
        raise InputTypeError(f"identify: motion must be a gsfric.Motion, got {short(motion)} "
                             "(gsfric.read_measured)")
    prior = platform_from(platform)
    forces = np.array(as_array(forces, (len(motion), 6), "forces"))
    ps = parameter_set(prior, sensors=as_flag(sensors, "sensors"))
    given = None if force_noise is None else _given_noise(force_noise, forces)
    weights = np.ones(6) if given is None else 1.0 / given
    check_force_channels(motion.t, forces)
    check_measured_forces(prior, motion, forces, limit=PRIOR_LOAD_RATIO)
    keep = unflagged_steps(prior, motion)
    model, forces = Model(ps, state_array(motion)[keep], motion.t[keep]), forces[keep]
    F0, J0 = model.jacobian(ps.prior)
    st0 = structure(J0, weights, ps.units)
    if st0.rank == 0:
        raise InputError("the motion identifies no parameter: " + "; ".join(
            _unreachable(ps, st0)))
    linear = ps.prior + _step(J0, weights, st0, forces - F0)
    z, nfev = _solve(model, ps, st0, weights, forces, start=_start(ps, linear))
    if given is None:
        weights = 1.0 / _noise(forces - model.forces(_theta(ps, z)), st0.rank)
        z, more = _solve(model, ps, structure(J0, weights, ps.units), weights, forces, start=z)
        nfev += more
    return _result(model, ps, _theta(ps, z), forces, weights, given, nfev,
                   flagged=int(np.count_nonzero(~keep)))


def unflagged_steps(platform: Platform, motion: Motion, where: str = "") -> np.ndarray:
    """The steps (N,) bool that the model of ``platform`` does not flag along ``motion``: the
    forces of a flagged one (a leg outside the stroke, near a singularity, the coupled solve
    not converged) are not the model's to fit. An ``InputError`` (prefixed ``where``, a file)
    when most are flagged (``evaluation.flags.check_flagged``, as ``discover`` refuses such a
    record)."""
    flag = Evaluator(platform).evaluate_quiet(motion).flag
    check_flagged(platform, flag_counts(flag), int(np.count_nonzero(flag)), len(flag), where)
    return flag == 0


def _step(J: np.ndarray, weights: np.ndarray, st: Structure, residual: np.ndarray
          ) -> np.ndarray:
    """The Gauss-Newton step (p,) on the identifiable directions for a residual (N, 6): the
    linear weighted least-squares estimate from the regressor (the rigid-body part of F is
    linear in the inertial parameters), the nonlinear fit's start."""
    A = (J * weights[None, :, None]).reshape(-1, J.shape[2])
    return covariance(J, weights, st) @ (A.T @ (residual * weights).ravel())


def _given_noise(value, forces: np.ndarray) -> np.ndarray:
    """The load cells' noise (6,) N of one value or six (``ForceNoise.specified``), plausible
    against each measured channel's spread (``PLAUSIBLE_SPREAD``); InputError otherwise."""
    noise = value if isinstance(value, ForceNoise) else ForceNoise.specified(value)
    noise.check_plausible(forces, PLAUSIBLE_SPREAD)
    return np.broadcast_to(np.asarray(noise.std, float), (6,)).copy()


def _noise(residual: np.ndarray, rank: int) -> np.ndarray:
    """Each leg's noise standard deviation (6,) N from a residual (N, 6), for a fit of ``rank``
    directions (shared by the six legs)."""
    n = len(residual)
    dof = max(n - rank / 6.0, 1.0)
    return np.maximum(np.sqrt(np.sum(residual ** 2, axis=0) / dof), 1e-12)


def _coordinates(ps: ParameterSet) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the body's parameters in theta, and of the others."""
    kinds = np.array([p.kind for p in ps.parameters])
    return np.flatnonzero(kinds == "body"), np.flatnonzero(kinds != "body")


def _theta(ps: ParameterSet, z: np.ndarray) -> np.ndarray:
    """theta of the fit's coordinates z (the body's first, log-Cholesky)."""
    body, rest = _coordinates(ps)
    theta = np.empty(len(ps.parameters))
    theta[body] = body_from_factor(z[: body.size])
    theta[rest] = z[body.size:]
    return theta


def _dtheta(ps: ParameterSet, z: np.ndarray) -> np.ndarray:
    """d theta / d z (p, p): the body block by central differences of its (cheap) map."""
    body, rest = _coordinates(ps)
    D = np.zeros((len(ps.parameters), len(z)))
    D[rest, body.size + np.arange(rest.size)] = 1.0
    for k in range(body.size):
        h = 1e-6 * max(1.0, abs(z[k]))
        up, down = z[: body.size].copy(), z[: body.size].copy()
        up[k] += h
        down[k] -= h
        D[body, k] = (body_from_factor(up) - body_from_factor(down)) / (2 * h)
    return D


def _start(ps: ParameterSet, theta: np.ndarray) -> np.ndarray:
    """The fit's coordinates of theta; a body that is not consistent, or too nearly singular
    for its Cholesky factor, starts from the nearest consistent one."""
    body, rest = _coordinates(ps)
    pi = theta[body]
    try:
        if not consistent(pi):
            raise np.linalg.LinAlgError
        factor = factor_of_body(pi)
    except np.linalg.LinAlgError:
        factor = factor_of_body(nearest_consistent(pi))
    lower, upper = ps.bounds()
    return np.r_[factor, np.clip(theta[rest], lower[rest], upper[rest])]


def _solve(model: Model, ps: ParameterSet, st: Structure, weights: np.ndarray,
           forces: np.ndarray, start: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """The fit's coordinates z (from ``start``, else the prior's) minimising the weighted
    residual, null directions held at the prior (``evaluation.fitting.fit``); and the
    residual evaluations."""
    body, rest = _coordinates(ps)
    lower, upper = ps.bounds()
    body_lower, body_upper = factor_bounds()
    lb = np.r_[body_lower[: body.size], lower[rest]]
    ub = np.r_[body_upper[: body.size], upper[rest]]
    typical = np.array([TYPICAL.get(u, 1.0) for u in ps.units])
    reference = float(np.max(st.scales * typical))
    d = np.where(st.idle, reference / typical, st.scales)
    pin = st.singular[0] * (st.null.T * d)        # (p - rank, p), rows on theta - prior
    z0 = _start(ps, ps.prior) if start is None else start
    solution = fit(model.forces, model.jacobian, forces, z0, lb, ub, max_nfev=MAX_NFEV,
                   weight=weights, coordinates=(partial(_theta, ps), partial(_dtheta, ps)),
                   held=(pin, ps.prior))
    return solution.z, solution.nfev


def _result(model: Model, ps: ParameterSet, theta: np.ndarray, forces: np.ndarray,
            weights: np.ndarray, given, nfev: int, flagged: int = 0) -> Identification:
    """The Identification at the solution theta (``flagged`` steps left out of the fit)."""
    F, J = model.jacobian(theta)
    residual = forces - F
    noise = _noise(residual, 0) if given is None else given
    st = structure(J, 1.0 / noise, ps.units)
    cov = covariance(J, 1.0 / noise, st)
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    estimates = {}
    for k, p in enumerate(ps.parameters):
        ok = bool(st.identifiable[k])
        estimates[p.name] = Estimate(float(theta[k]), float(std[k]) if ok else None, p.unit,
                                     ok, float(ps.prior[k]))
    combinations = {}
    for i, coef in st.combinations.items():
        keep = {ps.names[k]: float(c) for k, c in enumerate(coef) if abs(c) > 1e-9}
        combinations[_expression(keep)] = Combination(
            float(coef @ theta), float(np.sqrt(max(coef @ cov @ coef, 0.0))),
            ps.parameters[i].unit, keep)
    ident = np.flatnonzero(st.identifiable)
    sub = cov[np.ix_(ident, ident)]
    scale = np.sqrt(np.maximum(np.diag(sub), 1e-300))
    prior_residual = forces - model.forces(ps.prior)
    platform, doubts = _checked_platform(ps, theta)
    correlation, names = sub / np.outer(scale, scale), [ps.names[k] for k in ident]
    return Identification(
        parameters=estimates, combinations=combinations,
        correlation=correlation, correlation_names=names,
        platform=platform, prior=ps.platform, unreachable=_unreachable(ps, st, theta),
        weak=_weak(ps, estimates, J, noise, correlation, names),
        implausible=_implausible(ps, st, theta, cov, J, residual, 1.0 / noise) + doubts,
        misfit=_misfit(residual, forces, given),
        residual=_rms(residual), residual_prior=_rms(prior_residual), noise=noise,
        noise_given=given is not None, rank=st.rank, condition=st.condition,
        samples=len(forces), evaluations=nfev, flagged=flagged)


def _misfit(residual: np.ndarray, forces: np.ndarray, given: np.ndarray | None) -> list[str]:
    """A line when the residual RMS exceeds ``MISFIT_RATIO`` times the noise: the given one,
    else the forces' own high-frequency noise (independent of the fit, unlike the noise
    estimated from the residual, which a misfit inflates)."""
    noise = given if given is not None else high_frequency_std(forces, HIGH_FREQUENCY_WINDOW)
    left, level = float(np.sqrt(np.mean(residual ** 2))), float(np.sqrt(np.mean(noise ** 2)))
    if level <= 0 or left <= MISFIT_RATIO * level:
        return []
    what = "the given noise" if given is not None else "the forces' high-frequency noise"
    return [f"the fit leaves {left:.4g} N RMS, {left / level:.3g} times {what} ({level:.4g} "
            "N): the model does not reproduce the forces; start from the rig's rough masses "
            "and friction (--platform) if the prior is far from it, else look for the effect "
            "it lacks (gsfric discover)"]


def _checked_platform(ps: ParameterSet, theta: np.ndarray) -> tuple[Platform, list[str]]:
    """The platform of theta, and the plausibility warnings of ``Platform`` (a centre of mass
    outside the body or beyond the longest leg) that it raises and the prior does not."""
    said = []
    for values in (ps.prior, theta):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", GsfricWarning)
            platform = ps.platform_of(values)
        said.append(list(dict.fromkeys(str(w.message) for w in caught
                                       if issubclass(w.category, GsfricWarning))))
    return platform, [m for m in said[1] if m not in said[0]]


def _rms(residual: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(residual ** 2, axis=0))


def _expression(coefficients: dict[str, float]) -> str:
    """``a + 0.5 b - 2 c`` of {name: coefficient} (the leading one first, coefficient 1)."""
    text = ""
    for name, c in coefficients.items():
        if c == 1.0 and not text:
            text = name
            continue
        sign = "-" if c < 0 else "+"
        text += f" {sign} {abs(c):.4g} {name}" if text else f"{c:.4g} {name}"
    return text


def _hint(name: str) -> str:
    return next(h for prefix, h in HINTS if name.startswith(prefix))


def _unreachable(ps: ParameterSet, st: Structure, theta: np.ndarray | None = None
                 ) -> list[str]:
    """One line per parameter not identifiable alone at ``theta`` (default the prior): why,
    and what motion would reach it."""
    out = []
    for k, name in enumerate(ps.names):
        if st.identifiable[k]:
            continue
        shifted = theta is not None and moved(theta[k], ps.prior[k], ps.units[k])
        if st.idle[k] and shifted:
            why = (f"the fit moved it from the prior's {ps.prior[k]:.6g} to {theta[k]:.6g}, "
                   "where it no longer acts on the forces along this motion: the data show "
                   "no such effect there")
        elif st.idle[k]:
            why = "does not act on the forces along this motion"
        else:
            combos = [_expression({ps.names[j]: c for j, c in enumerate(coef) if abs(c) > 1e-9})
                      for coef in st.combinations.values() if abs(coef[k]) > 1e-9]
            why = ("only in combination: " + "; ".join(combos) if combos else
                   "its effect on the forces is that of other parameters")
        out.append(f"{name}: {why}; needs {_hint(name)}")
    return out


def _weak(ps: ParameterSet, estimates: dict[str, Estimate], J: np.ndarray,
          noise: np.ndarray, correlation: np.ndarray, names: list[str]) -> list[str]:
    """One line per identifiable parameter whose standard deviation exceeds
    ``WEAK_RELATIVE_STD`` of its prior value (as ``excite`` reports it; a parameter whose
    prior is zero has no scale to be weak against), with the reason: the largest change of a
    force it makes along the motion (its value times the largest derivative, N) against the
    noise, or, when that change is above the noise, the parameter whose effect it shares
    (``correlation`` (q, q) of the identifiable ``names``); and what motion would reach it."""
    out = []
    rms_noise = float(np.sqrt(np.mean(noise ** 2)))
    for k, name in enumerate(ps.names):
        e = estimates[name]
        if e.std is None or e.prior == 0 or e.std <= WEAK_RELATIVE_STD * abs(e.prior):
            continue
        effect = float(np.abs(J[:, :, k]).max() * max(abs(e.value), abs(e.prior)))
        why = (f"it moves a force by {effect:.2g} N at most along this motion, against "
               f"{rms_noise:.2g} N of noise")
        if effect > rms_noise and len(names) > 1:
            i = names.index(name)
            r = np.where(np.arange(len(names)) == i, 0.0, correlation[i])
            j = int(np.argmax(np.abs(r)))
            why += f", much as {names[j]} does (correlation {r[j]:+.2f})"
        out.append(f"{name}: std {e.std:.2g} {e.unit}, {100 * e.std / abs(e.prior):.3g} % of "
                   f"its prior value; {why}; needs {_hint(name)}")
    return out


def _implausible(ps: ParameterSet, st: Structure, theta: np.ndarray, cov: np.ndarray,
                 J: np.ndarray, residual: np.ndarray, weights: np.ndarray) -> list[str]:
    """Masses the data want negative: the unconstrained (Gauss-Newton) estimate from the
    solution more than ``IMPLAUSIBLE_SIGMA`` standard deviations below zero."""
    free = theta + _step(J, weights, st, residual)
    out = []
    for k, name in enumerate(ps.names):
        if name in MASSES and st.identifiable[k]:
            std = float(np.sqrt(max(cov[k, k], 0.0)))
            if free[k] < -IMPLAUSIBLE_SIGMA * std:
                out.append(f"{name}: the data call for {free[k]:.4g} kg (std {std:.2g} kg), a "
                           "negative mass: check the forces' sign and unit, and that the "
                           "platform file describes this rig")
    return out


def validate(result: Identification, motion: Motion, forces: np.ndarray,
             source: str = "") -> Validation:
    """Prediction error on a second record (``motion``, measured ``forces`` (N, 6) N) with the
    prior and the identified platform, on the steps the prior's model does not flag (as the
    fit leaves them out)."""
    forces = np.asarray(forces, float)
    keep = unflagged_steps(result.prior, motion)
    x, t, forces = state_array(motion)[keep], motion.t[keep], forces[keep]
    out = []
    for platform in (result.prior, result.platform):
        ps = parameter_set(platform)
        predicted = Model(ps, x, t).forces(ps.prior)
        if platform is result.prior:
            check_force_sign(forces, predicted, source)
        out.append(_rms(forces - predicted))
    return Validation(out[0], out[1], result.noise, source,
                      flagged=int(np.count_nonzero(~keep)))
