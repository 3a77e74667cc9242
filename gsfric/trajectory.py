"""Platform motions: poses with their velocities and accelerations, from arrays or from sampled poses.

Conventions (see docs/explanation/architecture.md): SI units, radians, the step as the leading axis.
The orientation ``R`` maps platform-frame vectors to the base frame. In ZXZ angles,
``R = Rz(gamma) Rx(beta) Rz(alpha)``, whose entries are the paper's b_ij; this is
``scipy.spatial.transform.Rotation.from_euler("zxz", [alpha, beta, gamma])`` (extrinsic).
Quaternions are unit and scalar-first, ``(qw, qx, qy, qz)``, Hamilton product, mapping the
platform frame to the base frame. Angular velocity ``omega`` and acceleration ``alpha`` are
expressed in the base frame: ``dR/dt = [omega]x R``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gsfric._checks import as_array, as_float, fields_equal
from gsfric._optional import optional
from gsfric.errors import GsfricWarning, InputError
from gsfric.signal.noise import divided_noise_std, white_noise_std
from gsfric.signal.rotations import (
    MIN_QUATERNION_LENGTH,
    angular_rates,
    continuous_quaternions,
    euler_from_rotation,
    quaternion_from_euler,
    quaternion_from_rotation,
    rotation_defects,
    rotation_from_quaternion,
    unit_quaternions,
)
from gsfric.signal.savgol import DEFAULT_POLYORDER, check_polyorder
from gsfric.signal.smoothing import Smoothed, evenly_spaced, smooth

if TYPE_CHECKING:
    import pandas as pd

MIN_SAMPLES = 7
"""Fewest samples ``Motion.from_samples`` (and the trajectory readers) accept."""

UNIFORM_RTOL = 1e-2
"""A file streamed in chunks (``gsfric.simulate``) must have every time step within this
fraction of the mean step (``is_uniform``): its chunks are differentiated with one
Savitzky-Golay filter at that step. A file read whole chooses its time base from its poses
(``gsfric.signal.smoothing.evenly_spaced``)."""

GIMBAL_SIN_BETA = 1e-3
GIMBAL_JUMP = 0.5
"""A ZXZ sample with |sin(beta)| < GIMBAL_SIN_BETA whose alpha or gamma jumps by more than
GIMBAL_JUMP rad from its neighbour triggers a warning."""

ROTATION_TOL = 1e-6
"""The largest entry of |R^T R - I| of a matrix taken as a rotation (``Motion.rotation``, the
rotation block of the states given to ``Evaluator``): a rotation rounded to 7 significant
digits passes, a scaled (2 R), sheared or mirrored (determinant < 0) matrix does not. Forces
from such a matrix would look plausible while no pose has them."""


def first_non_rotation(rotation: np.ndarray) -> tuple[int, str] | None:
    """The first of the (N, 3, 3) matrices that is not a rotation (to ``ROTATION_TOL``, or a
    determinant < 0), as (index, "(|R^T R - I| = 3, det = 8)"); None when all are (NaN
    entries pass: the finite checks name them)."""
    error, det = rotation_defects(rotation)
    bad = np.flatnonzero((error > ROTATION_TOL) | (det < 0))
    if not len(bad):
        return None
    k = int(bad[0])
    return k, f"(|R^T R - I| = {error[k]:.3g}, det = {det[k]:.3g})"


SAMPLING_RATE_RANGE = (1.0, 1e6)
"""Plausible sampling rates, Hz, of a motion log: outside them t is in another unit than the one
declared (a microsecond counter read as seconds gives 1e-4 Hz at 100 Hz), an error naming the
likely unit (``time_unit_hint``)."""

TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
"""Time units and their factor to s."""

TYPICAL_RATE = 300.0
"""Sampling rate, Hz, in the middle of motion logs' usual 10 Hz .. 10 kHz: of the units that
put a time step inside ``SAMPLING_RATE_RANGE``, the one closest to it (on a log scale) is named."""


def time_unit_hint(step: float, unit: str = "s") -> str | None:
    """The time unit that makes a median time step ``step`` (in ``unit``) a plausible sampling
    interval, or None when ``unit`` already does (or no unit does)."""
    low, high = SAMPLING_RATE_RANGE
    if not np.isfinite(step) or step <= 0:
        return None
    with np.errstate(divide="ignore", over="ignore"):          # a step that underflows: inf
        rates = {u: float(np.divide(1.0, np.float64(step) * f)) for u, f in TIME_UNITS.items()}
    if low <= rates[unit] <= high:
        return None
    fits = [u for u, rate in rates.items() if low <= rate <= high]
    if not fits:
        return None
    return min(fits, key=lambda u: abs(np.log(rates[u] / TYPICAL_RATE)))


def check_sampling_rate(t: np.ndarray, what: str = "t", unit: str = "s",
                        factor: float = 1.0) -> None:
    """Raise ``InputError`` when the median time step of t (N,), s, is not a plausible sampling
    interval (``SAMPLING_RATE_RANGE``), naming the likely unit: ``what`` names the column,
    ``unit`` and ``factor`` (to s) the unit it was declared in."""
    if len(t) < 2:
        return
    with np.errstate(all="ignore"):
        step = float(np.median(np.diff(t)))
    if not np.isfinite(step) or step <= 0:
        return
    low, high = SAMPLING_RATE_RANGE
    rate = 1.0 / step
    if low <= rate <= high:
        return
    raw = step / factor
    hint = time_unit_hint(raw, unit if unit in TIME_UNITS else "s")
    advice = (f" -> looks like {hint}; declare t={hint} (--units t={hint}, or [units] t = "
              f"\"{hint}\" in the log format)" if hint else "; check the time column")
    raise InputError(f"{what}: median time step {raw:.4g} {unit}, a sampling rate of "
                     f"{rate:.4g} Hz, outside {low:g} Hz .. {high:g} Hz{advice}")


MAX_POSITION = 100.0
"""Positions farther than this from the base frame's origin, m, draw a warning (mm given as m);
``gsfric log inspect``, which takes the unit from the values, refuses them (no hexapod reaches
that far: a glitch in the log)."""

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
                      "angles must be in radians", GsfricWarning, stacklevel=5)
    near_lock = np.abs(np.sin(euler[:, 1])) < GIMBAL_SIN_BETA
    near_lock = near_lock[1:] | near_lock[:-1]
    steps = np.abs((np.diff(euler[:, [0, 2]], axis=0) + np.pi) % (2 * np.pi) - np.pi)
    jumps = np.flatnonzero(near_lock & (steps.max(axis=1) > GIMBAL_JUMP)) + 1
    if len(jumps):
        warnings.warn(f"{prefix}ZXZ angles near beta = 0 (where alpha and gamma are ill-defined) "
                      f"jump by more than {GIMBAL_JUMP} rad in alpha or gamma at "
                      f"{_where(source, jumps)}; give the orientation as a quaternion "
                      "(qw, qx, qy, qz) instead", GsfricWarning, stacklevel=5)


def check_units(t: np.ndarray, position: np.ndarray, source: str | None = None,
                stacklevel: int = 4) -> None:
    """Check that times and positions are in s and m.

    A median time step outside 1 us .. 1 s (a sampling rate outside ``SAMPLING_RATE_RANGE``,
    1 Hz .. 1 MHz) is an ``InputError`` naming the likely unit (``check_sampling_rate``); a
    position beyond ``MAX_POSITION`` (100 m) draws a warning (``GsfricWarning``): mm rather
    than m.

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
        check_sampling_rate(t)
    far = float(np.abs(position).max()) if len(position) else 0.0
    if far > MAX_POSITION:
        warnings.warn(f"{prefix}position: up to {far:.4g} m from the base frame's origin (more "
                      f"than {MAX_POSITION:g} m); positions must be in m, not mm",
                      GsfricWarning, stacklevel=stacklevel)


