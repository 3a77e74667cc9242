"""An excitation motion designed for identification.

Each pose coordinate (x, y, z about the home pose, m; the angles psi, theta, phi of
``Rz Ry Rx``, rad) is a finite Fourier series of period ``period`` repeated over the duration,

    q_j(t) = sum_k a_jk sin(k w t) + b_jk (cos(k w t) - 1),   w = 2 pi / period,

with ``sum_k k a_jk = 0`` and ``sum_k k^2 b_jk = 0``: every period starts and ends at the home
pose at rest (zero speed and acceleration), so the whole motion does too. A candidate shape is
scaled to the largest size that keeps every leg within the stroke (a margin of
``STROKE_MARGIN`` of it), under the leg speed and acceleration limits, and the forces finite (no
singular pose).

The criterion is D-optimality: the sum of the logarithms of the squared singular values of the
noise-weighted base regressor, i.e. minus the log-volume of the parameters' confidence
ellipsoid. It is chosen over the condition number because it is smooth in the coefficients,
rewards information on every base parameter (not only the ratio of the extremes), and does not
depend on the parameters' units (a change of unit scales the determinant by a constant), where
the condition number depends on how the columns are scaled. Candidates with more identifiable
directions win first. The search scores ``EXCITE_CANDIDATES`` random shapes on one period
sampled coarsely (``MAX_SAMPLES_EXCITE``) and refines the best by random steps of shrinking
size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsfric._checks import as_count, as_flag, as_float
from gsfric.errors import InputError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import check_flagged, flag_counts
from gsfric.identification.parameters import parameter_set
from gsfric.identification.regressor import Model, covariance, structure
from gsfric.identification.settings import (EXCITE_CANDIDATES, EXCITE_HARMONICS,
                                            EXCITE_SAMPLES_PER_CYCLE, MAX_EXCITE_SAMPLES,
                                            MAX_SAMPLES_EXCITE, TYPICAL, WEAK_RELATIVE_STD)
from gsfric.models import home_centre, platform_from, pose_motion, resting_at_home, sinusoidal
from gsfric.platform.description import Platform
from gsfric.platform.usable import SPEED_STROKES
from gsfric.signal.noise import PLAUSIBLE_SPREAD
from gsfric.trajectory import Motion

PERIOD = 4.0
"""Default period of the Fourier series, s: harmonics 1..5 at 0.25 to 1.25 Hz, the band of a
hexapod's own motions, and a duration of 60 s repeats it 15 times."""

AMPLITUDE = np.array([0.06, 0.06, 0.05, 0.15, 0.15, 0.15])
"""Size of each coordinate's random shape before scaling to the limits (m, m, m, rad x 3)."""

STROKE_MARGIN = 0.05
"""Share of the stroke kept free at each end."""

MAX_SPEED = 0.3
"""Default leg speed limit, m/s."""

MAX_ACCELERATION = 3.0
"""Default leg acceleration limit, m/s^2."""

NOISE_SHARE = 0.005
"""Default force noise: 0.5 % of the mean static actuator force at the home pose."""

REFINE_STEPS = 24
"""Random refinement steps of the best candidate."""


