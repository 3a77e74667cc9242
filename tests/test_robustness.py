"""Robustness of the evaluation: step flags, friction at zero speed, the level pose, bad input
to the API, and the streamed evaluation of long files (docs/explanation/robustness.md)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner
from scipy.interpolate import make_smoothing_spline
from scipy.spatial.transform import Rotation

import gsfric
from gsfric import models
from gsfric.cli import main
from gsfric.errors import GsfricWarning, InputError, StepFlagError
from gsfric.evaluation.evaluator import Evaluator
from gsfric.simulate.api import evaluate
from gsfric.evaluation.flags import (
    COND_LIMIT,
    FLAG_NONFINITE,
    FLAG_SINGULAR,
    FLAG_STROKE,
    FLAG_UNIVERSAL,
    SINGULAR_LIMIT,
    UNIVERSAL_LIMIT,
)
from gsfric.evaluation.parameters import JOINT_EPS, PRISMATIC_EPS
from gsfric.io.readers import read_measured, read_trajectory
from gsfric.io.tables import write_table
from gsfric.signal import spline as tr
from gsfric.signal.rotations import (
    euler_from_rotation,
    quaternion_from_rotation,
    rotation_from_euler,
)
from gsfric.signal.savgol import savgol_derivatives
from gsfric.simulate.differentiate import iter_motions
from gsfric.simulate.run import simulate_file
from gsfric.trajectory import Motion

ROOT = Path(__file__).resolve().parent.parent
BENCHMARK = ROOT / "benchmarks" / "memory_10M.py"
HOME = np.array([0.0, 0.0, models.HOME_HEIGHT])
OUTPUTS = ("F", "F0", "R_E", "R_C", "M_C", "R_3", "M_3", "MfrE", "MfrC", "Ffr", "MfrE_s",
           "MfrC_s", "Ffr_s", "D", "D_dot")


@pytest.fixture(scope="module")
def evaluator():
    return Evaluator(models.reference_platform())


@pytest.fixture(scope="module", params=["coupled", "paper"])
def model_evaluator(request):
    """The reference platform with either friction model."""
    return Evaluator(models.reference_platform(request.param))


def coulomb_level(platform, result):
    """The prismatic joint's Coulomb force (N, per step and leg) at full sliding speed: mu |R_3|
    in the paper's model, mu (|N_a| + |N_b|) in the coupled one; plus the seal in both."""
    fr = platform.friction
    if fr.model == "paper":
        load = np.linalg.norm(result.R_3, axis=2)
    else:
        load = result.N_bushing.sum(axis=2)
    return fr.prismatic_coulomb * load + fr.prismatic_seal


def poses(position, rotation=None, velocity=None, omega=None, acceleration=None,
          alpha=None) -> Motion:
    """A Motion of independent poses (zero rates unless given); t = 0, 1, 2, ..."""
    position = np.atleast_2d(np.asarray(position, float))
    n = len(position)
    zero = np.zeros((n, 3))
    rotation = np.broadcast_to(np.eye(3), (n, 3, 3)) if rotation is None else rotation

    def rate(value):
        return zero if value is None else np.broadcast_to(np.asarray(value, float), (n, 3))

    return Motion(np.arange(n, dtype=float), position, rotation, rate(velocity), rate(omega),
                  rate(acceleration), rate(alpha))


