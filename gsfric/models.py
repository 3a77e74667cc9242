"""Reference platforms and motions, shared by the CLI, tests, notebooks and benchmarks.

The paper's figures 6-7 (the dimensions) are not in its text, so the reference geometry is the
project's own, documented in docs/explanation/reference-platform.md: a three-fold symmetric hexapod, base joints on a
circle of radius 0.5 m in pairs 30 degrees apart, platform joints on a circle of radius 0.3 m in
pairs 30 degrees apart (the pairs turned by 60 degrees against the base's), home height 0.7 m.

The paper's motion: the platform starts from rest at the home pose and moves with the constant
acceleration a = (0.07, 0.05, 0.04) m/s^2 and angular acceleration
alpha = (0.005, 0.003, 0.0025) rad/s^2 (base frame); its 40 steps are t_j = j dt, j = 1..40,
with dt = 0.05 s.
"""

from __future__ import annotations

import os

import numpy as np

from gsfric._checks import as_array
from gsfric._optional import optional
from gsfric.compiled.state import state_of
from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.paper_constants import (
    PAPER_ACCELERATION,
    PAPER_ANGULAR_ACCELERATION,
)
from gsfric.evaluation.result import Result
from gsfric.platform.description import Body, Friction, Geometry, Legs, Platform
from gsfric.platform.usable import UNIT_RATIO, check_force_sign, check_forces, home_height
from gsfric.signal.rotations import quaternion_from_rotation, rotation_from_euler
from gsfric.trajectory import Motion

BASE_RADIUS = 0.5
PLATFORM_RADIUS = 0.3
HALF_SPACING = np.radians(15.0)
HOME_HEIGHT = 0.7
STROKE = (0.5, 1.1)

PAPER_STEPS = 40
PAPER_DT = 0.05


def hexagon_joints(radius: float, centre_deg: float, half_spacing: float = HALF_SPACING,
                   z: float = 0.0) -> np.ndarray:
    """Six points in pairs around ``centre_deg + 120 k`` degrees, (6, 3), m."""
    angles = []
    for k in range(3):
        c = np.radians(centre_deg + 120.0 * k)
        angles += [c - half_spacing, c + half_spacing]
    a = np.array(angles)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.full(6, z)])


def reference_geometry() -> Geometry:
    """The reference hexapod's joints (base pairs at 0, 120, 240 deg; platform pairs at 60, ...).

    Base joint 2k+1 and platform joint 2k+1 are joined by leg 2k+1; each platform pair sits between
    two base pairs, so the legs cross over as in most Gough-Stewart platforms.
    """
    base = hexagon_joints(BASE_RADIUS, 0.0)
    top = hexagon_joints(PLATFORM_RADIUS, 60.0)
    # leg i joins base joint i with the nearest platform joint of the neighbouring pair
    top = np.roll(top, 1, axis=0)
    return Geometry(base_joints=base, platform_joints=top, stroke=STROKE)


def reference_leg() -> Legs:
    """The reference leg: a 32 mm electric cylinder (ball screw, motor at the universal joint).

    Lower part (body, screw, motor) 2.6 kg, centre 0.21 m from C_i; upper part (rod, nut, rod
    end) 0.7 kg, centre 0.25 m from E_i: the mass of an SMC LEY32 with 250 mm of stroke, split
    and placed from its parts. The numbers and how they were obtained: docs/explanation/reference-platform.md.
    """
    return Legs(model="rigid", weight=True,
                lower_mass=REFERENCE_LEG["lower_mass"], lower_com=REFERENCE_LEG["lower_com"],
                lower_inertia=np.diag(REFERENCE_LEG["lower_inertia"]),
                upper_mass=REFERENCE_LEG["upper_mass"], upper_com=REFERENCE_LEG["upper_com"],
                upper_inertia=np.diag(REFERENCE_LEG["upper_inertia"]))


REFERENCE_LEG = dict(lower_mass=2.6, lower_com=0.21, lower_inertia=(0.071, 0.071, 0.0012),
                     upper_mass=0.7, upper_com=0.25, upper_inertia=(0.019, 0.019, 0.0001))
"""The reference leg's masses (kg), centre distances (m, from C_i and from E_i) and principal
inertias (kg m^2, leg body frame: transverse, transverse, axial); see docs/explanation/reference-platform.md."""

REFERENCE_FRICTION = dict(model="coupled", bushing_offset=0.25, bushing_spacing=0.1,
                          prismatic_seal=2.0, prismatic_coulomb=0.1)
