"""Helpers of the independent validation: random platforms, the Pinocchio engine's inputs, and
energies of the hexapod computed from positions alone.

Nothing here uses gsfric's dynamics: the energies come from the platform pose and the geometry,
with velocities by finite differences in time.
"""

from __future__ import annotations

import numpy as np

import gsfric
from gsfric import models

try:
    from engines import pinocchio_hexapod as engine
except ImportError:
    from tests.engines import pinocchio_hexapod as engine


def random_inertia(rng: np.random.Generator, scale: float) -> np.ndarray:
    """A full (non-diagonal) inertia tensor of a physical body, principal moments ~ scale."""
    principal = scale * rng.uniform(0.5, 1.0, 3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q @ np.diag(principal) @ q.T


def random_platform(rng: np.random.Generator) -> gsfric.Platform:
    """The reference platform with moved joints, tilted universal axes, full inertias, offset
    centres of mass and payload, and random masses (rigid leg model)."""
    base = models.reference_platform("paper")
    g = base.geometry
    axes = g.universal_axes + rng.uniform(-0.3, 0.3, (6, 3))
    return (base
            .replace(gravity=rng.uniform(5.0, 15.0))
            .with_geometry(base_joints=g.base_joints + rng.uniform(-0.03, 0.03, (6, 3)),
                           platform_joints=g.platform_joints + rng.uniform(-0.03, 0.03, (6, 3)),
                           universal_axes=axes / np.linalg.norm(axes, axis=1)[:, None])
            .with_body(mass=rng.uniform(5.0, 20.0), inertia=random_inertia(rng, 0.1),
                       com=rng.uniform(-0.03, 0.03, 3), payload_mass=rng.uniform(1.0, 5.0),
                       payload_inertia=random_inertia(rng, 0.02),
                       payload_com=rng.uniform(-0.08, 0.08, 3))
            .with_legs(model="rigid", lower_mass=rng.uniform(0.3, 2.0),
                       upper_mass=rng.uniform(0.3, 2.0), lower_com=rng.uniform(0.05, 0.3),
                       upper_com=rng.uniform(0.05, 0.3), lower_inertia=random_inertia(rng, 0.02),
                       upper_inertia=random_inertia(rng, 0.02)))


def combined_body(body) -> tuple[float, np.ndarray, np.ndarray]:
    """Platform and payload as one rigid body: mass, centre of mass (platform frame) and inertia
    about that centre (platform frame), by the parallel-axis theorem."""
    parts = ((body.mass, body.com, body.inertia),
             (body.payload_mass, body.payload_com, body.payload_inertia))
    mass = sum(m for m, _, _ in parts)
    com = sum(m * np.asarray(c) for m, c, _ in parts) / mass
    inertia = np.zeros((3, 3))
    for m, c, inertia_c in parts:
        r = np.asarray(c) - com
        inertia += inertia_c + m * (r @ r * np.eye(3) - np.outer(r, r))
    return mass, com, inertia


def engine_geometry(platform: gsfric.Platform) -> dict:
    """The Pinocchio engine's description of a platform with the rigid leg model."""
    assert platform.legs.model == "rigid" and platform.legs.weight
    mass, com, inertia = combined_body(platform.platform)
    g, legs = platform.geometry, platform.legs
    return dict(gravity=platform.gravity, base_joints=g.base_joints,
                platform_joints=g.platform_joints, universal_axes=g.universal_axes,
                platform_mass=mass, platform_com=com, platform_inertia=inertia,
                lower_mass=legs.lower_mass, lower_com=legs.lower_com,
                lower_inertia=legs.lower_inertia, upper_mass=legs.upper_mass,
                upper_com=legs.upper_com, upper_inertia=legs.upper_inertia)


def engine_results(platform: gsfric.Platform, motion: gsfric.Motion) -> dict[str, np.ndarray]:
    """The engine's outputs at every step of a motion, stacked with the step as leading axis."""
    geom = engine_geometry(platform)
    steps = []
    for k in range(len(motion)):
        state = dict(position=motion.position[k], rotation=motion.rotation[k],
                     velocity=motion.velocity[k], omega=motion.omega[k],
                     acceleration=motion.acceleration[k], alpha=motion.alpha[k])
        steps.append(engine.inverse_dynamics(geom, state))
    return {key: np.array([s[key] for s in steps]) for key in steps[0]}


def relative_difference(value: np.ndarray, reference: np.ndarray) -> float:
    """Largest absolute difference, relative to the largest magnitude of the reference."""
    return float(np.max(np.abs(value - reference)) / np.max(np.abs(reference)))


# -- energies from positions ------------------------------------------------------------------

FD_STEP = 1e-3
"""Time step of the finite differences, s (fourth-order central: error ~ FD_STEP^4)."""


def fd_derivative(function, t: np.ndarray, h: float = FD_STEP) -> np.ndarray:
    """Fourth-order central difference of ``function(t)`` (arrays with time leading)."""
    return (function(t - 2 * h) - 8 * function(t - h) + 8 * function(t + h)
            - function(t + 2 * h)) / (12 * h)


def vee(skew: np.ndarray) -> np.ndarray:
    """Axial vectors (N, 3) of (nearly) skew matrices (N, 3, 3)."""
    return 0.5 * np.stack([skew[:, 2, 1] - skew[:, 1, 2], skew[:, 0, 2] - skew[:, 2, 0],
                           skew[:, 1, 0] - skew[:, 0, 1]], axis=1)


def fd_angular_velocity(frames, t: np.ndarray, h: float = FD_STEP) -> np.ndarray:
    """Angular velocities (base frame) of orientations ``frames(t)``, (N, ..., 3, 3):
    vee(dR/dt R^T)."""
    R = frames(t)
    dR = fd_derivative(frames, t, h)
    W = dR @ np.swapaxes(R, -1, -2)
    shape = W.shape[:-2]
    return vee(W.reshape(-1, 3, 3)).reshape(shape + (3,))


class Bodies:
    """Positions and orientations of every body of a platform, from the platform pose only.

    ``pose(t)`` returns (position (N, 3), rotation (N, 3, 3)) of the platform frame. The bodies:
    the platform, the payload, and each leg's lower part (centre ``C + lower_com u``) and upper
    part (centre ``E - upper_com u``), turning with the leg frame ``(a2, u x a2, u)``,
    ``a2 = normalize(a1 x u)`` (rigid leg model).
    """

    def __init__(self, platform: gsfric.Platform, pose) -> None:
        assert platform.legs.model == "rigid"
        self.platform = platform
        self.pose = pose

    def legs(self, t):
        g = self.platform.geometry
        p, R = self.pose(t)
        E = p[:, None, :] + np.einsum("nij,kj->nki", R, g.platform_joints)
        CE = E - g.base_joints
        d = np.linalg.norm(CE, axis=2)
        u = CE / d[..., None]
        a2 = np.cross(g.universal_axes, u)
        a2 /= np.linalg.norm(a2, axis=2)[..., None]
        frame = np.stack([a2, np.cross(u, a2), u], axis=-1)
        return E, d, u, frame

    def lengths(self, t):
        return self.legs(t)[1]

    def centres(self, t):
        """Centres of mass (N, 14, 3): platform, payload, 6 lower parts, 6 upper parts."""
        b, legs = self.platform.platform, self.platform.legs
        p, R = self.pose(t)
        E, _, u, _ = self.legs(t)
        return np.concatenate([(p + R @ b.com)[:, None], (p + R @ b.payload_com)[:, None],
                               self.platform.geometry.base_joints + legs.lower_com * u,
                               E - legs.upper_com * u], axis=1)

    def orientations(self, t):
        """Orientations (N, 8, 3, 3): platform, payload (the platform's), 6 legs."""
        _, R = self.pose(t)
        frames = self.legs(t)[3]
        return np.concatenate([R[:, None], R[:, None], frames], axis=1)

    def masses_inertias(self):
        b, legs = self.platform.platform, self.platform.legs
        masses = np.array([b.mass, b.payload_mass] + [legs.lower_mass] * 6
                          + [legs.upper_mass] * 6)
        inertias = ([b.inertia, b.payload_inertia] + [legs.lower_inertia] * 6
                    + [legs.upper_inertia] * 6)
        return masses, np.array(inertias)

    def energies(self, t):
        """Kinetic and potential energy (N,) each, J, with finite-difference velocities."""
        masses, inertias = self.masses_inertias()
        v = fd_derivative(self.centres, t)
        w8 = fd_angular_velocity(self.orientations, t)
        w = np.concatenate([w8, w8[:, 2:]], axis=1)  # both parts of a leg share its rotation
        frames = self.orientations(t)
        frames = np.concatenate([frames, frames[:, 2:]], axis=1)
        inertia_world = frames @ inertias @ np.swapaxes(frames, -1, -2)
        kinetic = 0.5 * (np.einsum("k,nki,nki->n", masses, v, v)
                         + np.einsum("nki,nkij,nkj->n", w, inertia_world, w))
        potential = self.platform.gravity * np.einsum("k,nk->n", masses,
                                                      self.centres(t)[:, :, 2])
        return kinetic, potential

    def leg_rates(self, t):
        """Leg length rates (N, 6) by finite differences."""
        return fd_derivative(self.lengths, t)

    def angular_velocities(self, t):
        """Platform (N, 3) and leg (N, 6, 3) angular velocities by finite differences."""
        w8 = fd_angular_velocity(self.orientations, t)
        return w8[:, 0], w8[:, 2:]


def motion_pose(motion_of_t):
    """``pose(t)`` of a motion given as a function of time (position, rotation)."""
    def pose(t):
        m = motion_of_t(t)
        return m.position, m.rotation
    return pose