def quiet(function, *args, **kwargs):
    """Call without the flag warning; return the result."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"[0-9]+ of [0-9]+ steps flagged")
        return function(*args, **kwargs)


def assert_flagged_where_not_finite(result):
    """Every non-finite output value sits on a flagged step; FLAG_NONFINITE steps are all NaN."""
    for name in OUTPUTS:
        values = getattr(result, name).reshape(len(result), -1)
        bad = ~np.isfinite(values).all(axis=1)
        assert not (bad & (result.flag == 0)).any(), name
        nonfinite = (result.flag & FLAG_NONFINITE) != 0
        assert np.isnan(values[nonfinite]).all(), name


def condition_numbers(platform, result, rotation) -> np.ndarray:
    """cond of the 6x6 force Jacobian, columns (u_i, (E_i - p) x u_i), computed here."""
    arm = np.einsum("nij,kj->nki", rotation, platform.geometry.platform_joints)
    return np.linalg.cond(np.concatenate([result.u, np.cross(arm, result.u)], axis=2))


def scaled_jacobian(platform, result, rotation) -> np.ndarray:
    """The force Jacobian with its moment rows in units of the platform's size L, columns
    scaled to unit length, (N, 6, 6), computed here with NumPy."""
    e = platform.geometry.platform_joints
    size = np.sqrt(np.mean(np.sum(e * e, axis=1)))
    arm = np.einsum("nij,kj->nki", rotation, e)
    A = np.concatenate([result.u, np.cross(arm, result.u) / size], axis=2)  # (N, leg, 6)
    return A / np.linalg.norm(A, axis=2, keepdims=True)


# -- 1. step flags ------------------------------------------------------------------------------


def test_pose_beyond_the_stroke_is_flagged_with_its_indices(evaluator):
    z = np.full(8, models.HOME_HEIGHT)
    z[[3, 4, 5]] = 1.4                      # legs longer than the stroke's 1.1 m
    motion = poses(np.column_stack([np.zeros(8), np.zeros(8), z]))
    with pytest.warns(GsfricWarning, match=r"^3 of 8 steps flagged \(leg length outside the "
                                           r"stroke\): steps 3, 4, 5$") as caught:
        result = evaluator.evaluate(motion)
    assert {type(w.message) for w in caught} == {GsfricWarning}     # the documented class
    np.testing.assert_array_equal(result.flagged(), [3, 4, 5])
    assert (result.flag[[3, 4, 5]] & FLAG_STROKE).all()
    assert (result.D[[3, 4, 5]] > 1.1).any(axis=1).all()
    # the flagged steps keep their (finite) values: a pose out of the stroke is still a pose
    assert np.isfinite(result.F).all()
    with pytest.raises(StepFlagError, match=r"steps 3, 4, 5"):
        evaluator.evaluate(motion, strict=True)


def test_without_a_stroke_there_is_no_stroke_flag():
    platform = models.reference_platform().with_geometry(stroke=None)
    motion = poses([[0.0, 0.0, 1.4]] * 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        warnings.filterwarnings("ignore", message="generated/ is stale")
        result = evaluate(platform, motion)
    assert not result.flag.any()


def test_flag_message_lists_ten_indices_then_a_count(evaluator):
    motion = poses([[0.0, 0.0, 1.4]] * 25)
    with pytest.raises(StepFlagError, match=r"^25 of 25 steps flagged .*: steps 0, 1, 2, 3, 4, "
                                            r"5, 6, 7, 8, 9, \.\.\. \(15 more\)$"):
        evaluator.evaluate(motion, strict=True)


def test_overflowing_input_is_flagged_non_finite_and_set_to_nan(evaluator):
    position = np.tile(HOME, (5, 1))
    position[2] = [1e200, 0.0, 1e200]       # finite input, overflowing outputs
    result = quiet(evaluator.evaluate, poses(position))
    assert result.flag[2] & FLAG_NONFINITE
    assert result.flag[[0, 1, 3, 4]].tolist() == [0, 0, 0, 0]
    assert_flagged_where_not_finite(result)
    # steps are independent: the bad step leaves the others as they are alone
    alone = evaluator.evaluate(poses(np.tile(HOME, (2, 1))))
    np.testing.assert_array_equal(result.F[[0, 4]], alone.F)


@pytest.mark.parametrize("offset", [0.0, 1e-9, 1e-7])
def test_near_singular_jacobian_is_flagged(evaluator, offset):
    """The reference hexapod is singular when turned by 90 degrees about z (cond ~ 1e16)."""
    angles = np.pi / 2 + np.array([-offset, offset, 0.3, -0.3])
    rotation = Rotation.from_rotvec(angles[:, None] * [0.0, 0.0, 1.0]).as_matrix()
    result = quiet(evaluator.evaluate, poses(np.tile(HOME, (4, 1)), rotation))
    cond = condition_numbers(evaluator.platform, result, rotation)
    assert (cond[:2] > COND_LIMIT).all() and (cond[2:] < 100).all()
    np.testing.assert_array_equal((result.flag & FLAG_SINGULAR) != 0, cond >= COND_LIMIT)
    np.testing.assert_array_equal((result.flag & FLAG_SINGULAR) != 0, result.h < SINGULAR_LIMIT)
    assert_flagged_where_not_finite(result)


def test_singular_flag_follows_the_documented_threshold(evaluator):
    """Flagged exactly where h < SINGULAR_LIMIT; h is the Hadamard ratio of the scaled
    Jacobian (|det| over the product of column norms, here by NumPy), and every unflagged
    step has a scaled, column-normalised condition number below COND_LIMIT (the bound 2 / h)."""
    offsets = np.geomspace(1e-9, 1e-1, 41)
    rotation = Rotation.from_rotvec((np.pi / 2 + offsets)[:, None] * [0, 0, 1.0]).as_matrix()
    result = quiet(evaluator.evaluate, poses(np.tile(HOME, (41, 1)), rotation))
    A = scaled_jacobian(evaluator.platform, result, rotation)
    hadamard = np.abs(np.linalg.det(A))
    np.testing.assert_allclose(result.h, hadamard, rtol=1e-6, atol=1e-12)
    cond = np.linalg.cond(A)
    flagged = (result.flag & FLAG_SINGULAR) != 0
    assert flagged.any() and not flagged.all()
    np.testing.assert_array_equal(flagged, result.h < SINGULAR_LIMIT)
    assert (cond[~flagged] < COND_LIMIT).all()
    assert (cond[~flagged] <= 2 / result.h[~flagged]).all()


def test_singularity_measure_is_independent_of_the_platform_size():
    """Every length of platform and motion times 1000: the same h and the same flags."""
    platform = models.reference_platform()
    g = platform.geometry
    with pytest.warns(GsfricWarning, match="lengths must be in m, not mm"):
        big = platform.with_geometry(base_joints=1000 * g.base_joints,
                                     platform_joints=1000 * g.platform_joints, stroke=None)
    rotation = Rotation.from_rotvec(np.linspace(1.2, 1.7, 30)[:, None] * [0, 0, 1.0]).as_matrix()
    small = quiet(evaluate, platform.with_geometry(stroke=None),
                  poses(np.tile(HOME, (30, 1)), rotation))
    large = quiet(evaluate, big, poses(np.tile(1000 * HOME, (30, 1)), rotation))
    np.testing.assert_allclose(large.h, small.h, rtol=1e-9)
    np.testing.assert_array_equal(large.flag & FLAG_SINGULAR, small.flag & FLAG_SINGULAR)


def test_parallel_legs_are_singular():
    """A degenerate design (platform joints above the base joints: six vertical legs)."""
    platform = models.reference_platform()
    base = platform.geometry.base_joints
    degenerate = platform.with_geometry(platform_joints=base, stroke=None)
    result = quiet(evaluate, degenerate, poses(np.tile(HOME, (3, 1))))
    assert (result.flag & FLAG_SINGULAR).all()
    assert_flagged_where_not_finite(result)


def _aligned_universal_platform(angle: float):
    """Leg 1's universal-joint axis a1 at ``angle`` rad from the leg at the home pose."""
    platform = models.reference_platform()
    g = platform.geometry
    u = HOME + g.platform_joints[0] - g.base_joints[0]
    u /= np.linalg.norm(u)
    side = np.cross(u, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    axes = np.array(g.universal_axes)
    axes[0] = np.cos(angle) * u + np.sin(angle) * side
    return platform.with_geometry(universal_axes=axes)


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-4, 5e-3])
def test_leg_along_its_universal_axis_is_flagged(angle):
    platform = _aligned_universal_platform(angle)
    result = quiet(evaluate, platform, poses(np.tile(HOME, (3, 1))))
    assert np.sin(angle) ** 2 < UNIVERSAL_LIMIT
    assert (result.flag & FLAG_UNIVERSAL).all(), result.flag
    # exactly along the axis the joint's second axis is undefined: NaN, but flagged as such
    # and still named as the universal joint's problem (not as a singular Jacobian)
    assert not (result.flag & FLAG_SINGULAR).any()
    assert_flagged_where_not_finite(result)


