"""Physical properties that every correct model has, over random platforms and motions.

* Three-fold symmetry: turning a whole motion of a three-fold symmetric hexapod by 120 degrees
  about the vertical axis turns every result with it and passes leg i's results to leg i + 2.
* No motion gives the static solution: at zero velocity, the change of the actuator forces from
  the static ones does work 2 T on the acceleration twist (T the kinetic energy of the hexapod
  moving with that twist), so it vanishes only without acceleration. Traversing a path s times
  faster scales the dynamic part by s^2.
* Static reactions scale linearly with gravity, and balance the whole hexapod's weight.
* Friction dissipates: in every joint, at every step, its power is <= 0.
"""

from __future__ import annotations

import numpy as np
from helpers_validation import Bodies, combined_body, random_inertia, random_platform
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import gsfric
from gsfric import models

EXAMPLES = settings(max_examples=50, deadline=None)
STATIC_KEYS = ("F0", "R_E", "R_C", "M_C")


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


RZ = rot_z(2 * np.pi / 3)

seeds = st.integers(0, 2**32 - 1)
unit = st.floats(0.0, 1.0)


@st.composite
def motion_parameters(draw):
    amplitude = np.array([draw(unit) for _ in range(6)]) * [0.06, 0.06, 0.05, 0.1, 0.1, 0.12]
    frequency = [draw(st.floats(0.2, 1.2)) for _ in range(6)]
    phase = [draw(st.floats(0.0, 2 * np.pi)) for _ in range(6)]
    times = np.sort([draw(st.floats(0.0, 5.0)) for _ in range(8)])
    return times, amplitude, frequency, phase


def smooth_motion(params) -> gsfric.Motion:
    times, amplitude, frequency, phase = params
    return models.sinusoidal(times, amplitude, frequency, phase)


def evaluate(platform, motion):
    return gsfric.Evaluator(platform).evaluate(motion, strict=True)


MOMENTS = ("M_C", "M_3", "MfrE", "MfrC", "MfrE_s", "MfrC_s", "M_3_leg")
FORCES = ("F", "F0", "R_E", "R_C", "R_3", "Ffr", "Ffr_s", "R_3_leg")


def assert_close(value, reference, rtol, name="", load=0.0):
    """|value - reference| <= rtol * scale, the scale being the reference's largest magnitude
    or, for forces and moments (which may vanish), the load scale (N, or N m over 1 m)."""
    scale = float(np.max(np.abs(reference)))
    if name in FORCES or name in MOMENTS:
        scale = max(scale, load)
    error = float(np.max(np.abs(value - reference)))
    assert error <= rtol * scale + 1e-300, f"{name}: difference {error:.3g} of {scale:.3g}"


# -- three-fold symmetry -----------------------------------------------------------------


def threefold(first_two: np.ndarray) -> np.ndarray:
    """Six vectors: the first two, then each turned by 120 and by 240 degrees about z."""
    return np.concatenate([first_two, first_two @ RZ.T, first_two @ RZ.T @ RZ.T])