def jitter(t: np.ndarray) -> float:
    """The largest deviation of a time step from the mean step, as a fraction of the mean
    step, of times t (N,), s (0 for evenly spaced stamps)."""
    t = np.asarray(t, float)
    mean_step = (t[-1] - t[0]) / (len(t) - 1)
    return float(np.max(np.abs(np.diff(t) - mean_step)) / mean_step)


def is_uniform(t: np.ndarray) -> bool:
    """Whether the times t (N,), s, are uniform enough to be streamed in chunks: every step
    within ``UNIFORM_RTOL`` of the mean step."""
    t = np.asarray(t, float)
    steps = np.diff(t)
    mean_step = (t[-1] - t[0]) / (len(t) - 1)
    return bool(np.all(np.abs(steps - mean_step) <= UNIFORM_RTOL * mean_step))


def taken_as_even(motion: Motion) -> bool:
    """Whether ``motion``'s stamps were differentiated as evenly spaced: as
    ``Motion.from_samples`` decided, or ``is_uniform`` of its times for a motion not made by
    it."""
    how = motion.differentiation()
    return how.even if how is not None else is_uniform(motion.t)


@dataclass(frozen=True)
class Differentiation:
    """How ``Motion.from_samples`` got the velocities and accelerations of a motion.

    Attributes
    ----------
    method : str
        "savgol, per-sample filters" (uniform stamps, no window: a filter chosen per sample),
        "savgol" (uniform stamps, the window given), "local polynomial" (uneven stamps, the
        window given: the window's polynomial fitted on the stamps themselves) or
        "smoothing spline" (uneven stamps, no window).
    window : int or None
        Samples of the window given.
    polyorder : int
        Polynomial order of the Savitzky-Golay and local fits.
    jitter : float
        Largest deviation of a time step from the mean step, fraction of the mean step.
    rates : tuple of str
        The ``Motion`` rates taken from the log's own columns (``velocity``, ``omega``,
        ``acceleration``, ``alpha``); the others are differentiated.
    """

    method: str
    window: int | None
    polyorder: int
    jitter: float
    rates: tuple[str, ...] = ()

    @property
    def even(self) -> bool:
        """Whether the stamps were taken as evenly spaced (a Savitzky-Golay filter)."""
        return self.method.startswith("savgol")

    def describe(self) -> str:
        """One line, e.g. ``savgol (window 21, order 4) on stamps with 0.3 % jitter taken as
        evenly spaced; velocity from the log's columns``."""
        parts = [f"window {self.window}"] if self.window is not None else []
        if self.method != "smoothing spline":
            parts.append(f"order {self.polyorder}")
        text = f"{self.method} ({', '.join(parts)})" if parts else self.method
        if self.method.startswith("savgol") and self.jitter > 1e-9:
            text += (f" on stamps with {100 * self.jitter:.2g} % jitter taken as evenly "
                     "spaced")
        elif not self.method.startswith("savgol"):
            text += f" on uneven stamps ({100 * self.jitter:.2g} % jitter)"
        if self.rates:
            text += f"; {', '.join(self.rates)} from the log's columns"
        return text