def test_leg_clear_of_its_universal_axis_is_not_flagged():
    result = evaluate(_aligned_universal_platform(0.02), poses(np.tile(HOME, (3, 1))))
    assert not result.flag.any()
    assert np.isfinite(result.M_C).all()


def test_flags_combine_bits(evaluator):
    rotation = Rotation.from_rotvec([[0, 0, np.pi / 2]] * 2).as_matrix()
    result = quiet(evaluator.evaluate, poses([[0.0, 0.0, 1.4], HOME], rotation))
    assert result.flag[0] & FLAG_STROKE
    assert result.flag[1] & FLAG_SINGULAR


def test_flag_column_in_the_frame(evaluator):
    motion = poses([HOME, [0.0, 0.0, 1.4], HOME])
    frame = quiet(evaluator.evaluate, motion).to_frame()
    assert frame["flag"].tolist() == [0, FLAG_STROKE, 0]


# -- 2. friction at zero speed and through reversals --------------------------------------------


def test_friction_at_rest_is_zero_and_finite(evaluator):
    result = evaluator.evaluate(poses(np.tile(HOME, (3, 1))))
    for name in ("MfrE", "MfrC", "Ffr", "MfrE_s", "MfrC_s", "Ffr_s"):
        values = getattr(result, name)
        assert np.isfinite(values).all()
        np.testing.assert_array_equal(values, 0.0)   # the Coulomb part vanishes at zero speed
    np.testing.assert_allclose(result.F, result.F0, rtol=0, atol=1e-12)
    assert not result.flag.any()


SPEEDS = [0.0, 5e-324, 1e-300, 1e-12, 1e-9, PRISMATIC_EPS / 10, PRISMATIC_EPS,
          10 * PRISMATIC_EPS, 1e-3, 0.1, 1.0]


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_prismatic_friction_is_the_regularised_law_at_every_speed(model_evaluator, sign):
    evaluator = model_evaluator
    speeds = sign * np.array(SPEEDS)
    motion = poses(np.tile(HOME, (len(speeds), 1)), velocity=speeds[:, None] * [0, 0, 1.0])
    result = evaluator.evaluate(motion)
    fr = evaluator.platform.friction
    v = result.D_dot
    assert np.isfinite(result.Ffr).all() and np.isfinite(result.Ffr_s).all()
    coulomb = coulomb_level(evaluator.platform, result)
    expected = -(fr.prismatic_viscous * v + coulomb * v / np.sqrt(v * v + PRISMATIC_EPS**2))
    np.testing.assert_allclose(result.Ffr, expected, rtol=1e-9, atol=1e-300)
    assert (result.Ffr * v <= 0).all()                          # always opposes the motion
    assert (np.abs(result.Ffr) <= fr.prismatic_viscous * np.abs(v) + coulomb + 1e-12).all()
    if fr.model == "paper":
        np.testing.assert_allclose(result.Ffr_s, -np.abs(result.Ffr), rtol=1e-9, atol=1e-300)


def test_stiction_band_fractions(model_evaluator):
    """Coulomb part at |v| = eps, 3 eps, 10 eps, 1000 eps: 71 %, 95 %, 99.5 %, 1 - 5e-7."""
    factors = np.array([1.0, 3.0, 10.0, 1000.0])
    motion = poses(np.tile(HOME, (4, 1)), velocity=(factors * PRISMATIC_EPS)[:, None]
                   * [0, 0, 1.0])
    platform = model_evaluator.platform.with_friction(prismatic_viscous=0.0)
    result = evaluate(platform, motion)
    v = result.D_dot
    fraction = -result.Ffr / (coulomb_level(platform, result) * np.sign(v))
    speed_in_eps = np.abs(v) / PRISMATIC_EPS
    np.testing.assert_allclose(fraction, speed_in_eps / np.sqrt(speed_in_eps**2 + 1), rtol=1e-9)
    assert fraction[0].min() > 0.3 and fraction[-1].min() > 1 - 1e-5


@pytest.mark.parametrize("omega_z", [0.0, 1e-300, 1e-10, JOINT_EPS, -JOINT_EPS, 1.0])
def test_joint_friction_is_the_regularised_law(evaluator, omega_z):
    motion = poses(np.tile(HOME, (1, 1)), omega=[0.0, 0.0, omega_z])
    result = evaluator.evaluate(motion)
    fr = evaluator.platform.friction
    w = result.omega_rel
    speed2 = np.sum(w * w, axis=2, keepdims=True)
    RE = np.linalg.norm(result.R_E, axis=2)[..., None]
    expected = -(fr.joint_viscous * w + fr.joint_coulomb * fr.joint_radius * RE * w
                 / np.sqrt(speed2 + JOINT_EPS**2))
    np.testing.assert_allclose(result.MfrE, expected, rtol=1e-9, atol=1e-300)
    for name in ("MfrE", "MfrC", "MfrE_s", "MfrC_s"):
        assert np.isfinite(getattr(result, name)).all()
    assert (np.sum(result.MfrE * w, axis=2) <= 0).all()


def test_friction_through_a_reversal_is_continuous(model_evaluator):
    """The sliding speed ramps from -20 eps to +20 eps: friction changes sign through zero
    without a spike; consecutive steps differ by at most the law's Lipschitz bound."""
    evaluator = model_evaluator
    n = 4001
    t = np.linspace(0.0, 1.0, n)
    V = 20 * PRISMATIC_EPS
    velocity = (V * (2 * t - 1))[:, None] * [0.3, 0.0, 1.0]
    acceleration = np.broadcast_to(2 * V * np.array([0.3, 0.0, 1.0]), (n, 3))
    motion = Motion(t, np.tile(HOME, (n, 1)), np.broadcast_to(np.eye(3), (n, 3, 3)),
                    velocity, np.zeros((n, 3)), acceleration, np.zeros((n, 3)))
    result = evaluator.evaluate(motion)
    assert np.isfinite(result.Ffr).all() and np.isfinite(result.F).all()
    fr = evaluator.platform.friction
    v, ffr = result.D_dot, result.Ffr
    assert (ffr * v <= 0).all()
    for leg in range(6):
        changes = np.flatnonzero(np.diff(np.sign(v[:, leg])) != 0)
        np.testing.assert_array_equal(np.flatnonzero(np.diff(np.sign(ffr[:, leg])) != 0),
                                      changes)
    coulomb = coulomb_level(evaluator.platform, result)
    lipschitz = fr.prismatic_viscous + coulomb.max() / PRISMATIC_EPS
    assert np.abs(np.diff(ffr, axis=0)).max() <= 1.01 * lipschitz * np.abs(np.diff(v, axis=0)
                                                                             ).max()
    # and it reaches the Coulomb level away from the reversal
    assert (np.abs(ffr[[0, -1]]) > 0.99 * coulomb[[0, -1]]).all()


