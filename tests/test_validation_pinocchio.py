"""gsfric against an independent inverse-dynamics engine (Pinocchio, tests/engines).

The same hexapod is built as a Pinocchio tree (free-flyer platform, each leg a universal joint
and a prismatic joint, a 3-D point closure at each spherical joint). Its RNEA and closure
Jacobians give the actuator forces and the joint reactions; gsfric's frictionless actuator
forces F0, the spherical joints' forces R_E, the universal joints' forces R_C and constraint
moments M_C must agree to a relative 1e-8 (of each quantity's largest magnitude over the steps).

With the coupled friction model the engine carries the same friction wrenches (the universal
joints' friction torques as the revolute joints' generalized forces, the spherical joints'
friction moments as external moments on platform and upper part, the prismatic friction on the
upper part); the actuator forces with friction F and the coupled reactions must agree to 1e-8.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from helpers_validation import (  # noqa: E402
    engine,
    engine_geometry,
    engine_results,
    random_platform,
    relative_difference,
)

import gsfric  # noqa: E402
from gsfric import models  # noqa: E402

TOLERANCE = 1e-8
STEPS = 40
COMPARED = (("F0", "F"), ("R_E", "R_E"), ("R_C", "R_C"), ("M_C", "M_C"),
            ("D_dot", "d_dot"), ("omega_leg", "omega_leg"))


def differences(platform, motion) -> dict[str, float]:
    result = gsfric.Evaluator(platform).evaluate(motion, strict=True)
    reference = engine_results(platform, motion)
    assert reference["closure_acceleration"].max() < 1e-9
    assert reference["solve_residual"].max() < 1e-9 * np.abs(reference["F"]).max()
    return {ours: relative_difference(getattr(result, ours), reference[theirs])
            for ours, theirs in COMPARED}


def smooth_motion(rng, scale=1.5):
    return models.random_motion(rng, np.sort(rng.uniform(0.0, 6.0, STEPS)), scale=scale)


def assert_agree(diffs):
    worst = {k: f"{v:.1e}" for k, v in diffs.items()}
    assert max(diffs.values()) <= TOLERANCE, worst


def test_reference_platform():
    rng = np.random.default_rng(7)
    assert_agree(differences(models.reference_platform("paper"), smooth_motion(rng)))


COUPLED = (("F", "F"), ("R_E", "R_E"), ("R_C", "R_C"), ("M_C", "M_C"))


def coupled_differences(platform, motion) -> dict[str, float]:
    """gsfric's coupled solve against the engine loaded with gsfric's friction wrenches."""
    result = gsfric.Evaluator(platform).evaluate(motion, strict=True)
    geom = engine_geometry(platform)
    steps = []
    for k in range(len(motion)):
        state = {key: getattr(motion, key)[k] for key in engine.STATE_KEYS}
        friction = dict(MfrE=result.MfrE[k], MfrC=result.MfrC[k], Ffr=result.Ffr[k])
        steps.append(engine.inverse_dynamics(geom, state, friction))
    reference = {key: np.array([s[key] for s in steps]) for key in steps[0]}
    assert reference["solve_residual"].max() < 1e-9 * np.abs(reference["F"]).max()
    assert reference["moment_offaxis"].max() < 1e-9 * np.abs(reference["M_C"]).max()
    return {ours: relative_difference(getattr(result, ours), reference[theirs])
            for ours, theirs in COUPLED}


def test_coupled_friction_reference_platform():
    rng = np.random.default_rng(8)
    platform = models.reference_platform("coupled")
    assert platform.friction.model == "coupled"
    assert_agree(coupled_differences(platform, smooth_motion(rng)))


@pytest.mark.parametrize("seed", range(3))
def test_coupled_friction_random_platforms(seed):
    """Large joint friction (mu r = 0.003 m, 1.5x the paper's) so that it matters."""
    rng = np.random.default_rng(6000 + seed)
    platform = random_platform(rng).with_friction(model="coupled", joint_coulomb=0.06,
                                                  prismatic_seal=1.0)
    assert_agree(coupled_differences(platform, smooth_motion(rng)))


def test_coupled_comparison_detects_friction_left_out():
    """Without the joint friction's load the engine disagrees by far more than 1e-8."""
    rng = np.random.default_rng(6100)
    platform = random_platform(rng).with_friction(model="coupled")
    motion = smooth_motion(rng)
    coupled = gsfric.Evaluator(platform).evaluate(motion, strict=True)
    paper = gsfric.Evaluator(platform.with_friction(model="paper")).evaluate(motion,
                                                                             strict=True)
    reference = engine_results(platform, motion)   # frictionless engine
    assert relative_difference(coupled.R_E, reference["R_E"]) > 1e3 * TOLERANCE
    assert relative_difference(paper.R_E, reference["R_E"]) < TOLERANCE


@pytest.mark.parametrize("seed", range(5))
def test_random_platforms_smooth_motions(seed):
    rng = np.random.default_rng(1000 + seed)
    platform = random_platform(rng)
    assert_agree(differences(platform, smooth_motion(rng)))


@pytest.mark.parametrize("seed", range(2))
def test_random_platforms_without_gravity(seed):
    """Only inertial loads: the velocity and acceleration terms alone must agree."""
    rng = np.random.default_rng(2000 + seed)
    platform = random_platform(rng).replace(gravity=0.0)
    assert_agree(differences(platform, smooth_motion(rng, scale=2.0)))


@pytest.mark.parametrize("seed", range(2))
def test_random_states(seed):
    """Unrelated random poses, velocities and accelerations, not from one motion."""
    rng = np.random.default_rng(3000 + seed)
    platform = random_platform(rng)
    states = [engine.random_state(rng, height=models.HOME_HEIGHT) for _ in range(25)]
    motion = gsfric.Motion.from_arrays(
        t=np.arange(len(states), dtype=float),
        **{k: np.array([s[k] for s in states]) for k in engine.STATE_KEYS})
    assert_agree(differences(platform, motion))


def test_effects_on_the_loads():
    """``leg_weight`` on a model without leg weight, and ``payload_offset``, against the engine
    built with the leg weight and the moved payload."""
    rng = np.random.default_rng(4000)
    platform = random_platform(rng)
    offset = rng.uniform(-0.05, 0.05, 3)
    with_effects = (platform.with_legs(weight=False)
                    .with_effect("leg_weight", lower_mass=platform.legs.lower_mass,
                                 upper_mass=platform.legs.upper_mass)
                    .with_effect("payload_offset", x=offset[0], y=offset[1], z=offset[2]))
    moved = platform.with_body(payload_com=platform.platform.payload_com + offset)
    motion = smooth_motion(rng)
    result = gsfric.Evaluator(with_effects).evaluate(motion, strict=True)
    reference = engine_results(moved, motion)
    diffs = {ours: relative_difference(getattr(result, ours), reference[theirs])
             for ours, theirs in COMPARED}
    assert_agree(diffs)


def test_comparison_detects_a_wrong_model():
    """The comparison is sharp: a 1% heavier payload is far outside the tolerance."""
    rng = np.random.default_rng(5000)
    platform = random_platform(rng)
    motion = smooth_motion(rng)
    heavier = platform.with_body(payload_mass=platform.platform.payload_mass * 1.01)
    result = gsfric.Evaluator(heavier).evaluate(motion, strict=True)
    reference = engine_results(platform, motion)
    assert relative_difference(result.F0, reference["F"]) > 1e3 * TOLERANCE
