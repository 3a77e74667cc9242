"""Energy balance along smooth motions.

The work of the actuators, integrated over the motion, must equal the change of the hexapod's
kinetic plus potential energy, plus the work lost to friction when the actuators carry it.

The platforms use the paper's friction model unless a test says otherwise; the coupled model
(docs/explanation/friction.md) has its own balance below.

The energies are computed independently of gsfric's dynamics (tests/helpers_validation.py):
from the platform pose alone, every body's centre and orientation (platform, payload, each leg's
two parts) is placed by the geometry, and the velocities come from fourth-order central finite
differences in time (step 1e-3 s). The leg length rates in the actuator power come from the same
finite differences. The power is integrated with the cumulative Simpson rule (error ~ h^4);
(integral over every sample - integral over every other sample) / 15 estimates its error.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from helpers_validation import Bodies, motion_pose, random_platform, relative_difference
from scipy.integrate import cumulative_simpson

import gsfric
from gsfric import models

DURATION = 4.0
STEPS = 4001
TOLERANCE = 1e-8
"""Largest |work - energy change| over the motion, relative to the largest |energy change|."""
SEEDS = (0, 1, 2)


@functools.lru_cache(maxsize=None)
def case(seed: int):
    rng = np.random.default_rng(seed)
    platform = models.reference_platform("paper") if seed == 0 else random_platform(rng)

    def motion_of_t(t):
        return models.random_motion(np.random.default_rng(100 + seed), t, scale=1.5)

    t = np.linspace(0.0, DURATION, STEPS)
    motion = motion_of_t(t)
    bodies = Bodies(platform, motion_pose(motion_of_t))
    kinetic, potential = bodies.energies(t)
    energy = kinetic + potential
    omega_platform, omega_legs = bodies.angular_velocities(t)
    return dict(platform=platform, t=t, motion=motion, energy_change=energy - energy[0],
                leg_rates=bodies.leg_rates(t), omega_platform=omega_platform,
                omega_legs=omega_legs)


def work(t, power):
    return cumulative_simpson(power, x=t, initial=0.0)


def evaluate(platform, motion):
    return gsfric.Evaluator(platform).evaluate(motion, strict=True)


def balance_error(c, actuator_power, lost_power=0.0):
    """Largest |actuator work - energy change - work lost|, relative to max |energy change|."""
    residual = work(c["t"], actuator_power - lost_power) - c["energy_change"]
    return np.max(np.abs(residual)) / np.max(np.abs(c["energy_change"]))


@pytest.mark.parametrize("seed", SEEDS)
def test_kinematics_agree_with_finite_differences(seed):
    c = case(seed)
    result = evaluate(c["platform"], c["motion"])
    assert relative_difference(result.D_dot, c["leg_rates"]) < 1e-8
    assert relative_difference(result.omega_leg, c["omega_legs"]) < 1e-8
    omega_rel = c["omega_platform"][:, None, :] - c["omega_legs"]
    assert relative_difference(result.omega_rel, omega_rel) < 1e-8


@pytest.mark.parametrize("seed", SEEDS)
def test_frictionless_energy_balance(seed):
    c = case(seed)
    result = evaluate(c["platform"], c["motion"])
    power = np.sum(result.F0 * c["leg_rates"], axis=1)
    assert balance_error(c, power) < TOLERANCE
    every_other = work(c["t"][::2], power[::2])
    richardson = np.max(np.abs(work(c["t"], power)[::2] - every_other)) / 15.0
    assert richardson < TOLERANCE * np.max(np.abs(c["energy_change"]))


@pytest.mark.parametrize("seed", SEEDS)
def test_energy_balance_is_sharp(seed):
    """Leaving out the legs' rotational inertia, or taking the motion 1% faster, breaks it."""
    c = case(seed)
    platform = c["platform"]
    result = evaluate(platform, c["motion"])
    power = np.sum(result.F0 * c["leg_rates"], axis=1)
    no_rotation = platform.with_legs(lower_inertia=np.zeros((3, 3)),
                                     upper_inertia=np.zeros((3, 3)))
    wrong = evaluate(no_rotation, c["motion"])
    assert balance_error(c, np.sum(wrong.F0 * c["leg_rates"], axis=1)) > 1e3 * TOLERANCE
    m = c["motion"]
    faster = gsfric.Motion.from_arrays(m.t, m.position, m.rotation, m.velocity, m.omega,
                                       1.01 * m.acceleration, 1.01 * m.alpha)
    wrong = evaluate(platform, faster)
    assert balance_error(c, np.sum(wrong.F0 * c["leg_rates"], axis=1)) > 1e3 * TOLERANCE
    assert balance_error(c, power) < TOLERANCE