"""The reference platform's friction besides the paper's joint coefficients: the coupled model
(the default of ``reference_platform``), polymer bushings (mu 0.1) at 0.25 m and 0.35 m from
C_i, a 2 N rod seal."""

def reference_platform(friction_model: str = "coupled") -> Platform:
    """The built-in platform: the reference geometry, the paper's platform and payload, the
    reference leg (``reference_leg``) and, by default, the coupled friction model.

    Platform 10 kg with inertia 0.07 kg m^2 (times identity), payload 3 kg; joints
    c_s = 0.02 N m s/rad, mu = 0.04, r = 0.05 m; prismatic joints 0.02 N s/m, bushings with
    mu = 0.1 at 0.25 m and 0.35 m from C_i, seal 2 N (docs/explanation/reference-platform.md, docs/explanation/friction.md).

    Parameters
    ----------
    friction_model : {"coupled", "paper"}
        ``"coupled"`` (default): friction loads the mechanism (bushings, seal, per-axis
        universal joints, solved at every step; docs/explanation/friction.md). ``"paper"``: the paper's
        post-hoc friction model, (35) as printed with mu = 0.1 at R_3 and no seal.

    Returns
    -------
    Platform

    Examples
    --------
    >>> import gsfric
    >>> platform = gsfric.reference_platform()
    >>> platform.friction.model, platform.geometry.stroke
    ('coupled', (0.5, 1.1))
    """
    return Platform(
        gravity=9.81,
        geometry=reference_geometry(),
        platform=Body(mass=10.0, inertia=np.eye(3) * 0.07, payload_mass=3.0),
        legs=reference_leg(),
        friction=Friction(**{**REFERENCE_FRICTION, "model": friction_model,
                             **({"prismatic_seal": 0.0} if friction_model == "paper" else {})}),
        effects={},
    )


def platform_from(source: Platform | str | os.PathLike[str] | None) -> Platform:
    """The platform a command or function works on: ``source`` itself when it is a
    ``Platform``, read from the TOML file it names, or, when None, the default: the reference
    platform (``reference_platform()``, coupled friction)."""
    if source is None:
        return reference_platform()
    if isinstance(source, Platform):
        return source
    return Platform.from_toml(source)


def paper_platform() -> Platform:
    """The paper's platform: the paper's masses and coefficients on the reference geometry.

    Leg parts 0.5 kg with inertia 0.035 kg m^2, the paper's leg model (zone centres at 0.25 D
    and 0.75 D from C_i), friction c_s = 0.02 N m s/rad, mu = 0.04, r = 0.05 m, prismatic
    0.02 N s/m and 0.04, the paper's post-hoc friction model.

    Returns
    -------
    Platform
        With ``[friction] model = "paper"`` and the paper's leg model.

    Examples
    --------
    >>> import gsfric
    >>> gsfric.paper_platform().friction.model
    'paper'
    """
    return reference_platform().replace(legs=Legs(model="paper"), friction=Friction())