@dataclass
class Excitation:
    """A designed excitation and what it promises.

    Attributes
    ----------
    motion : Motion
        The motion at the requested rate, at rest at both ends.
    coefficients : ndarray, shape (6, 2, K)
        ``a`` and ``b`` of each coordinate's series (m or rad).
    period : float
        s.
    log_det : float
        D-optimality criterion of the motion (sum of log squared singular values of the
        noise-weighted base regressor; larger is better).
    condition, sinusoid_condition : float
        Condition number of the column-normalised base regressor of this motion and of a plain
        sinusoidal motion (``gsfric.models.sinusoidal``) of the same duration and rate.
    rank, sinusoid_rank : int
        Identifiable directions of each.
    force_noise : float
        Force noise the standard deviations assume, N.
    expected_std : dict[str, float or None]
        Each parameter's expected standard deviation (its unit), None where not identifiable.
    prior : dict[str, float]
        The platform's value of each parameter (for relative standard deviations).
    units : dict[str, str]
    largest_effect : dict[str, float]
        The largest change of an actuator force along the motion that each parameter makes at
        its platform value (the value's size times the largest size of the forces'
        derivative with respect to it), N: with ``n`` forces, no fit can know it better than
        ``force_noise * abs(value) / (sqrt(n) * largest_effect)``.
    """

    motion: Motion
    coefficients: np.ndarray
    period: float
    log_det: float
    condition: float
    sinusoid_condition: float
    rank: int
    sinusoid_rank: int
    force_noise: float
    expected_std: dict
    prior: dict
    units: dict
    largest_effect: dict

    def relative_std(self) -> dict:
        """Expected std divided by the absolute value of the platform's, per parameter (None
        without a std or at a zero value)."""
        return {n: (s / abs(self.prior[n]) if s is not None and self.prior[n] != 0 else None)
                for n, s in self.expected_std.items()}

    def report(self) -> str:
        """Lines for a reader: condition numbers and the expected std of each parameter."""
        span = float(self.motion.t[-1] - self.motion.t[0])
        periods = int(round(span / self.period))
        lines = [f"excitation: {span:g} s ({periods} period{'s' if periods > 1 else ''} of "
                 f"{self.period:g} s: a duration is rounded up to whole periods), "
                 f"{len(self.motion)} samples, rank {self.rank}, condition number "
                 f"{self.condition:.4g} (plain sinusoid: {self.sinusoid_condition:.4g}, rank "
                 f"{self.sinusoid_rank}); expected std for {self.force_noise:.4g} N force "
                 "noise:"]
        if self.sinusoid_rank == self.rank and self.sinusoid_condition < self.condition:
            lines.insert(1, "  (the plain sinusoid is better conditioned within these limits: "
                            "the design maximises the determinant of the information, the "
                            "parameters' joint precision, not the condition number; compare "
                            "the expected stds below)")
        rel = self.relative_std()
        for name, std in self.expected_std.items():
            text = "not identifiable" if std is None else f"{std:.3g} {self.units[name]}"
            if rel[name] is not None:
                text += f" ({100 * rel[name]:.3g} %)"
                if rel[name] > WEAK_RELATIVE_STD:
                    text += (f"; it moves a force by {self.largest_effect[name]:.2g} N at "
                             f"most along this motion")
            lines.append(f"  {name}: {text}")
        return "\n".join(lines)


def _basis(harmonics: int) -> np.ndarray:
    """Null-space basis (2K, 2K - 2) of the rest constraints on (a_1..a_K, b_1..b_K)."""
    k = np.arange(1, harmonics + 1, dtype=float)
    C = np.zeros((2, 2 * harmonics))
    C[0, :harmonics] = k
    C[1, harmonics:] = k ** 2
    _, _, Vt = np.linalg.svd(C)
    return Vt[2:].T


def _series(coef: np.ndarray, t: np.ndarray, period: float):
    """q, qd, qdd (N, 6) of coefficients (6, 2, K)."""
    K = coef.shape[2]
    w = 2 * np.pi / period * np.arange(1, K + 1)
    arg = t[:, None] * w
    s, c = np.sin(arg), np.cos(arg)
    a, b = coef[:, 0, :], coef[:, 1, :]
    q = s @ a.T + (c - 1) @ b.T
    qd = (c * w) @ a.T - (s * w) @ b.T
    qdd = -(s * w ** 2) @ a.T - (c * w ** 2) @ b.T
    return q, qd, qdd


def _motion(coef, t, period, platform: Platform) -> Motion:
    """The series of coefficients ``coef`` about the platform's home pose."""
    return pose_motion(t, *_series(coef, t, period), centre=home_centre(platform))