# -- 3. the level pose: quaternions and Euler jumps ----------------------------------------------


def _level_crossing(n: int = 201):
    """A rotation about z with a small tilt passing through the level pose (beta = 0)."""
    t = np.linspace(0.0, 2.0, n)
    tilt = 0.05 * (t - 1.0)
    rotation = Rotation.from_rotvec(np.stack([tilt, 0 * t, 0.4 * t], axis=1)).as_matrix()
    position = HOME + 0.01 * np.stack([np.sin(t), np.cos(t), t], axis=1)
    return t, position, rotation


def test_euler_angles_from_measured_rotations_jump_at_the_level_pose():
    t, position, rotation = _level_crossing()
    euler = euler_from_rotation(rotation)
    # exactly level at the middle sample: alpha and gamma are undefined there and jump
    assert abs(euler[100, 1]) < 1e-12
    assert np.abs(np.diff(euler[:, 0])).max() > 0.5


def test_euler_jumps_are_reported_and_not_differentiated(evaluator):
    t, position, rotation = _level_crossing()
    euler = euler_from_rotation(rotation)
    with pytest.warns(GsfricWarning, match=r"near beta = 0 .* at sample"):
        from_euler = Motion.from_samples(t, position, euler=euler)
    from_quaternion = Motion.from_samples(t, position,
                                          quaternion=quaternion_from_rotation(rotation))
    for name in ("rotation", "omega", "alpha"):
        np.testing.assert_allclose(getattr(from_euler, name), getattr(from_quaternion, name),
                                   atol=1e-9, err_msg=name)
    # no spike where the angles jump: omega stays near the true 0.4 rad/s about z
    assert np.abs(from_euler.omega[10:-10, 2] - 0.4).max() < 0.01
    a, b = evaluator.evaluate(from_euler), evaluator.evaluate(from_quaternion)
    np.testing.assert_allclose(a.F, b.F, atol=1e-8)


def test_quaternion_input_at_the_level_pose_gives_no_warning():
    t, position, rotation = _level_crossing()
    with warnings.catch_warnings():
        warnings.simplefilter("error", GsfricWarning)
        Motion.from_samples(t, position, quaternion=quaternion_from_rotation(rotation))


def test_rotation_matrices_are_used_internally():
    """The paper's b_ij at beta = 0: a rotation about z by alpha + gamma, nothing singular."""
    R = rotation_from_euler(0.3, 0.0, 0.5)
    np.testing.assert_allclose(R, Rotation.from_rotvec([0, 0, 0.8]).as_matrix(), atol=1e-15)


# -- 4. validation across the API ---------------------------------------------------------------


def _samples(n=20):
    t = np.linspace(0, 1, n)
    return t, np.tile(HOME, (n, 1)), np.zeros((n, 3))


@pytest.mark.parametrize(("change", "message"), [
    (dict(position=np.zeros((20, 2))), r"^position: expected an array of shape \(20, 3\), got "
                                       r"\(20, 2\)$"),
    (dict(euler=np.zeros((19, 3))), r"^euler: expected an array of shape \(20, 3\)"),
    (dict(euler=np.full((20, 3), "a")), r"^euler: expected an array of numbers, got dtype <U1$"),
    (dict(position=[[0, 0, "x"]] * 20), r"^position: expected an array of shape \(20, 3\) of "
                                        r"numbers, found 'x'$"),
    (dict(t=np.r_[np.linspace(0, 1, 19), np.nan]), r"^t\[19\]: must be finite, got nan$"),
    (dict(position=np.r_[np.zeros((19, 3)), [[0, np.inf, 0]]]),
     r"^position\[19\]\[1\]: must be finite, got inf$"),
    (dict(euler=None, quaternion=np.zeros((20, 4))), r"^sample 0: quaternion of zero length$"),
    (dict(t=np.linspace(0, 1, 5), position=np.zeros((5, 3)), euler=np.zeros((5, 3))),
     r"^5 samples; at least 7"),
    (dict(window=4), r"^window must be odd, got 4$"),
])
def test_from_samples_names_the_field(change, message):
    t, position, euler = _samples()
    kwargs = dict(t=t, position=position, euler=euler)
    kwargs.update(change)
    with pytest.raises(InputError, match=message):
        Motion.from_samples(kwargs.pop("t"), kwargs.pop("position"), **kwargs)


def test_degrees_warning_names_the_angle():
    t, position, _ = _samples()
    euler = np.column_stack([np.linspace(0, 90, 20), np.full(20, 30.0), np.zeros(20)])
    with pytest.warns(GsfricWarning, match=r"angles look like degrees \(\|alpha\| up to 90, "
                                           r"\|beta\| up to 30 > 2\*pi\)"):
        Motion.from_samples(t, position, euler=euler)