@dataclass(frozen=True)
class RateUncertainty:
    """One standard deviation of each differentiated rate of a motion, from the white noise of
    its recorded poses (``gsfric.signal.smoothing``: the smoother's noise gain times the noise
    of the poses on the time base used, which includes the stamps' jitter there).

    Attributes
    ----------
    velocity : ndarray, shape (N, 3)
        m/s, base frame axes.
    omega : ndarray, shape (N, 3)
        rad/s: ``2 gain sigma_q``, sigma_q the root mean square of the quaternion components'
        noise (``omega = 2 vec(qdot q*)`` maps a noise of equal variance on the four
        components to each axis with twice its standard deviation).
    acceleration : ndarray, shape (N, 3)
        m/s^2.
    alpha : ndarray, shape (N, 3)
        rad/s^2: ``2 gain sigma_q`` (the term in omega neglected).

    Rates taken from the log's own columns carry the white noise of those columns (a given
    acceleration) or its passage through the smoother (an acceleration made from a given
    velocity). The pose noise is taken as white and independent between the axes.
    """

    velocity: np.ndarray
    omega: np.ndarray
    acceleration: np.ndarray
    alpha: np.ndarray

    def stacked(self) -> np.ndarray:
        """(N, 12): velocity, omega, acceleration, alpha, in the state's order."""
        return np.concatenate([self.velocity, self.omega, self.acceleration, self.alpha],
                              axis=1)

    def slice(self, part) -> RateUncertainty:
        """The steps ``part`` (a slice or an array of indices)."""
        return RateUncertainty(self.velocity[part], self.omega[part],
                               self.acceleration[part], self.alpha[part])


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

    Raises
    ------
    InputTypeError
        An argument that is not an array of numbers (None, a string), naming the field.
    InputError
        A wrong shape, a NaN or infinite value (naming the field and index, e.g.
        ``Motion.position[4][2]: must be finite, got nan``), a matrix that is not a rotation,
        no step at all.

    Examples
    --------
    >>> import numpy as np, gsfric
    >>> t = np.linspace(0.0, 2.0, 401)
    >>> position = np.column_stack([0.01 * np.sin(t), 0 * t, 0.7 + 0 * t])
    >>> level = np.tile([1.0, 0.0, 0.0, 0.0], (401, 1))
    >>> motion = gsfric.Motion.from_samples(t, position, quaternion=level)
    >>> motion.velocity.shape
    (401, 3)
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
        bad = first_non_rotation(rotation)
        if bad is not None:
            raise InputError(f"Motion.rotation[{bad[0]}]: not a rotation matrix {bad[1]}")
        object.__setattr__(self, "rotation", rotation)

    __eq__ = fields_equal
    __hash__ = None  # type: ignore[assignment]

    def __len__(self) -> int:
        return len(self.t)

    @classmethod
    def from_arrays(cls, t: np.ndarray, position: np.ndarray, rotation: np.ndarray,
                    velocity: np.ndarray, omega: np.ndarray, acceleration: np.ndarray,
                    alpha: np.ndarray) -> Motion:
        """A motion from its arrays (shapes as the attributes), validated; raises as
        ``Motion``."""
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
                     lam: float | None = None, source: str | None = None,
                     rates: dict[str, np.ndarray] | None = None) -> Motion:
        """A motion from sampled poses, by smoothing differentiation.

        The orientation becomes sign-continuous unit quaternions (angles are never
        differentiated); position and quaternion are smoothed and differentiated twice:

        * stamps taken as evenly spaced (exactly even, or jittered while the poses look no
          noisier on the even grid than on the stamps: ``gsfric.signal.smoothing``): a
          Savitzky-Golay filter of ``window`` samples and order ``polyorder`` at the mean step,
          or, with ``window=None``, the filter of least estimated error chosen per sample
          (``adaptive_filters``);
        * uneven stamps with a ``window``: the polynomial of that window fitted on the stamps
          themselves (``local_polynomial_derivatives``);
        * uneven stamps without a window: a cubic smoothing spline with penalty ``lam``, chosen
          from the data when None (``spline_penalties``); its accelerations at the ends are
          biased towards zero.

        ``rates`` given are taken as they are; an acceleration not given whose velocity is, is
        that velocity's smoothed derivative. ``differentiation()`` tells what was used and
        ``rate_uncertainty()`` the standard deviation of every rate (the smoother's noise gain
        times the white noise of the recorded poses on the time base used). From
        the smoothed quaternion p: ``omega = 2 vec(pdot p*) / |p|^2`` and
        ``alpha = 2 vec(pddot p*) / |p|^2 - omega 2 (p . pdot) / |p|^2`` (base frame).

        Parameters
        ----------
        t : array_like, shape (N,)
            Strictly increasing times, s; N >= ``MIN_SAMPLES``.
        position : array_like, shape (N, 3)
            Platform frame origin in the base frame, m.
        euler : array_like, shape (N, 3), optional
            ZXZ angles (alpha, beta, gamma), rad. Warns (``GsfricWarning``) if any exceeds
            2 pi in magnitude (degrees?) or if, where ``abs(sin(beta)) < GIMBAL_SIN_BETA``, alpha
            or gamma jump by more than ``GIMBAL_JUMP`` between samples.
        quaternion : array_like, shape (N, 4), optional
            ``(qw, qx, qy, qz)``, platform frame to base frame; normalized here. Give exactly
            one of ``euler`` and ``quaternion``.
        window : int, optional
            Odd Savitzky-Golay window, ``polyorder < window <= N``.
        polyorder : int
            Savitzky-Golay polynomial order, >= 2.
        lam : float, optional
            Smoothing-spline penalty (non-uniform sampling only).
        source : str, optional
            File name for messages; when given, messages start with it and name 1-based rows,
            otherwise they name 0-based sample indices.
        rates : dict of str to array_like (N, 3), optional
            Any of ``velocity``, ``omega`` (rad/s), ``acceleration``, ``alpha`` (rad/s^2) in
            the base frame, SI: used instead of the differentiated ones.

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
                                         lam, source, rates)
        except InputError as error:
            if prefix and not str(error).startswith(prefix):
                raise type(error)(prefix + str(error)) from None
            raise

    @classmethod
    def _from_samples(cls, t, position, euler, quaternion, window, polyorder, lam,
                      source, rates) -> Motion:
        t, position, q = _sampled_poses(t, position, euler, quaternion, source)
        check_polyorder(polyorder, len(t))
        if lam is not None:
            lam = as_float(lam, "lam", minimum=0.0)
        rates = _checked_rates(rates, len(t))
        even = evenly_spaced(t, position, q)
        ps, qs = (smooth(t, y, even, window, polyorder, lam) for y in (position, q))
        omega, alpha = angular_rates(qs.value, qs.first, qs.second)
        rotation = rotation_from_quaternion(qs.value)
        p1, p2, sigma_p = _given_rates(t, rates, "velocity", "acceleration", ps, even,
                                       window, polyorder, lam)
        qs_rates = Smoothed(qs.value, omega, alpha, qs.gains,
                            np.full(3, 2.0 * np.sqrt(np.mean(qs.noise ** 2))))
        omega, alpha, sigma_q = _given_rates(t, rates, "omega", "alpha", qs_rates, even,
                                             window, polyorder, lam)
        results = (ps.value, p1, p2, rotation, omega, alpha)
        if not all(np.isfinite(r).all() for r in results):
            raise InputError("differentiation gave non-finite values (values or time steps "
                             "out of range)")
        motion = cls(t, ps.value, rotation, p1, omega, p2, alpha)
        if ps.filters is not None:
            object.__setattr__(motion, "_filters", (int(polyorder), (ps.filters, qs.filters)))
        object.__setattr__(motion, "_recorded", (position, q))
        object.__setattr__(motion, "_differentiation",
                           _how(t, even, window, polyorder, tuple(rates)))
        if sigma_p is not None and sigma_q is not None:
            object.__setattr__(motion, "_uncertainty", RateUncertainty(
                sigma_p[0], sigma_q[0], sigma_p[1], sigma_q[1]))
        return motion

    def differentiation(self) -> Differentiation | None:
        """How ``from_samples`` differentiated this motion (method, window, jitter, rates from
        the log), or None for a motion not made by it, or a slice."""
        return getattr(self, "_differentiation", None)

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
        # the steps of a valid motion are valid: no second validation pass
        motion = Motion._trusted(self.t[part], self.position[part], self.rotation[part],
                                 self.velocity[part], self.omega[part],
                                 self.acceleration[part], self.alpha[part])
        uncertainty = self.rate_uncertainty()
        if uncertainty is not None:
            object.__setattr__(motion, "_uncertainty", uncertainty.slice(part))
        return motion

    def rate_uncertainty(self) -> RateUncertainty | None:
        """One standard deviation of the differentiated rates (``RateUncertainty``), or None
        for a motion given with its rates (``from_arrays``) or whose smoother's noise gains
        are not known (an uneven record of at most ``SPLINE_GCV_ROWS`` samples without a
        window)."""
        return getattr(self, "_uncertainty", None)

    def quaternion(self) -> np.ndarray:
        """The orientation as sign-continuous unit quaternions ``(qw, qx, qy, qz)``, (N, 4)."""
        return continuous_quaternions(quaternion_from_rotation(self.rotation))

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
        pd = optional("pandas")

        columns: dict[str, np.ndarray] = {"t": self.t}
        columns.update(zip(("x", "y", "z"), self.position.T))
        columns.update(zip(("qw", "qx", "qy", "qz"), self.quaternion().T))
        columns.update(zip(("alpha", "beta", "gamma"), self.euler().T))
        if derivatives:
            for prefix, values in (("v", self.velocity), ("omega_", self.omega),
                                   ("a", self.acceleration), ("alpha_", self.alpha)):
                columns.update(zip((prefix + c for c in "xyz"), values.T))
        return pd.DataFrame(columns)


def _sampled_poses(t, position, euler, quaternion, source: str | None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The checked samples of ``Motion.from_samples``: times (N,), positions (N, 3) and
    sign-continuous unit quaternions (N, 4)."""
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
    check_units(t, position, source, stacklevel=6)
    if euler is not None:
        euler = as_array(euler, (n, 3), "euler")
        _check_euler(euler, source)
        q = quaternion_from_euler(euler[:, 0], euler[:, 1], euler[:, 2])
    else:
        q = as_array(quaternion, (n, 4), "quaternion")
        q, norms = unit_quaternions(q)
        zero = np.flatnonzero(norms < MIN_QUATERNION_LENGTH)
        if len(zero):
            raise InputError(f"{_where(source, zero[:1])}: quaternion of zero length")
    return t, position, continuous_quaternions(q)