def _feasible(platform: Platform, motion: Motion, limits: tuple[float, float]) -> bool:
    """Legs within the stroke's margin and under the speed and acceleration limits, forces
    finite."""
    lengths = platform.leg_lengths(motion.position, motion.rotation)
    stroke = platform.geometry.stroke
    if stroke is not None:
        margin = STROKE_MARGIN * (stroke[1] - stroke[0])
        if lengths.min() < stroke[0] + margin or lengths.max() > stroke[1] - margin:
            return False
    t = motion.t
    speed = np.gradient(lengths, t, axis=0)
    if np.abs(speed).max() > limits[0]:
        return False
    if np.abs(np.gradient(speed, t, axis=0)).max() > limits[1]:
        return False
    F = Evaluator(platform).actuator_forces(state_array(motion))
    return bool(np.all(np.isfinite(F)))


def _scaled(platform, shape, t, period, limits) -> np.ndarray | None:
    """The shape scaled to the largest size within the limits (bisection), None if none is."""
    low, high = 0.0, 1.0
    if _feasible(platform, _motion(shape, t, period, platform), limits):
        return shape
    for _ in range(12):
        mid = 0.5 * (low + high)
        if _feasible(platform, _motion(mid * shape, t, period, platform), limits):
            low = mid
        else:
            high = mid
    return low * shape if low > 0 else None


def _score(ps, motion: Motion, noise: float) -> tuple[int, float, float, np.ndarray]:
    """(rank, log det, condition, J) of a motion's base regressor, rows weighted by 1/noise."""
    _, J = Model(ps, state_array(motion), motion.t).jacobian(ps.prior)
    weights = np.full(6, 1.0 / noise)
    st = structure(J, weights, ps.units)
    typical = np.array([TYPICAL.get(u, 1.0) for u in ps.units])
    A = (J * weights[None, :, None] * typical).reshape(-1, J.shape[2])
    s = np.linalg.svd(np.linalg.qr(A, mode="r"), compute_uv=False)
    return st.rank, float(np.sum(np.log(s[: st.rank] ** 2))), st.condition, J


def _shape(rng, basis, harmonics) -> np.ndarray:
    """A random shape (6, 2, K) satisfying the rest constraints, higher harmonics smaller."""
    decay = np.tile(1.0 / np.arange(1, harmonics + 1), 2)[:, None]
    raw = rng.normal(size=(2 * harmonics, 6)) * decay
    shape = (basis @ (basis.T @ raw)).T.reshape(6, 2, harmonics)      # onto the constraints
    size = np.abs(_series(shape, np.linspace(0, 1, 200), 1.0)[0]).max(axis=0)
    return shape * (AMPLITUDE / np.maximum(size, 1e-12))[:, None, None]