def test_motion_rejects_non_finite_and_non_rotations():
    n = 3
    good = dict(t=np.arange(n, dtype=float), position=np.zeros((n, 3)),
                rotation=np.broadcast_to(np.eye(3), (n, 3, 3)), velocity=np.zeros((n, 3)),
                omega=np.zeros((n, 3)), acceleration=np.zeros((n, 3)), alpha=np.zeros((n, 3)))
    bad = dict(good, omega=np.r_[np.zeros((2, 3)), [[0, np.nan, 0]]])
    with pytest.raises(InputError, match=r"^Motion.omega\[2\]\[1\]: must be finite"):
        Motion(**bad)
    bad = dict(good, rotation=np.broadcast_to(2 * np.eye(3), (n, 3, 3)))
    with pytest.raises(InputError, match=r"^Motion.rotation\[0\]: not a rotation matrix"):
        Motion(**bad)
    with pytest.raises(InputError, match=r"^Motion.velocity: expected an array of shape"):
        Motion(**dict(good, velocity=np.zeros((n, 4))))


def test_evaluator_names_a_bad_mode():
    with pytest.raises(InputError, match=r"^mode: unknown mode 'papr'"):
        Evaluator(models.reference_platform(), mode="papr")


def test_platform_names_unknown_keys_and_effects():
    data = models.reference_platform().to_dict()
    data["friction"]["joint_colomb"] = data["friction"].pop("joint_coulomb")
    with pytest.raises(InputError, match=r"^p.toml: friction.joint_colomb: unknown key \(did "
                                         r"you mean 'joint_coulomb'\?\)$"):
        gsfric.Platform.from_dict(data, source="p.toml")
    data = models.reference_platform().to_dict()
    data["effects"] = {"stribek": {}}
    with pytest.raises(InputError, match=r"^p.toml: effects.stribek: unknown effect \(did you "
                                         r"mean 'stribeck'\?\)$"):
        gsfric.Platform.from_dict(data, source="p.toml")


# -- 5. streamed evaluation ---------------------------------------------------------------------


