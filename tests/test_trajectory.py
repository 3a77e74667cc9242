"""Motion and rotation helpers: conventions, differentiation accuracy, warnings, validation."""

from __future__ import annotations

import contextlib
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gsfric.errors import GsfricWarning, InputError
from gsfric.signal.rotations import (
    angular_rates,
    euler_from_rotation,
    quaternion_from_euler,
    quaternion_from_rotation,
    quaternion_multiply,
    rotation_from_euler,
    rotation_from_quaternion,
)
from gsfric.trajectory import MIN_SAMPLES, Motion

AXIS = np.array([1.0, 2.0, 2.0]) / 3
R0 = Rotation.from_euler("zxz", [0.4, 0.5, -0.3]).as_matrix()


def analytic(t: np.ndarray):
    """Rotation about the fixed axis AXIS by 0.3 sin(2t) after R0, plus a translation.

    Returns position, rotation and the exact velocity, omega, acceleration, alpha.
    """
    angle, rate, accel = 0.3 * np.sin(2 * t), 0.6 * np.cos(2 * t), -1.2 * np.sin(2 * t)
    rotation = Rotation.from_rotvec(angle[:, None] * AXIS).as_matrix() @ R0
    position = np.stack([0.1 * np.sin(t), 0.05 * np.cos(1.5 * t), 1 + 0.02 * t**2], axis=1)
    velocity = np.stack([0.1 * np.cos(t), -0.075 * np.sin(1.5 * t), 0.04 * t], axis=1)
    acceleration = np.stack([-0.1 * np.sin(t), -0.1125 * np.cos(1.5 * t), 0.04 + 0 * t], axis=1)
    return (position, rotation, velocity, rate[:, None] * AXIS, acceleration,
            accel[:, None] * AXIS)


def max_errors(motion: Motion, t: np.ndarray, skip: int) -> dict[str, float]:
    _, _, velocity, omega, acceleration, alpha = analytic(t)
    inner = slice(skip, len(t) - skip)
    return {name: float(np.abs(getattr(motion, name)[inner] - exact[inner]).max())
            for name, exact in (("velocity", velocity), ("omega", omega),
                                ("acceleration", acceleration), ("alpha", alpha))}


# -- rotation conventions -----------------------------------------------------------------------


def test_rotation_from_euler_is_the_papers_matrix():
    rng = np.random.default_rng(0)
    a, b, g = rng.uniform(-3, 3, (3, 50))
    r = rotation_from_euler(a, b, g)
    assert r.shape == (50, 3, 3)
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    np.testing.assert_allclose(r[:, 0, 0], ca * cg - cb * sa * sg, atol=1e-15)
    np.testing.assert_allclose(r[:, 0, 2], sb * sg, atol=1e-15)
    np.testing.assert_allclose(r[:, 2, 0], sb * sa, atol=1e-15)
    np.testing.assert_allclose(r[:, 2, 2], cb, atol=1e-15)
    scipy_matrix = Rotation.from_euler("zxz", np.stack([a, b, g], axis=1)).as_matrix()
    np.testing.assert_allclose(r, scipy_matrix, atol=1e-15)
    rz = lambda x: Rotation.from_euler("z", x).as_matrix()  # noqa: E731
    rx = lambda x: Rotation.from_euler("x", x).as_matrix()  # noqa: E731
    np.testing.assert_allclose(r[7], rz(g[7]) @ rx(b[7]) @ rz(a[7]), atol=1e-15)
    assert rotation_from_euler(0.1, 0.2, 0.3).shape == (3, 3)


@pytest.mark.parametrize("beta", [None, 0.0, np.pi, 1e-14])
def test_euler_from_rotation_round_trip(beta):
    rng = np.random.default_rng(1)
    angles = rng.uniform(-3, 3, (40, 3))
    angles[:, 1] = np.abs(angles[:, 1]) if beta is None else beta
    r = rotation_from_euler(*angles.T)
    back = euler_from_rotation(r)
    np.testing.assert_allclose(rotation_from_euler(*back.T), r, atol=1e-13)
    assert np.all((back[:, 1] >= 0) & (back[:, 1] <= np.pi))
    if beta is None:
        np.testing.assert_allclose(back, angles, atol=1e-12)