def excite(platform: Platform | str | None = None, *, duration: float = 60.0,
           rate: float = 500.0, period: float = PERIOD, max_speed: float = MAX_SPEED,
           max_acceleration: float = MAX_ACCELERATION, force_noise: float | None = None,
           sensors: bool = False, seed: int = 0) -> Excitation:
    """Design an excitation motion for ``identify`` (see the module docstring).

    Parameters
    ----------
    platform : Platform, path or None
        The platform (its geometry, stroke and current values; default the reference one).
    duration : float
        s, rounded up to whole periods.
    rate : float
        Sampling rate of the motion, Hz.
    period : float
        Period of the Fourier series, s.
    max_speed, max_acceleration : float
        Leg speed (m/s) and acceleration (m/s^2) limits.
    force_noise : float, optional
        Force noise for the expected standard deviations, N (default 0.5 % of the mean static
        actuator force at the home pose).
    sensors : bool
        Include the load cells' offsets and gains in the parameters.
    seed : int
        Seed of the random search.

    Returns
    -------
    Excitation

    Raises
    ------
    InputError
        A non-positive duration, rate or limit; a period of too few samples at the rate
        (``EXCITE_SAMPLES_PER_CYCLE``), a motion of more than ``MAX_EXCITE_SAMPLES``; a
        platform with no feasible motion.
    """
    platform = platform_from(platform)
    duration, rate, period, max_speed, max_acceleration = (
        _positive(value, name) for name, value in (
            ("duration", duration), ("rate", rate), ("period", period),
            ("max_speed", max_speed), ("max_acceleration", max_acceleration)))
    sensors, seed = as_flag(sensors, "sensors"), as_count(seed, "seed", minimum=0)
    force_noise = None if force_noise is None else as_float(force_noise, "force_noise")
    _check_samples(duration, rate, period)
    _check_speed_limit(platform, max_speed)
    ps = parameter_set(platform, sensors=sensors)
    noise = _design_noise(platform, force_noise)
    limits = (float(max_speed), float(max_acceleration))
    coarse = np.linspace(0.0, period, min(MAX_SAMPLES_EXCITE, int(period * rate) + 1))
    rng = np.random.default_rng(seed)
    basis = _basis(EXCITE_HARMONICS)
    best, best_key = None, None
    for _ in range(EXCITE_CANDIDATES):
        shape = _scaled(platform, _shape(rng, basis, EXCITE_HARMONICS), coarse, period, limits)
        if shape is None:
            continue
        key = _score(ps, _motion(shape, coarse, period, platform), noise)[:2]
        if best_key is None or key > best_key:
            best, best_key = shape, key
    if best is None:
        raise InputError("excite: no motion within the stroke and limits; widen the limits "
                         "or check the platform's stroke")
    best = _refine(ps, platform, best, best_key, rng, basis, coarse, period, limits, noise)
    return _excitation(ps, platform, best, duration, rate, period, noise)


def _positive(value, name: str) -> float:
    """A finite number > 0; ``InputTypeError`` for what is not a number, ``InputError``
    otherwise, naming ``name``."""
    value = as_float(value, name)
    if value <= 0:
        raise InputError(f"{name}: must be a positive number, got {value:g}")
    return value


def _periods(duration: float, period: float) -> int:
    """Whole periods of the series that hold ``duration`` (at least one; a duration within
    rounding of a whole number of periods is that number)."""
    return max(1, int(np.ceil(duration / period - 1e-9)))


def _check_samples(duration: float, rate: float, period: float) -> None:
    """An ``InputError`` for a period that holds too few samples at the rate to draw the
    series, or a motion of more samples than ``MAX_EXCITE_SAMPLES``."""
    fewest = EXCITE_SAMPLES_PER_CYCLE * EXCITE_HARMONICS
    if period * rate < fewest:
        raise InputError(f"period: {period:g} s at {rate:g} Hz holds {int(period * rate)} "
                         f"samples; the series needs at least {fewest} a period "
                         f"({EXCITE_SAMPLES_PER_CYCLE} a cycle of its highest harmonic, "
                         f"{EXCITE_HARMONICS} cycles a period): a period of at least "
                         f"{fewest / rate:.3g} s at this rate")
    whole = _periods(duration, period) * period
    samples = whole * rate + 1
    if samples > MAX_EXCITE_SAMPLES:
        name, given = "duration", f"{duration:g} s"
        if duration * rate + 1 <= MAX_EXCITE_SAMPLES:  # the rounding to whole periods is why
            name, given = "period", (f"{period:g} s (the duration of {duration:g} s rounded "
                                     f"up to whole periods: {whole:g} s)")
        raise InputError(f"{name}: {given} at {rate:g} Hz is {round(samples):,} samples, more "
                         f"than the {MAX_EXCITE_SAMPLES:,} an excitation is designed with "
                         "(each sample's regressor is kept); a shorter duration or period, "
                         "or a lower rate")