def joint_friction_power(result, c):
    """Power of the spherical and universal joints' friction moments, (N,) W."""
    omega_rel = c["omega_platform"][:, None, :] - c["omega_legs"]
    return (np.einsum("nki,nki->n", result.MfrE, omega_rel)
            + np.einsum("nki,nki->n", result.MfrC, c["omega_legs"]))


def prismatic_friction_power(result, c):
    return np.sum(result.Ffr * c["leg_rates"], axis=1)


@pytest.mark.parametrize("seed", SEEDS)
def test_prismatic_friction_work(seed):
    """With friction the actuators do the frictionless work plus the prismatic friction's."""
    c = case(seed)
    result = evaluate(c["platform"], c["motion"])
    frictionless = work(c["t"], np.sum(result.F0 * c["leg_rates"], axis=1))
    with_friction = work(c["t"], np.sum(result.F * c["leg_rates"], axis=1))
    lost = -work(c["t"], prismatic_friction_power(result, c))
    scale = np.max(np.abs(c["energy_change"]))
    assert np.max(np.abs(with_friction - frictionless - lost)) < TOLERANCE * scale
    assert np.all(np.diff(lost) >= -TOLERANCE * scale)
    assert balance_error(c, np.sum(result.F * c["leg_rates"], axis=1),
                         -prismatic_friction_power(result, c)) < TOLERANCE


@pytest.mark.parametrize("seed", SEEDS)
def test_energy_balance_with_joint_friction_carried(seed):
    """``joint_friction_coupling``: the actuators also carry the joints' friction moments, so
    their work is the energy change plus the work lost in every joint."""
    c = case(seed)
    platform = c["platform"].with_effect("joint_friction_coupling", scale=1.0)
    result = evaluate(platform, c["motion"])
    lost = -(prismatic_friction_power(result, c) + joint_friction_power(result, c))
    actuator = np.sum(result.F * c["leg_rates"], axis=1)
    assert balance_error(c, actuator, lost) < TOLERANCE
    frictionless = np.sum(result.F0 * c["leg_rates"], axis=1)
    assert work(c["t"], actuator - frictionless)[-1] > 0.0


@pytest.mark.parametrize("seed", SEEDS)
def test_friction_power_is_never_positive(seed):
    """Friction power in every joint (spherical, universal, prismatic) at every step: <= 0."""
    c = case(seed)
    result = evaluate(c["platform"], c["motion"])
    omega_rel = c["omega_platform"][:, None, :] - c["omega_legs"]
    powers = {"spherical": np.einsum("nki,nki->nk", result.MfrE, omega_rel),
              "universal": np.einsum("nki,nki->nk", result.MfrC, c["omega_legs"]),
              "prismatic": result.Ffr * c["leg_rates"]}
    powers["total"] = sum(p.sum(axis=1) for p in powers.values())
    for joint, power in powers.items():
        worst = np.unravel_index(np.argmax(power), power.shape)
        assert power[worst] <= 1e-9 * np.max(np.abs(power)), (
            f"{joint} friction produces {power[worst]:.3g} W at t = {c['t'][worst[0]]:.3f} s")


@pytest.mark.parametrize("seed", SEEDS)
def test_energy_balance_with_coupled_friction(seed):
    """Coupled model: the actuators' power minus the friction dissipated in every joint
    (spherical, universal per bearing axis, prismatic bushings and seal) is the rate of change
    of kinetic plus potential energy; and the friction actually loads the actuators."""
    c = case(seed)
    platform = c["platform"].with_friction(model="coupled", prismatic_seal=1.5,
                                           bushing_offset=0.2, bushing_spacing=0.12)
    result = evaluate(platform, c["motion"])
    lost = -(prismatic_friction_power(result, c) + joint_friction_power(result, c))
    actuator = np.sum(result.F * c["leg_rates"], axis=1)
    assert balance_error(c, actuator, lost) < TOLERANCE
    # leaving out the joints' dissipation breaks it: the coupled F carries it
    assert balance_error(c, actuator, -prismatic_friction_power(result, c)) > 1e2 * TOLERANCE
    assert np.all(lost >= -1e-9 * np.max(np.abs(lost)))