def symmetric_platform(rng: np.random.Generator) -> gsfric.Platform:
    """A three-fold symmetric hexapod: joints, universal axes, bodies invariant under a turn by
    120 degrees about z (which carries leg i onto leg i + 2); the leg parts are arbitrary.
    The joints' mu r (coulomb x radius) stays within 0.006, where the coupled friction solve
    converges (docs/explanation/friction.md); beyond it a step may be flagged, and ``evaluate`` is strict."""
    ref = models.reference_platform()
    g = ref.geometry
    axes = g.universal_axes[:2] + rng.uniform(-0.3, 0.3, (2, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]

    def axial_inertia():
        a, b = rng.uniform(0.01, 0.2, 2)
        return np.diag([a, a, min(b, 2 * a)])       # a rigid body's: b <= a + a

    return (ref
            .with_geometry(base_joints=threefold(g.base_joints[:2] + rng.uniform(-0.03, 0.03,
                                                                                  (2, 3))),
                           platform_joints=threefold(g.platform_joints[:2]
                                                     + rng.uniform(-0.03, 0.03, (2, 3))),
                           universal_axes=threefold(axes))
            .with_body(mass=rng.uniform(5, 20), inertia=axial_inertia(),
                       com=[0.0, 0.0, rng.uniform(-0.05, 0.05)],
                       payload_mass=rng.uniform(0, 5), payload_inertia=axial_inertia(),
                       payload_com=[0.0, 0.0, rng.uniform(-0.05, 0.1)])
            .with_legs(lower_mass=rng.uniform(0.2, 2), upper_mass=rng.uniform(0.2, 2),
                       lower_com=rng.uniform(0.05, 0.3), upper_com=rng.uniform(0.05, 0.3),
                       lower_inertia=random_inertia(rng, 0.02),
                       upper_inertia=random_inertia(rng, 0.02))
            .with_friction(joint_radius=rng.uniform(0.0, 0.06),
                           **{f: rng.uniform(0.0, 0.1) for f in
                              ("joint_viscous", "joint_coulomb", "prismatic_viscous",
                               "prismatic_coulomb")}))


def turned(motion: gsfric.Motion, Q: np.ndarray) -> gsfric.Motion:
    """The motion turned as a whole by Q about the base origin.

    The platform's frame turns with it: ``R -> Q R Q^T``, so the platform joint that sits at
    Q E_i is joint i + 2 (k turns: i + 2k), which is where the symmetric platform has it.
    """
    vec = lambda x: x @ Q.T  # noqa: E731
    return gsfric.Motion.from_arrays(motion.t, vec(motion.position), Q @ motion.rotation @ Q.T,
                                     vec(motion.velocity), vec(motion.omega),
                                     vec(motion.acceleration), vec(motion.alpha))


VECTORS = ("R_E", "R_C", "R_3", "M_3", "MfrE", "MfrC", "u", "omega_leg", "omega_rel")
SCALARS = ("F", "F0", "M_C", "Ffr", "MfrE_s", "MfrC_s", "Ffr_s", "D", "D_dot", "s2",
           "R_3_leg", "M_3_leg")


@EXAMPLES
@given(seed=seeds, params=motion_parameters(), turns=st.sampled_from([1, 2]))
def test_threefold_symmetry_permutes_the_legs(seed, params, turns):
    platform = symmetric_platform(np.random.default_rng(seed))
    Q = np.linalg.matrix_power(RZ, turns)
    motion = smooth_motion(params)
    result = evaluate(platform, motion)
    other = evaluate(platform, turned(motion, Q))
    shift = 2 * turns
    load = np.max(np.abs(result.F0))
    for name in VECTORS:
        expected = np.roll(getattr(result, name) @ Q.T, shift, axis=1)
        assert_close(getattr(other, name), expected, 1e-10, name, load)
    for name in SCALARS:
        expected = np.roll(getattr(result, name), shift, axis=1)
        assert_close(getattr(other, name), expected, 1e-10, name, load)


def test_symmetry_needs_the_right_permutation():
    """Leg i + 2, not leg i or i + 4, takes over leg i's loads after one turn."""
    platform = symmetric_platform(np.random.default_rng(0))
    motion = models.random_motion(np.random.default_rng(1), np.linspace(0, 3, 7))
    result = evaluate(platform, motion)
    other = evaluate(platform, turned(motion, RZ))
    errors = [np.max(np.abs(other.F - np.roll(result.F, shift, axis=1))) for shift in range(6)]
    assert errors[2] < 1e-10 * np.max(np.abs(result.F))
    assert min(errors[:2] + errors[3:]) > 1e-3 * np.max(np.abs(result.F))


# -- motion against the static solution ----------------------------------------------------------


def pose_at(params, platform_seed):
    """A platform and one pose (position, rotation) of a random motion."""
    platform = random_platform(np.random.default_rng(platform_seed))
    motion = smooth_motion(params)
    return platform, motion.position[0], motion.rotation[0]


def state(position, rotation, velocity=(0, 0, 0), omega=(0, 0, 0), acceleration=(0, 0, 0),
          alpha=(0, 0, 0)) -> gsfric.Motion:
    one = lambda x: np.asarray(x, float)[None]  # noqa: E731
    return gsfric.Motion.from_arrays(np.zeros(1), one(position), one(rotation), one(velocity),
                                     one(omega), one(acceleration), one(alpha))


def kinetic_energy(platform, position, rotation, v, w) -> float:
    """Kinetic energy of the hexapod whose platform moves with twist (v, w) at this pose."""
    turn = lambda t: Rotation.from_rotvec(np.outer(t, w)).as_matrix()  # noqa: E731
    bodies = Bodies(platform, lambda t: (position + np.outer(t, v), turn(t) @ rotation))
    kinetic, _ = bodies.energies(np.zeros(1))
    return float(kinetic[0])


vectors = st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3).map(np.array)