def _refine(ps, platform, best, best_key, rng, basis, t, period, limits, noise):
    """Random steps around the best shape, of shrinking size, kept when they score higher."""
    for step in range(REFINE_STEPS):
        size = 0.3 * (1.0 - step / REFINE_STEPS)
        trial = _scaled(platform, best + size * _shape(rng, basis, best.shape[2]), t, period,
                        limits)
        if trial is None:
            continue
        key = _score(ps, _motion(trial, t, period, platform), noise)[:2]
        if key > best_key:
            best, best_key = trial, key
    return best


def _excitation(ps, platform, coef, duration, rate, period, noise) -> Excitation:
    """The Excitation of coefficients over the whole duration, with the plain sinusoid's
    condition number for comparison."""
    periods = _periods(duration, period)
    t = np.arange(round(periods * period * rate) + 1) / rate
    motion = _motion(coef, t, period, platform)
    rank, log_det, condition, J = _score(ps, motion, noise)
    weights = np.full(6, 1.0 / noise)
    st = structure(J, weights, ps.units)
    std = np.sqrt(np.maximum(np.diag(covariance(J, weights, st)), 0.0))
    plain = sinusoidal(t, centre=home_centre(platform))
    s_rank, _, s_condition, _ = _score(ps, plain, noise)
    return Excitation(
        motion=motion, coefficients=coef, period=period, log_det=log_det, condition=condition,
        sinusoid_condition=s_condition, rank=rank, sinusoid_rank=s_rank, force_noise=noise,
        expected_std={n: (float(std[k]) if st.identifiable[k] else None)
                      for k, n in enumerate(ps.names)},
        prior=dict(zip(ps.names, map(float, ps.prior))), units=dict(zip(ps.names, ps.units)),
        largest_effect=dict(zip(ps.names, map(float, np.abs(J).max(axis=(0, 1))
                                              * np.abs(ps.prior)))))


def _design_noise(platform: Platform, force_noise: float | None) -> float:
    """The force noise of the design, N: ``force_noise`` if given, else ``NOISE_SHARE`` of the
    mean static actuator force at the home pose; an ``InputError`` for a platform the model
    flags at its home pose (singular, beyond its stroke: ``check_flagged``), for a default of
    zero (no static load) and for a noise outside ``PLAUSIBLE_SPREAD`` times that static
    force."""
    home = resting_at_home(platform)
    flagged = int(np.count_nonzero(home.flag))
    check_flagged(platform, flag_counts(home.flag), flagged, len(home.flag), "platform at home")
    static = float(np.mean(np.abs(home.F)))
    if force_noise is None:
        if static <= 0.0:
            raise InputError("force_noise: the legs carry no static load at the home pose "
                             "(gravity 0 or no masses), so the default 0.5 % of it is none; "
                             "give the load cells' noise (--force-noise, N)")
        return NOISE_SHARE * static
    low, high = PLAUSIBLE_SPREAD
    if not (np.isfinite(force_noise) and force_noise > 0):
        raise InputError(f"force_noise: must be a positive number of N, got {force_noise!r}")
    if static > 0 and not low * static <= force_noise <= high * static:
        raise InputError(f"force_noise: {force_noise:.3g} N is implausible against the "
                         f"{static:.3g} N the legs carry at rest: the noise must lie within "
                         f"{low:g} to {high:g} times it (is it in N?)")
    return float(force_noise)


def _check_speed_limit(platform: Platform, max_speed: float) -> None:
    """An ``InputError`` for a leg speed limit no hexapod of this stroke reaches
    (``SPEED_STROKES`` strokes a second, the limit the readers apply to a record)."""
    stroke = platform.geometry.stroke
    if stroke is not None and max_speed > SPEED_STROKES * (stroke[1] - stroke[0]):
        raise InputError(f"max_speed: {max_speed:g} m/s crosses the legs' stroke "
                         f"({stroke[1] - stroke[0]:.3g} m) more than {SPEED_STROKES:g} times "
                         "a second: no hexapod of this size moves so (is it in m/s?)")