def test_quaternion_helpers_agree():
    rng = np.random.default_rng(2)
    angles = rng.uniform(-3, 3, (30, 3))
    r = rotation_from_euler(*angles.T)
    q = quaternion_from_euler(*angles.T)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(rotation_from_quaternion(q), r, atol=1e-14)
    q2 = quaternion_from_rotation(r)
    assert np.all(q2[:, 0] >= 0)
    np.testing.assert_allclose(np.abs(np.sum(q * q2, axis=1)), 1.0, atol=1e-14)
    xyzw = Rotation.from_matrix(r).as_quat()
    np.testing.assert_allclose(rotation_from_quaternion(np.roll(xyzw, 1, axis=1)), r, atol=1e-14)
    p, s = q[:5], q[5:10]
    np.testing.assert_allclose(rotation_from_quaternion(quaternion_multiply(p, s)),
                               rotation_from_quaternion(p) @ rotation_from_quaternion(s),
                               atol=1e-14)


# -- differentiation ----------------------------------------------------------------------------
#
# Measured maximum errors over interior samples (10 left out at each end) of the analytic motion
# on t in [0, 4], |omega| <= 0.6 rad/s, |alpha| <= 1.2 rad/s^2, |a| <= 0.11 m/s^2:
#   uniform, 201 samples, noise-free:  velocity 1.3e-8, omega 2.6e-7, acceleration 1.0e-8,
#                                      alpha 1.7e-7 (all samples: alpha 1.7e-4)
#   jittered (+-0.3 step), 201:        velocity 5.5e-7, omega 3.5e-6, acceleration 2.9e-5,
#                                      alpha 2.3e-4
#   uniform, 201, noise 1e-6:          velocity 1.4e-5, omega 5.2e-5, acceleration 1.2e-4,
#                                      alpha 7.2e-4
# The tolerances below leave a margin of about 10.


def test_from_samples_recovers_an_analytic_motion_uniform():
    t = np.linspace(0, 4, 201)
    position, rotation, *_ = analytic(t)
    motion = Motion.from_samples(t, position, quaternion=quaternion_from_rotation(rotation))
    errors = max_errors(motion, t, skip=10)
    assert errors["velocity"] < 1e-7
    assert errors["omega"] < 3e-6
    assert errors["acceleration"] < 1e-7
    assert errors["alpha"] < 2e-6
    assert max_errors(motion, t, skip=0)["alpha"] < 2e-3
    np.testing.assert_allclose(motion.position, position, atol=1e-9)
    np.testing.assert_allclose(motion.rotation, rotation, atol=1e-8)


def test_from_samples_recovers_an_analytic_motion_non_uniform():
    rng = np.random.default_rng(0)
    step = 0.02
    t = np.arange(201) * step + np.concatenate([[0], rng.uniform(-0.3, 0.3, 199) * step, [0]])
    position, rotation, *_ = analytic(t)
    motion = Motion.from_samples(t, position, quaternion=quaternion_from_rotation(rotation))
    errors = max_errors(motion, t, skip=10)
    assert errors["velocity"] < 6e-6
    assert errors["omega"] < 4e-5
    assert errors["acceleration"] < 3e-4
    assert errors["alpha"] < 3e-3


def test_from_samples_with_noise():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 4, 201)
    position, rotation, *_ = analytic(t)
    position = position + rng.normal(0, 1e-6, position.shape)
    quaternion = quaternion_from_rotation(rotation) + rng.normal(0, 1e-6, (201, 4))
    errors = max_errors(Motion.from_samples(t, position, quaternion=quaternion), t, skip=10)
    assert errors["velocity"] < 1.5e-4
    assert errors["omega"] < 5e-4
    assert errors["acceleration"] < 1.2e-3
    assert errors["alpha"] < 7e-3


def test_omega_is_in_the_base_frame():
    t = np.linspace(0, 4, 401)
    position, rotation, *_ = analytic(t)
    motion = Motion.from_samples(t, position, quaternion=quaternion_from_rotation(rotation))
    r_dot = np.gradient(motion.rotation, t, axis=0)
    skew = r_dot @ np.transpose(motion.rotation, (0, 2, 1))
    omega = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)
    np.testing.assert_allclose(omega[5:-5], motion.omega[5:-5], atol=1e-4)


def test_euler_and_quaternion_inputs_give_the_same_motion():
    t = np.linspace(0, 4, 101)
    position, rotation, *_ = analytic(t)
    from_quaternion = Motion.from_samples(t, position,
                                          quaternion=quaternion_from_rotation(rotation))
    from_euler = Motion.from_samples(t, position, euler=euler_from_rotation(rotation))
    for name in ("position", "rotation", "velocity", "omega", "acceleration", "alpha"):
        np.testing.assert_allclose(getattr(from_euler, name), getattr(from_quaternion, name),
                                   atol=1e-11, err_msg=name)