RATE_NAMES = ("velocity", "omega", "acceleration", "alpha")


def _checked_rates(rates, n: int) -> dict[str, np.ndarray]:
    if rates is None:
        return {}
    out = {}
    for name, values in dict(rates).items():
        if name not in RATE_NAMES:
            raise InputError(f"rates: unknown rate {name!r}; use {', '.join(RATE_NAMES)}")
        out[name] = as_array(values, (n, 3), f"rates[{name!r}]")
    return out


def _given_rates(t, rates, first: str, second: str, smoothed: Smoothed, even: bool, window,
                 polyorder, lam):
    """The first and second derivative (N, 3) of a pose part and their standard deviations
    ((N, 3) twice, or None): those given in ``rates`` (with the white noise of their columns),
    the second otherwise smoothed from a given first one, else ``smoothed``'s."""
    d1, d2, sigma = smoothed.first, smoothed.second, smoothed.sigma()
    if first in rates:
        d1 = rates[first]
        noise = _noise(t, d1, even)
        if second not in rates:
            made = smooth(t, d1, even, window, polyorder, lam)
            d2 = made.first
            sigma = None if made.gains is None else \
                (np.broadcast_to(noise, d1.shape), made.sigma()[0])
        else:
            sigma = None if sigma is None else (np.broadcast_to(noise, d1.shape), sigma[1])
    if second in rates:
        d2 = rates[second]
        if sigma is not None:
            sigma = (sigma[0], np.broadcast_to(_noise(t, d2, even), d2.shape))
    return d1, d2, sigma


def _noise(t, y, even: bool) -> np.ndarray:
    """White-noise standard deviation (k,) of a recorded signal y (N, k) on its time base."""
    return white_noise_std(y) if even else divided_noise_std(t, y)


def _how(t, even, window, polyorder, rates) -> Differentiation:
    """The ``Differentiation`` that ``smooth`` used on the times t."""
    if even:
        method = "savgol, per-sample filters" if window is None else "savgol"
    else:
        method = "smoothing spline" if window is None else "local polynomial"
    return Differentiation(method, None if window is None else int(window), int(polyorder),
                           jitter(t), tuple(r for r in RATE_NAMES if r in rates))