def _axis_angle(axis_angle: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of rotation vectors (N, 3) (Rodrigues)."""

    return optional("scipy.spatial.transform").Rotation.from_rotvec(axis_angle).as_matrix()


def constant_acceleration(t: np.ndarray, acceleration=PAPER_ACCELERATION,
                          angular_acceleration=PAPER_ANGULAR_ACCELERATION,
                          start=(0.0, 0.0, HOME_HEIGHT)) -> Motion:
    """Motion from rest at ``start`` (level) with constant linear and angular accelerations.

    The angular velocity ``alpha t`` keeps its direction, so the orientation is the rotation
    about that fixed axis by ``|alpha| t^2 / 2``: the motion is exact, not integrated.
    """
    t = np.asarray(t, dtype=float)
    a = np.broadcast_to(np.asarray(acceleration, float), (t.size, 3))
    al = np.broadcast_to(np.asarray(angular_acceleration, float), (t.size, 3))
    tt = t[:, None]
    return Motion.from_arrays(
        t=t,
        position=np.asarray(start, float) + 0.5 * a * tt**2,
        rotation=_axis_angle(0.5 * al * tt**2),
        velocity=a * tt,
        omega=al * tt,
        acceleration=a.copy(),
        alpha=al.copy(),
    )


def paper_motion(steps: int = PAPER_STEPS, dt: float = PAPER_DT) -> Motion:
    """The paper's 40-step motion: constant accelerations from rest, t_j = j dt, j = 1..steps."""
    return constant_acceleration(dt * np.arange(1, steps + 1))


def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def sinusoidal(t: np.ndarray, amplitude=(0.05, 0.05, 0.04, 0.08, 0.08, 0.1),
               frequency=(0.5, 0.7, 0.9, 0.6, 0.8, 0.4), phase=None,
               centre=(0.0, 0.0, HOME_HEIGHT)) -> Motion:
    """A smooth 6-DoF motion with exact velocities and accelerations.

    Position ``centre + A_k sin(2 pi f_k t + phi_k)`` (k = x, y, z); orientation
    ``Rz(psi) Ry(theta) Rx(phi)`` with each angle ``A sin(2 pi f t + phi)``. Angular velocity
    and acceleration follow analytically from the angle rates.

    Parameters
    ----------
    t : ndarray (N,), s
    amplitude, frequency, phase : 6 values each (x, y, z in m; psi, theta, phi in rad), Hz, rad
    """
    t = as_array(t, (None,), "t")
    A = np.asarray(amplitude, float)
    w = 2 * np.pi * np.asarray(frequency, float)
    ph = np.zeros(6) if phase is None else np.asarray(phase, float)
    arg = w * t[:, None] + ph
    q = A * np.sin(arg)
    qd = A * w * np.cos(arg)
    qdd = -A * w**2 * np.sin(arg)
    return pose_motion(t, q, qd, qdd, centre)


def home_centre(platform: Platform) -> tuple[float, float, float]:
    """The platform's home pose, m: level, at mid-stroke (``platform.usable.home_height``; the
    reference platform's height for a platform without a stroke)."""
    height = home_height(platform)
    return (0.0, 0.0, HOME_HEIGHT if height is None else height)


def resting_at_home(platform: Platform) -> Result:
    """The model of ``platform`` at rest at its home pose (``home_centre``), over 8 steps,
    flags included (no warning)."""
    still = sinusoidal(np.linspace(0.0, 1.0, 8), amplitude=np.zeros(6),
                       centre=home_centre(platform))
    return Evaluator(platform).evaluate_quiet(still)


CHECK_STEPS = 500
"""Steps of a record, spread evenly over it, along which the model's forces are computed to
check the measured ones' unit and sign (``check_measured_forces``): the unit check compares
loads within a factor of ``platform.usable.UNIT_RATIO``, the sign check their means, both
settled by a few hundred steps to far better than that."""


def check_measured_forces(platform: Platform, motion: Motion, forces: np.ndarray,
                          where: str = "", limit: float = UNIT_RATIO) -> None:
    """``InputError`` (prefixed ``where``, a file) for measured forces (N, 6), N, along
    ``motion`` in another unit than N (``check_forces``) or of the opposite sign
    (``check_force_sign``) against the model of ``platform`` along the same poses, rates and
    accelerations (``CHECK_STEPS`` of them; steps whose forces the model cannot give, at a
    singular pose, are left out, and without any the check is skipped). ``limit``: the
    factor between the loads beyond which the unit is another (``check_forces``)."""
    rows = np.unique(np.linspace(0, len(motion) - 1, min(len(motion), CHECK_STEPS)).astype(int))
    x = state_of(tuple(a[rows] for a in (motion.position, motion.rotation, motion.velocity,
                                         motion.omega, motion.acceleration, motion.alpha)))
    model = Evaluator(platform).actuator_forces(x)
    finite = np.isfinite(model).all(axis=1)
    if not finite.any():
        return
    measured = np.asarray(forces, float)[rows][finite]
    check_forces(float(np.mean(np.sum(np.abs(model[finite]), axis=1))), measured, where,
                 limit)
    check_force_sign(measured, model[finite], where)


def pose_motion(t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                centre=(0.0, 0.0, HOME_HEIGHT)) -> Motion:
    """The motion of pose coordinates and their exact rates.

    Parameters
    ----------
    t : ndarray (N,), s
    q, qd, qdd : ndarray (N, 6)
        x, y, z (m, added to ``centre``) and the angles psi, theta, phi (rad) of the
        orientation ``Rz(psi) Ry(theta) Rx(phi)``; their first and second time derivatives.
    centre : 3 values, m

    Returns
    -------
    Motion
        With the angular velocity and acceleration following analytically from the angle rates.
    """
    psi, theta, phi = q[:, 3], q[:, 4], q[:, 5]
    Rz, Ry, Rx = _rot(2, psi), _rot(1, theta), _rot(0, phi)
    Rzy = Rz @ Ry
    ez = np.array([0.0, 0.0, 1.0])
    ey_ = Rz[:, :, 1]
    ex_ = Rzy[:, :, 0]
    w1 = qd[:, 3:4] * ez
    w2 = qd[:, 4:5] * ey_
    w3 = qd[:, 5:6] * ex_
    omega = w1 + w2 + w3
    alpha = (qdd[:, 3:4] * ez + qdd[:, 4:5] * ey_ + np.cross(w1, w2)
             + qdd[:, 5:6] * ex_ + np.cross(w1 + w2, w3))
    return Motion.from_arrays(t=t, position=np.asarray(centre, float) + q[:, :3],
                              rotation=Rzy @ Rx, velocity=qd[:, :3], omega=omega,
                              acceleration=qdd[:, :3], alpha=alpha)


def random_motion(rng: np.random.Generator, t: np.ndarray, scale: float = 1.0) -> Motion:
    """A ``sinusoidal`` motion with random amplitudes, frequencies and phases (workspace-safe)."""
    amp = rng.uniform(0.2, 1.0, 6) * np.array([0.06, 0.06, 0.05, 0.1, 0.1, 0.12]) * scale
    freq = rng.uniform(0.2, 1.2, 6)
    phase = rng.uniform(0, 2 * np.pi, 6)
    return sinusoidal(t, amp, freq, phase)


def point_to_point(rng: np.random.Generator, samples: int, rate: float = 200.0,
                   amplitude=(0.03, 0.03, 0.02, 0.05, 0.05, 0.05), height: float = HOME_HEIGHT,
                   tilt: float = 0.2, move=(1.0, 2.0), rest=(0.3, 0.7)) -> Motion:
    """Minimum-jerk moves between random poses, each followed by a rest (about a quarter of
    the time at rest): the motion of a test rig driven from point to point.

    Each move lasts ``move`` and each rest ``rest`` (s, uniform between the two bounds: by
    default 1-2 s and 0.3-0.7 s); targets are uniform within +-``amplitude``.
    The motion is differentiated from its samples (``Motion.from_samples``), as measured
    poses would be.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the durations and targets.
    samples : int
        Number of samples N.
    rate : float, Hz
        Sampling rate; the samples are at ``t = k / rate``.
    amplitude : 6 values
        Largest offsets of x, y, z (m) and of the three ZXZ angles (rad) from the centre pose.
    height : float, m
        z of the centre pose.
    tilt : float, rad
        beta of the centre pose (away from the ZXZ angles' singularity at beta = 0).
    move, rest : (float, float), s
        Shortest and longest move and rest.
    """
    t = np.arange(samples) / rate
    pose = np.zeros((samples, 6))
    k, current = 0, np.zeros(6)
    while k < samples:
        steps, still = int(rng.uniform(*move) * rate), int(rng.uniform(*rest) * rate)
        target = rng.uniform(-1, 1, 6) * np.asarray(amplitude, float)
        s = np.linspace(0, 1, steps)
        seg = current + (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)[:, None] * (target - current)
        m = min(steps, samples - k)
        pose[k:k + m] = seg[:m]
        k += m
        m = min(still, samples - k)
        pose[k:k + m] = target
        k += m
        current = target
    position = pose[:, :3] + [0.0, 0.0, height]
    rotation = rotation_from_euler(pose[:, 3], pose[:, 4] + tilt, pose[:, 5])
    return Motion.from_samples(t, position, quaternion=quaternion_from_rotation(rotation))


def minimum_jerk_moves(t: np.ndarray, targets: np.ndarray, period: float, move: float) -> Motion:
    """Translations through ``targets`` (K, 3), m, the orientation fixed: from target k to
    k + 1 a minimum-jerk move of ``move`` s starting at ``k period`` s, then a rest until the
    next. Positions, velocities and accelerations in closed form at the times t (N,), s (not
    differentiated from samples: the true motion of a synthetic record)."""
    k = np.minimum((t // period).astype(int), len(targets) - 2)
    s = np.clip((t - k * period) / move, 0.0, 1.0)
    moving = (t - k * period) < move
    d = targets[k + 1] - targets[k]
    shape = [10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5,
             (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / move * moving,
             (60 * s - 180 * s ** 2 + 120 * s ** 3) / move ** 2 * moving]
    zero = np.zeros((len(t), 3))
    return Motion.from_arrays(t, targets[k] + shape[0][:, None] * d,
                              np.tile(np.eye(3), (len(t), 1, 1)), shape[1][:, None] * d, zero,
                              shape[2][:, None] * d, zero)