def _trajectory_frame(n: int, orientation: str = "quaternion", noise: float = 1e-5,
                      seed: int = 0, rate: float = 100.0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    motion = models.sinusoidal(t)
    frame = pd.DataFrame({"t": t})
    frame[["x", "y", "z"]] = motion.position + rng.normal(0, noise, (n, 3))
    if orientation == "quaternion":
        frame[["qw", "qx", "qy", "qz"]] = motion.quaternion()
    else:
        frame[["alpha", "beta", "gamma"]] = motion.euler()
    return frame


def _concatenated(parts):
    names = ("t", "position", "rotation", "velocity", "omega", "acceleration", "alpha")
    return {k: np.concatenate([getattr(p.motion, k) for p in parts]) for k in names}


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
@pytest.mark.parametrize(("chunk", "window"), [(50, 11), (97, 21), (31, 31), (7, 5), (600, 9)])
def test_chunked_differentiation_equals_the_whole_file(tmp_path, suffix, chunk, window):
    path = tmp_path / f"trajectory{suffix}"
    write_table(_trajectory_frame(613), path)
    whole = read_trajectory(path, window=window)
    parts = list(iter_motions(path, chunk=chunk, window=window))
    starts = [p.start for p in parts]
    assert starts == list(range(0, 613, chunk))[:len(parts)]
    assert all(len(p.motion) >= chunk for p in parts[:-1]) \
        and sum(len(p.motion) for p in parts) == 613
    for name, values in _concatenated(parts).items():
        np.testing.assert_allclose(values, getattr(whole, name), rtol=1e-12, atol=1e-12,
                                   err_msg=name)


def test_chunked_differentiation_with_the_window_of_the_first_chunk(tmp_path):
    path = tmp_path / "trajectory.csv"
    write_table(_trajectory_frame(2000, noise=1e-4), path)
    parts = list(iter_motions(path, chunk=300))
    wp, wq = parts[0].windows
    assert wp > 7                                    # the noise needs a longer window
    position = np.concatenate([p.motion.position for p in parts])
    frame = pd.read_csv(path)
    expected = savgol_derivatives(frame[["x", "y", "z"]].to_numpy(), wp, 4, 0.01)
    np.testing.assert_allclose(position, expected[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.concatenate([p.motion.velocity for p in parts]), expected[1],
                               rtol=1e-10, atol=1e-10)


def test_quaternion_signs_are_continuous_across_chunks(tmp_path):
    frame = _trajectory_frame(400)
    flipped = frame.copy()
    signs = np.where((np.arange(400) // 37) % 2 == 0, 1.0, -1.0)   # flips inside and at edges
    flipped[["qw", "qx", "qy", "qz"]] = frame[["qw", "qx", "qy", "qz"]].to_numpy() \
        * signs[:, None]
    write_table(frame, tmp_path / "a.csv")
    write_table(flipped, tmp_path / "b.csv")
    a = _concatenated(list(iter_motions(tmp_path / "a.csv", chunk=37, window=9)))
    b = _concatenated(list(iter_motions(tmp_path / "b.csv", chunk=37, window=9)))
    for name in ("omega", "alpha", "rotation"):
        np.testing.assert_allclose(b[name], a[name], atol=1e-12, err_msg=name)


def test_a_file_within_one_chunk_is_read_as_read_trajectory(tmp_path):
    rng = np.random.default_rng(3)
    frame = _trajectory_frame(80)
    frame["t"] = np.cumsum(rng.uniform(0.005, 0.015, 80))   # non-uniform: smoothing spline
    path = tmp_path / "t.csv"
    write_table(frame, path)
    (part,) = iter_motions(path, chunk=80)
    start, motion = part.start, part.motion
    expected = read_trajectory(path)
    assert start == 0
    for name in ("position", "velocity", "omega", "acceleration", "alpha"):
        np.testing.assert_array_equal(getattr(motion, name), getattr(expected, name))


def test_non_uniform_sampling_in_a_long_file_names_the_row(tmp_path):
    frame = _trajectory_frame(300)
    frame.loc[250:, "t"] += 0.003
    path = tmp_path / "t.csv"
    write_table(frame, path)
    with pytest.raises(InputError, match=rf"^{path}: row 251: time step 0.013 s differs from "
                                         r"the first 100 rows' mean step 0.01 s"):
        list(iter_motions(path, chunk=100))


@pytest.mark.parametrize(("row", "column", "value", "message"), [
    (173, "y", np.nan, "row 173: column 'y' is empty or NaN"),
    (250, "qz", "abc", "row 250: column 'qz' is not a number: 'abc'"),
    (101, "t", 0.5, "row 101: t = 0.5 is less than t = 0.99 in row 100; t must increase"),
    (120, "t", 1.18, "row 120: duplicate time t = 1.18 (same as row 119)"),
])
def test_bad_rows_in_later_chunks_name_the_row(tmp_path, row, column, value, message):
    frame = _trajectory_frame(300).astype(object)
    frame.loc[row - 1, column] = value
    path = tmp_path / "t.csv"
    frame.to_csv(path, index=False)
    with pytest.raises(InputError) as info:
        list(iter_motions(path, chunk=50, window=11))
    assert str(info.value) == f"{path}: {message}"


def test_euler_jumps_are_reported_with_global_rows(tmp_path):
    t, position, rotation = _level_crossing(301)
    euler = euler_from_rotation(rotation)
    frame = pd.DataFrame({"t": t})
    frame[["x", "y", "z"]] = position
    frame[["alpha", "beta", "gamma"]] = euler
    path = tmp_path / "euler.csv"
    write_table(frame, path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        whole = read_trajectory(path)
    expected = [str(w.message) for w in caught if w.category is GsfricWarning]
    assert len(expected) == 1 and "at row" in expected[0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        parts = list(iter_motions(path, chunk=40))
    got = [str(w.message) for w in caught if w.category is GsfricWarning]
    assert got == expected
    assert np.isfinite(_concatenated(parts)["omega"]).all()
    np.testing.assert_allclose(_concatenated(parts)["omega"][20:-20], whole.omega[20:-20],
                               atol=1e-3)


def test_degrees_in_a_long_file_warn_once(tmp_path):
    frame = _trajectory_frame(300, orientation="euler")
    frame[["alpha", "beta", "gamma"]] = np.degrees(frame[["alpha", "beta", "gamma"]]) + 90
    path = tmp_path / "deg.csv"
    write_table(frame, path)
    with pytest.warns(GsfricWarning) as caught:
        list(iter_motions(path, chunk=50, window=11))
    messages = [str(w.message) for w in caught if "degrees" in str(w.message)]
    assert len(messages) == 1 and messages[0].startswith(f"{path}: angles look like degrees")


def test_streamed_simulation_equals_the_whole_evaluation(tmp_path):
    frame = _trajectory_frame(700)
    frame.loc[[130, 131], "z"] = 1.5                 # beyond the stroke: flagged steps in
    frame.loc[595:604, "z"] = 1.5                    # the second chunk and across a boundary
    path = tmp_path / "t.parquet"
    write_table(frame, path)
    platform = models.reference_platform()
    expected = quiet(evaluate, platform, read_trajectory(path, window=15))
    flagged = expected.flagged()
    assert {130, 131, 599, 600} <= set(flagged.tolist())
    with pytest.warns(GsfricWarning) as caught:
        summary = simulate_file(path, tmp_path / "out.parquet", platform, chunk=100,
                                       window=15, columns=("all",))
    message, = [str(w.message) for w in caught]
    shown = ", ".join(str(i) for i in flagged[:10])
    rows = ", ".join(str(i + 1) for i in flagged[:10])
    assert message.startswith(f"{path}: {len(flagged)} of 700 steps flagged (leg length outside "
                              f"the stroke: {len(flagged)}; ")
    assert f"): steps {shown}" in message
    assert f"(data rows {rows})" in message and "see the flag column of" in message
    assert (summary.steps, summary.chunks, summary.flagged) == (700, 7, len(flagged))
    np.testing.assert_array_equal(summary.flagged_steps, flagged)
    got = pd.read_parquet(tmp_path / "out.parquet")
    expected = expected.to_frame()
    assert list(got.columns) == list(expected.columns)
    assert got["flag"].dtype == expected["flag"].dtype
    # sigma_F is evaluated on a grid of steps and interpolated between (its cost): the
    # streamed file's grid points near a chunk's ends see another piece of the smoothing, and
    # near the flagged steps (the poses' jumps) another estimate of the slope
    sigma = [c for c in got.columns if c.startswith("sigma_F")]
    exact = [c for c in got.columns if c not in sigma]
    np.testing.assert_allclose(got[exact].to_numpy(), expected[exact].to_numpy(), rtol=1e-9,
                               atol=1e-9)
    away = np.min(np.abs(np.arange(700)[:, None] - flagged[None, :]), axis=1) > 20
    np.testing.assert_allclose(got.loc[away, sigma].to_numpy(),
                               expected.loc[away, sigma].to_numpy(), rtol=0.1)


def test_streamed_csv_output_reads_back_exactly(tmp_path):
    path = tmp_path / "t.csv"
    write_table(_trajectory_frame(250), path)
    simulate_file(path, tmp_path / "a.csv", chunk=60, window=9)
    simulate_file(path, tmp_path / "a.parquet", chunk=60, window=9)
    a = gsfric.io.read_table(tmp_path / "a.csv")
    b = pd.read_parquet(tmp_path / "a.parquet")
    pd.testing.assert_frame_equal(a, b)


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_interrupted_run_leaves_no_partial_file(tmp_path, monkeypatch):
    path = tmp_path / "t.csv"
    write_table(_trajectory_frame(500), path)
    out = tmp_path / "out.parquet"
    out.write_bytes(b"the previous result")
    calls = []
    original = gsfric.simulate.run.evaluate_outputs   # what simulate evaluates each chunk with

    def interrupted(evaluator, motion, *args, **kwargs):
        calls.append(len(motion))
        if len(calls) == 3:
            raise KeyboardInterrupt
        return original(evaluator, motion, *args, **kwargs)

    monkeypatch.setattr(gsfric.simulate.run, "evaluate_outputs", interrupted)
    with pytest.raises(KeyboardInterrupt):
        simulate_file(path, out, chunk=100, window=9)
    assert len(calls) == 3
    assert out.read_bytes() == b"the previous result"
    assert _leftovers(tmp_path) == []


def test_bad_row_after_written_chunks_leaves_no_output(tmp_path):
    frame = _trajectory_frame(500).astype(object)
    frame.loc[449, "x"] = "oops"
    path = tmp_path / "t.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / "out.csv"
    with pytest.raises(InputError, match=r"row 450: column 'x' is not a number: 'oops'"):
        simulate_file(path, out, chunk=100, window=9)
    assert not out.exists() and _leftovers(tmp_path) == []


def test_strict_stops_at_the_first_flagged_chunk(tmp_path, monkeypatch):
    frame = _trajectory_frame(500)
    frame.loc[[250, 480], "z"] = 1.5
    path = tmp_path / "t.csv"
    write_table(frame, path)
    out = tmp_path / "out.csv"
    seen = []
    original = gsfric.simulate.run.evaluate_outputs   # what simulate evaluates each chunk with
    monkeypatch.setattr(gsfric.simulate.run, "evaluate_outputs",
                        lambda evaluator, motion, *a, **kw: seen.append(motion.t[0])
                        or original(evaluator, motion, *a, **kw))
    with pytest.raises(StepFlagError, match=r"^.*t.csv: 1 of 300 steps flagged .*steps 250 "
                                            r"\(data rows 251\) \(--strict"):
        simulate_file(path, out, chunk=100, window=9, strict=True)
    assert len(seen) == 3                             # stopped at the third chunk
    assert not out.exists() and _leftovers(tmp_path) == []


def test_bad_output_paths(tmp_path):
    path = tmp_path / "t.csv"
    write_table(_trajectory_frame(50), path)
    for out, message in [(tmp_path / "o.txt", "unknown extension '.txt'"),
                         (tmp_path / "missing" / "o.csv", "does not exist"),
                         (path, "is the trajectory file itself"),
                         (tmp_path, "is a directory; give a file name")]:
        with pytest.raises(InputError, match=message):
            simulate_file(path, out)


def test_chunk_and_window_are_checked(tmp_path):
    path = tmp_path / "t.csv"
    write_table(_trajectory_frame(500), path)
    with pytest.raises(InputError, match=r"^chunk: must be an integer >= 7, got 3$"):
        list(iter_motions(path, chunk=3))
    with pytest.raises(InputError, match=r"^window = 21 is longer than the chunk of 11 steps"):
        list(iter_motions(path, chunk=11, window=21))
    with pytest.raises(InputError, match=r"t.csv: window must be odd, got 10$"):
        list(iter_motions(path, chunk=50, window=10))


@pytest.mark.integration
def test_200k_steps_in_small_chunks_bounded_memory(tmp_path):
    """The benchmark's own functions on 200k steps with chunks of 10k: every row written once,
    in order, and a peak RSS far below the ~0.9 GB that evaluating 200k steps at once takes.

    Run from a fresh interpreter, so that RUSAGE_CHILDREN sees only the simulate process.
    """
    trajectory, out = tmp_path / "t.parquet", tmp_path / "forces.parquet"
    code = (
        "import importlib.util, json, sys\n"
        f"spec = importlib.util.spec_from_file_location('bench', {str(BENCHMARK)!r})\n"
        "bench = importlib.util.module_from_spec(spec); spec.loader.exec_module(bench)\n"
        f"bench.write_trajectory(__import__('pathlib').Path({str(trajectory)!r}), 200_000, "
        "rows_per_group=30_000)\n"
        f"print(json.dumps(bench.run_simulate({str(trajectory)!r}, {str(out)!r}, "
        "chunk=10_000)))\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT)
    assert run.returncode == 0, run.stderr
    figures = json.loads(run.stdout)
    assert figures["returncode"] == 0, figures["stderr"]
    assert figures["stdout"].startswith(f"wrote {out} (200000 steps, 0 flagged; "
                                        "differentiated by savgol (windows ")

    source = pq.ParquetFile(out)
    assert source.metadata.num_rows == 200_000
    assert source.metadata.num_row_groups == 20
    t = source.read(columns=["t", "F1", "flag"]).to_pandas()
    np.testing.assert_array_equal(t["t"].to_numpy(), np.arange(200_000) / 1000.0)
    assert np.isfinite(t["F1"]).all() and not t["flag"].any()
    assert figures["peak_rss_mb"] < 600, figures


# -- implausible input: units, bodies, forces (warnings or one-line errors) ----------------------


def _unit_samples(t):
    motion = models.sinusoidal(np.asarray(t, float) / (t[-1] - t[0]) * 2.0)
    return motion.position, motion.quaternion()


def test_time_in_integer_nanoseconds_is_an_error_naming_the_unit(tmp_path):
    t_ns = np.arange(0, 400) * 5_000_000                  # 200 Hz written as integer ns
    position, q = _unit_samples(t_ns)
    frame = pd.DataFrame({"t": t_ns})
    frame[["x", "y", "z"]] = position
    frame[["qw", "qx", "qy", "qz"]] = q
    path = tmp_path / "ns.csv"
    write_table(frame, path)
    with pytest.raises(InputError) as caught:
        read_trajectory(path)
    assert str(caught.value) == (
        f"{path}: time column 't': median time step 5e+06 s, a sampling rate of 2e-07 Hz, "
        "outside 1 Hz .. 1e+06 Hz -> looks like ns; declare t=ns (--units t=ns, or [units] "
        't = "ns" in the log format)')


def test_sampling_rate_inside_the_range_does_not_warn():
    for rate in (1.5, 200.0, 9e5):
        t = np.arange(50) / rate
        position, q = _unit_samples(t)
        with warnings.catch_warnings():
            warnings.simplefilter("error", GsfricWarning)
            Motion.from_samples(t, position, quaternion=q)


def test_positions_in_millimetres_warn():
    t = np.arange(50) / 100.0
    position, q = _unit_samples(t)
    with pytest.warns(GsfricWarning, match=r"position: up to [0-9.e+]+ m from the base "
                                           r"frame's origin .*positions must be in m, not mm"):
        Motion.from_samples(t, position * 1000.0, quaternion=q)


def test_platform_in_millimetres_warns(platform):
    geometry = platform.geometry
    with pytest.warns(GsfricWarning) as record:
        platform.with_geometry(base_joints=geometry.base_joints * 1000.0,
                               platform_joints=geometry.platform_joints * 1000.0, stroke=None)
    for name in ("base_joints", "platform_joints"):
        assert any(re.search(rf"geometry\.{name}: a joint is \d+(\.\d+)? m from the origin "
                             r".*lengths must be in m, not mm", str(w.message)) for w in record)
    # a rig of tens of metres (a ship's or a building's test rig) is one, in metres
    with warnings.catch_warnings():
        warnings.simplefilter("error", GsfricWarning)
        platform.with_geometry(base_joints=geometry.base_joints * 80.0,
                               platform_joints=geometry.platform_joints * 80.0, stroke=None)


def test_inertia_violating_the_triangle_inequality_warns(platform):
    with pytest.warns(GsfricWarning, match=r"platform\.inertia: principal moments 1, 1, 5 kg "
                                           r"m\^2 violate the triangle inequality \(5 > 1 \+ 1"):
        platform.with_body(inertia=np.diag([1.0, 1.0, 5.0]))
    with warnings.catch_warnings():                        # a thin rod is the limit: fine
        warnings.simplefilter("error", GsfricWarning)
        platform.with_body(inertia=np.diag([1.0, 1.0, 0.0]))


def test_leg_centre_of_mass_outside_the_leg(platform):
    with pytest.raises(InputError, match=r"^legs\.lower_com: -5 m puts the lower part's centre "
                                         r"of mass beyond its joint C_i, outside the leg"):
        platform.with_legs(lower_com=-5)
    with pytest.warns(GsfricWarning, match=r"legs\.upper_com: 3 m is longer than the longest "
                                           r"leg \(geometry\.stroke d_max = 1\.1 m\)"):
        platform.with_legs(upper_com=3.0)


def test_body_centre_of_mass_far_outside_warns(platform):
    with pytest.warns(GsfricWarning, match=r"platform\.com: 50 m from the platform frame origin"):
        platform.with_body(com=[0.0, 0.0, 50.0])


def test_measured_forces_of_1e300_are_refused_with_the_row(tmp_path):
    t = np.arange(50) / 100.0
    position, q = _unit_samples(t)
    frame = pd.DataFrame({"t": t})
    frame[["x", "y", "z"]] = position
    frame[["qw", "qx", "qy", "qz"]] = q
    for i in range(1, 7):
        frame[f"F{i}"] = 10.0
    frame.loc[7, "F3"] = 1e300
    path = tmp_path / "m.csv"
    write_table(frame, path)

    with pytest.raises(InputError, match=r"m\.csv: row 8: column 'F3' = 1e\+300 N is not a "
                                         r"plausible actuator force \(\|F\| > 1e\+08 N\)"):
        read_measured(path)


def test_synth_rate_outside_the_range_exit_2(tmp_path):
    result = CliRunner().invoke(main, ["synth", "--out", str(tmp_path / "m.csv"), "--rate",
                                       "1e-300"])
    assert result.exit_code == 2
    assert "Invalid value for '--rate': 1e-300 is not in the range 1.0<=x<=1000000.0" in \
        result.stderr
    assert not (tmp_path / "m.csv").exists()


# -- API misuse: one-line TypeError / ValueError ---------------------------------------------


def test_evaluate_arguments(platform):
    motion = models.sinusoidal(np.linspace(0.0, 1.0, 11))
    with pytest.raises(TypeError, match=r"^evaluate\(platform, motion\): the arguments are "
                                        r"swapped; give the Platform first, then the Motion$"):
        gsfric.evaluate(motion, platform)
    with pytest.raises(TypeError, match=r"^evaluate: platform must be a gsfric\.Platform, "
                                        r"got None"):
        gsfric.evaluate(None, motion)
    with pytest.raises(TypeError, match=r"^evaluate: motion must be a gsfric\.Motion or a pandas "
                                        r"DataFrame of trajectory columns, got a NumPy array of shape \(3, 24\); for states"):
        gsfric.evaluate(platform, np.zeros((3, 24)))
    with pytest.raises(ValueError, match=r"^chunk: must be an integer >= 1 \(steps per call\), "
                                         r"got 0$"):
        gsfric.evaluate(platform, motion, chunk=0)
    np.testing.assert_array_equal(gsfric.evaluate(platform, motion, chunk=4).F,
                                  gsfric.evaluate(platform, motion).F)


def test_from_samples_with_lam_on_non_uniform_times():
    t = np.cumsum(np.r_[0.0, np.random.default_rng(1).uniform(0.008, 0.012, 59)])
    position, q = _unit_samples(t)
    smooth = Motion.from_samples(t, position, quaternion=q, lam=1e-3)
    rough = Motion.from_samples(t, position, quaternion=q, lam=1e-9)
    assert np.abs(rough.position - position).max() < np.abs(smooth.position - position).max()
    with pytest.raises(InputError, match=r"^lam: must be >= 0, got -1$"):
        Motion.from_samples(t, position, quaternion=q, lam=-1.0)


def test_long_non_uniform_spline_equals_scipy_with_its_penalties():
    """Above SPLINE_GCV_ROWS, the fit of every sample is make_smoothing_spline's with the
    penalties ``spline_penalties`` chose (same numbers, one banded set-up), and each penalty
    is the one of least estimated acceleration error: on a noise-free record the smallest."""
    rng = np.random.default_rng(3)
    n = tr.SPLINE_GCV_ROWS + 700
    t = np.cumsum(rng.uniform(0.5, 1.5, n)) * 0.01
    y = np.stack([np.sin(t * (j + 1)) + 1e-3 * rng.standard_normal(n) for j in range(3)], 1)
    got, _ = tr.spline_fit(t, y, None)
    penalties = tr.spline_penalties(t, y)
    for j in range(3):
        reference = make_smoothing_spline(t, y[:, j], lam=penalties[j])
        for k in range(3):
            expected = reference.derivative(k)(t) if k else reference(t)
            np.testing.assert_allclose(got[k][:, j], expected, rtol=1e-9,
                                       atol=1e-9 * np.abs(expected).max())
    h = (t[-1] - t[0]) / (n - 1)
    exact = np.sin(t)[:, None]
    assert tr.spline_penalties(t, exact)[0] == pytest.approx(h ** 3 * tr.SPLINE_PENALTIES[0])