@EXAMPLES
@given(seed=seeds, params=motion_parameters(), a=vectors, alpha=vectors,
       size=st.floats(0.05, 5.0))
def test_acceleration_from_rest_does_work_2T(seed, params, a, alpha, size):
    """F0(rest, a, alpha) - F0(static) does work 2 T(a, alpha) > 0 on the twist (a, alpha)."""
    norm = np.linalg.norm(np.concatenate([a, alpha]))
    if norm < 1e-3:
        a, alpha, norm = np.array([1.0, 0.0, 0.0]), np.zeros(3), 1.0
    a, alpha = a * size / norm, alpha * 2 * size / norm
    platform, p, R = pose_at(params, seed)
    static = evaluate(platform, state(p, R))
    moving = evaluate(platform, state(p, R, acceleration=a, alpha=alpha))
    arms = platform.geometry.platform_joints @ R.T
    rates = np.einsum("ki,ki->k", static.u[0], a + np.cross(alpha, arms))
    work = float(np.dot(moving.F0[0] - static.F0[0], rates))
    twice_kinetic = 2 * kinetic_energy(platform, p, R, a, alpha)
    mass, com, inertia = combined_body(platform.platform)
    twice_platform = (mass * np.sum((a + np.cross(alpha, R @ com)) ** 2)
                      + alpha @ R @ inertia @ R.T @ alpha)
    assert twice_kinetic >= twice_platform > 0.0
    assert abs(work - twice_kinetic) <= 1e-7 * twice_kinetic


@EXAMPLES
@given(seed=seeds, params=motion_parameters(), speed=st.floats(0.2, 4.0))
def test_dynamic_part_scales_with_the_square_of_the_speed(seed, params, speed):
    """Along the same path s times faster (v, omega times s; a, alpha times s^2), the loads
    minus the static ones scale by s^2."""
    platform = random_platform(np.random.default_rng(seed))
    m = smooth_motion(params)
    zero = np.zeros_like(m.velocity)
    static = gsfric.Motion.from_arrays(m.t, m.position, m.rotation, zero, zero, zero, zero)
    faster = gsfric.Motion.from_arrays(m.t, m.position, m.rotation, speed * m.velocity,
                                       speed * m.omega, speed**2 * m.acceleration,
                                       speed**2 * m.alpha)
    r0, r1, rs = evaluate(platform, static), evaluate(platform, m), evaluate(platform, faster)
    load = np.max(np.abs(r0.F0)) + speed**2 * np.max(np.abs(r1.F0 - r0.F0))
    for name in STATIC_KEYS:
        at_rest = getattr(r0, name)
        dynamic = speed**2 * (getattr(r1, name) - at_rest)
        assert_close(getattr(rs, name) - at_rest, dynamic, 1e-12, name, load)


# -- gravity ------------------------------------------------------------------------------------