def test_quaternion_sign_flips_do_not_matter():
    t = np.linspace(0, 4, 101)
    position, rotation, *_ = analytic(t)
    q = quaternion_from_rotation(rotation)
    flipped = q * np.where(np.arange(101) % 3 == 0, -1.0, 1.0)[:, None] * 2.5
    a = Motion.from_samples(t, position, quaternion=q)
    b = Motion.from_samples(t, position, quaternion=flipped)
    np.testing.assert_allclose(b.omega, a.omega, atol=1e-12)
    np.testing.assert_allclose(b.alpha, a.alpha, atol=1e-12)


def test_level_pose_through_beta_zero():
    """The level pose is a fine orientation: a rotation about z crossing beta = 0 is smooth."""
    t = np.linspace(0, 2, 81)
    tilt = 0.2 * (t - 1.0)
    rotation = Rotation.from_rotvec(np.stack([tilt, 0 * t, 0.5 * t], axis=1)).as_matrix()
    motion = Motion.from_samples(t, np.zeros((81, 3)),
                                 quaternion=quaternion_from_rotation(rotation))
    assert np.isfinite(motion.alpha).all()
    assert np.abs(motion.omega[10:-10] - motion.omega[10:-10].mean(axis=0)).max() < 0.1


def test_explicit_window_and_polyorder():
    t = np.linspace(0, 4, 201)
    position, rotation, *_ = analytic(t)
    q = quaternion_from_rotation(rotation)
    motion = Motion.from_samples(t, position, quaternion=q, window=21, polyorder=3)
    assert max_errors(motion, t, skip=10)["alpha"] < 1e-2


# -- warnings -----------------------------------------------------------------------------------


def euler_motion(n=40):
    t = np.linspace(0, 3.9, n)
    euler = np.stack([0.1 * t, 0.3 + 0.05 * np.sin(t), -0.2 * t], axis=1)
    return t, np.zeros((n, 3)), euler


def test_degrees_warning():
    t, position, euler = euler_motion()
    with pytest.warns(GsfricWarning, match=r"^angles look like degrees \(.*\|beta\| up to"):
        Motion.from_samples(t, position, euler=np.degrees(euler) + [0, 20, 0])


def test_gimbal_jump_warning_names_the_samples():
    t, position, euler = euler_motion()
    euler[:, 1] = 1e-5
    euler[20:, 0] += 1.5
    euler[20:, 2] -= 1.5
    with pytest.warns(GsfricWarning, match=r"near beta = 0 .* at sample 20; give the "
                                           r"orientation as a quaternion"):
        motion = Motion.from_samples(t, position, euler=euler)
    smooth = euler_motion()[2]
    smooth[:, 1] = 1e-5
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reference = Motion.from_samples(t, position, euler=smooth)
    np.testing.assert_allclose(motion.rotation, reference.rotation, atol=1e-4)


def test_no_warning_for_clean_angles_or_wrapping():
    t, position, euler = euler_motion()
    euler[:, 0] = np.angle(np.exp(1j * 2.0 * t))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Motion.from_samples(t, position, euler=euler)


# -- validation and helpers ---------------------------------------------------------------------


def test_from_samples_errors():
    t, position, euler = euler_motion(10)
    cases = [
        (dict(t=t[:5], position=position[:5], euler=euler[:5]),
         "5 samples; at least 7 are needed to differentiate"),
        (dict(t=t, position=position), "give the orientation as exactly one of"),
        (dict(t=t, position=position, euler=euler, quaternion=np.ones((10, 4))),
         "give the orientation as exactly one of"),
        (dict(t=t[::-1], position=position, euler=euler), "sample 1: t does not increase"),
        (dict(t=t, position=position[:, :2], euler=euler),
         r"position: expected an array of shape \(10, 3\), got \(10, 2\)"),
        (dict(t=t, position=position, euler=euler, window=8), "window must be odd, got 8"),
        (dict(t=t, position=position, euler=euler, window=11), "window = 11 is longer than"),
        (dict(t=t, position=position, euler=euler, window=3), "window = 3 must exceed polyorder"),
        (dict(t=t, position=position, euler=euler, polyorder=1), "polyorder must be an integer"),
        (dict(t=t, position=position, euler=euler, polyorder=9), "polyorder = 9 needs more"),
        (dict(t=t, position=position, quaternion=np.zeros((10, 4))),
         "sample 0: quaternion of zero length"),
        (dict(t=t, position=np.where(t[:, None] > 1, np.nan, position), euler=euler),
         r"position\[3\]\[0\]: must be finite, got nan"),
        (dict(t=t * 1e-300, position=position + t[:, None] * 1e300, euler=euler),
         "a sampling rate of 2.308e[+]300 Hz, outside 1 Hz .. 1e[+]06 Hz"),
    ]
    for kwargs, message in cases:
        # seconds of 1e-300 and metres of 1e300 are read as wrong units first
        units = (pytest.warns(GsfricWarning, match="must be in")
                 if message == "non-finite values" else contextlib.nullcontext())
        with pytest.raises(InputError, match=message), units:
            Motion.from_samples(**kwargs)
    with pytest.raises(InputError, match=r"^data.csv: row 2: t does not increase"):
        Motion.from_samples(t[::-1], position, euler=euler, source="data.csv")


