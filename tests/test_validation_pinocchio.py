"""gsfric against an independent inverse-dynamics engine (Pinocchio, tests/engines).

The same hexapod is built as a Pinocchio tree (free-flyer platform, each leg a universal joint
and a prismatic joint, a 3-D point closure at each spherical joint). Its RNEA and closure
Jacobians give the actuator forces and the joint reactions; gsfric's frictionless actuator
forces F0, the spherical joints' forces R_E, the universal joints' forces R_C and constraint
moments M_C must agree to a relative 1e-8 (of each quantity's largest magnitude over the steps).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pinocchio")

import gsfric  # noqa: E402
from gsfric import models  # noqa: E402
from helpers_validation import (engine, engine_results, random_platform,  # noqa: E402
                                relative_difference)

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
    assert_agree(differences(models.reference_platform(), smooth_motion(rng)))


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