@EXAMPLES
@given(seed=seeds, params=motion_parameters(), factor=st.floats(0.0, 3.0))
def test_static_reactions_scale_with_gravity(seed, params, factor):
    platform, p, R = pose_at(params, seed)
    rest = state(p, R)
    base = evaluate(platform, rest)
    scaled = evaluate(platform.replace(gravity=factor * platform.gravity), rest)
    load = np.max(np.abs(base.F0))
    for name in STATIC_KEYS:
        assert_close(getattr(scaled, name), factor * getattr(base, name), 1e-12, name, load)
    assert_close(scaled.F, scaled.F0, 1e-12, "F", load)


@EXAMPLES
@given(seed=seeds, params=motion_parameters())
def test_static_reactions_carry_the_whole_weight(seed, params):
    """At rest the base's forces and moments on the legs balance the weight of every body."""
    platform, p, R = pose_at(params, seed)
    r = evaluate(platform, state(p, R))
    bodies = Bodies(platform, lambda t: (np.broadcast_to(p, (len(t), 3)),
                                         np.broadcast_to(R, (len(t), 3, 3))))
    masses, _ = bodies.masses_inertias()
    centres = bodies.centres(np.zeros(1))[0]
    weights = -platform.gravity * masses[:, None] * np.array([0.0, 0.0, 1.0])
    a1 = platform.geometry.universal_axes
    u = r.u[0]
    n = u - np.sum(u * a1, axis=1)[:, None] * a1
    n /= np.linalg.norm(n, axis=1)[:, None]
    force = r.R_C[0].sum(axis=0) + weights.sum(axis=0)
    moment = (np.cross(platform.geometry.base_joints, r.R_C[0]).sum(axis=0)
              + (r.M_C[0][:, None] * n).sum(axis=0) + np.cross(centres, weights).sum(axis=0))
    total_weight = platform.gravity * masses.sum()
    assert np.max(np.abs(force)) <= 1e-12 * total_weight
    assert np.max(np.abs(moment)) <= 1e-12 * total_weight


# -- friction -----------------------------------------------------------------------------------

coefficient = st.floats(0.0, 0.2)


@st.composite
def friction_setup(draw):
    friction = dict(joint_viscous=draw(coefficient), joint_coulomb=draw(coefficient),
                    joint_radius=draw(st.floats(0.0, 0.1)),
                    prismatic_viscous=draw(st.floats(0.0, 5.0)),
                    prismatic_coulomb=draw(coefficient))
    effects = {
        "stribeck": dict(static=draw(st.floats(0.0, 5.0)), velocity=draw(st.floats(1e-3, 0.1))),
        "seal_friction": dict(force=draw(st.floats(0.0, 5.0))),
        "quadratic_drag": dict(coefficient=draw(st.floats(0.0, 5.0))),
        "stroke_friction": dict(slope=draw(st.floats(0.0, 10.0)),
                                reference=draw(st.floats(0.0, models.STROKE[1]))),
        "bushing_friction": dict(coefficient=draw(coefficient),
                                 spacing=draw(st.floats(0.05, 0.3))),
        "joint_friction_coupling": dict(scale=draw(unit)),
    }
    chosen = draw(st.sets(st.sampled_from(sorted(effects))))
    return friction, {name: effects[name] for name in chosen}


@EXAMPLES
@given(seed=seeds, params=motion_parameters(), setup=friction_setup())
def test_friction_dissipates_in_every_joint(seed, params, setup):
    friction, effects = setup
    platform = (random_platform(np.random.default_rng(seed)).with_friction(**friction)
                .with_effects(effects))
    r = evaluate(platform, smooth_motion(params))
    assert np.all(np.einsum("nki,nki->nk", r.MfrE, r.omega_rel) <= 0.0)
    assert np.all(np.einsum("nki,nki->nk", r.MfrC, r.omega_leg) <= 0.0)
    assert np.all(r.Ffr * r.D_dot <= 0.0)
    assert np.all(r.MfrE_s <= 0.0) and np.all(r.MfrC_s <= 0.0) and np.all(r.Ffr_s <= 0.0)