def test_motion_validation_and_helpers():
    t = np.linspace(0, 1, 12)
    position, rotation, velocity, omega, acceleration, alpha = analytic(t)
    motion = Motion.from_arrays(t, position, rotation, velocity, omega, acceleration, alpha)
    assert len(motion) == 12
    assert motion == Motion(t, position, rotation, velocity, omega, acceleration, alpha)
    with pytest.raises(ValueError):
        motion.position[0, 0] = 1.0
    part = motion.slice(2, 5)
    assert len(part) == 3
    np.testing.assert_array_equal(part.alpha, alpha[2:5])
    assert len(motion.slice(-4)) == 4
    with pytest.raises(InputError, match="no steps"):
        motion.slice(5, 5)
    frame = motion.to_frame()
    assert list(frame.columns) == ["t", "x", "y", "z", "qw", "qx", "qy", "qz",
                                   "alpha", "beta", "gamma"]
    np.testing.assert_allclose(rotation_from_euler(frame["alpha"], frame["beta"],
                                                   frame["gamma"]), rotation, atol=1e-14)
    np.testing.assert_allclose(rotation_from_quaternion(frame[["qw", "qx", "qy", "qz"]]
                                                        .to_numpy()), rotation, atol=1e-14)
    wide = motion.to_frame(derivatives=True)
    np.testing.assert_array_equal(wide["alpha_z"], alpha[:, 2])
    np.testing.assert_array_equal(wide["omega_x"], omega[:, 0])

    bad_rotation = rotation.copy()
    bad_rotation[3] *= 1.1
    with pytest.raises(InputError, match=r"Motion.rotation\[3\]: not a rotation matrix"):
        Motion(t, position, bad_rotation, velocity, omega, acceleration, alpha)
    mirrored = rotation.copy()
    mirrored[4] = -mirrored[4]
    with pytest.raises(InputError, match=r"Motion.rotation\[4\]: .*det = -1"):
        Motion(t, position, mirrored, velocity, omega, acceleration, alpha)
    with pytest.raises(InputError, match=r"Motion.omega: expected an array of shape \(12, 3\)"):
        Motion(t, position, rotation, velocity, omega[:5], acceleration, alpha)
    with pytest.raises(InputError, match=r"Motion.alpha\[2\]\[0\]: must be finite"):
        Motion(t, position, rotation, velocity, omega, acceleration,
               np.where(np.arange(12)[:, None] == 2, np.inf, alpha))
    assert MIN_SAMPLES == 7


def test_angular_rates_of_a_uniformly_accelerated_turn():
    """q(t) = (cos(phi/2), sin(phi/2) n) with phi = w0 t + a t^2 / 2 about the unit axis n:
    omega = phi' n and alpha = phi'' n, also for a quaternion scaled by 3 (not unit)."""
    t = np.linspace(0.0, 2.0, 9)[:, None]
    w0, a = 0.7, -0.3
    phi, rate = w0 * t + a * t**2 / 2, w0 + a * t
    half = np.hstack([np.cos(phi / 2), np.sin(phi / 2) * AXIS])
    turned = np.hstack([-np.sin(phi / 2), np.cos(phi / 2) * AXIS])
    q0, q1 = 3 * half, 3 * turned * rate / 2
    q2 = 3 * (-half * (rate / 2) ** 2 + turned * a / 2)
    omega, alpha = angular_rates(q0, q1, q2)
    np.testing.assert_allclose(omega, rate * AXIS, atol=1e-14)
    np.testing.assert_allclose(alpha, np.broadcast_to(a * AXIS, alpha.shape), atol=1e-14)
