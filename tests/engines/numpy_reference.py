"""A reference engine of the actuator forces in plain NumPy, independent of the compiled model.

It computes what the compiled map ``Evaluator.actuator_forces`` computes (actuator forces with
friction and the catalog's effects, kinematic mode) from a platform and states ``x`` (N, 24)
laid out as ``state_array``. tests/test_reference_impl.py compares the two at random states of
perturbed platforms; benchmarks/throughput.py times the compiled map against it.

Independent by design:

* What it takes from gsfric is the definition of the inputs only: the ``Platform``'s numbers,
  the state layout (``state_layout``), the regularisation speeds and the prismatic joint's
  point (``evaluation.parameters``), and the effects' parameter names and defaults
  (``platform.catalog.EFFECTS``). Nothing from derive/, generated/ or the compiled functions,
  and no formula: tests/test_reference_impl.py checks these imports.
* The mechanics is written from the paper's equations as vector mechanics, not from derive/'s
  SymPy: the equilibrium (2)-(16) of platform, payload and legs (sums of forces, moments about
  p and about C_i, Newton-Euler with gravity on every body, with the corrections listed in
  docs/reference/errata.md), the prismatic joint (28)-(32) and friction (33)-(35). The effects
  are written from their definitions in docs/reference/effects.md.
* Two formulations that share only those numbers (``parameters``):

  - ``actuator_forces_loop``: one step at a time, the paper's way: the dense 42x42 system of
    (2)-(16) (unknowns R_E, R_C, M_C; ``system_42``) built and solved at every step, then the
    prismatic joint and friction; no reduction.
  - ``actuator_forces_numpy``: vectorised over steps; R_C and M_C eliminated by hand, leaving
    one 6x6 system per step in the legs' axial forces, solved for every step at once.

So an error in derive/'s reduction, the code generation, the SIMD-over-steps code or the
packing of the parameters shows as a difference from both; an error common to all three would
have to be in the published definition of an equation or an effect itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gsfric.compiled.state import state_layout
from gsfric.evaluation.parameters import JOINT_EPS, PRISMATIC_EPS, PRISMATIC_POINT
from gsfric.platform.catalog import EFFECTS
from gsfric.platform.description import Platform

N_LEGS = 6
N_UNKNOWNS = 42
"""Unknowns of (2)-(16): R_E (18: leg i's force on the platform at E_i, base frame), R_C (18:
the base's force on leg i at C_i), M_C (6: the universal joints' moments along n_i)."""

@dataclass(frozen=True)
class Parameters:
    """A platform's numbers as the model uses them (SI units, base frame unless stated).

    Attributes
    ----------
    gravity : ndarray (3,)
        Gravitational acceleration vector ``(0, 0, -g)``.
    base_joints, platform_joints, universal_axes : ndarray (6, 3)
        C_i (base frame), E_i (platform frame), the universal joints' first axes a1 (unit).
    bodies : tuple of (mass, inertia (3, 3), com (3,))
        Platform and payload; inertia about the centre of mass and com in the platform frame
        (the payload's com includes the ``payload_offset`` effect).
    lower, upper : dict
        Leg parts: ``mass``, ``weight_mass`` (mass whose weight acts, with the ``leg_weight``
        effect), ``com`` and ``frac`` (centre at ``com + frac D`` from C_i, resp. from E_i),
        ``inertia`` (3, 3) in the leg's body frame.
    prismatic_point : float
        Prismatic joint point P_3 at ``C + prismatic_point D u``.
    joint_viscous, joint_coulomb, joint_radius, prismatic_viscous, prismatic_coulomb : float
        Friction coefficients of (33)-(35).
    joint_eps, prismatic_eps : float
        Regularisation speeds of the sign functions, rad/s and m/s.
    effects : dict
        Every catalog effect's parameters ``"effect.parameter" -> value`` (defaults filled in).
    """

    gravity: np.ndarray
    base_joints: np.ndarray
    platform_joints: np.ndarray
    universal_axes: np.ndarray
    bodies: tuple
    lower: dict
    upper: dict
    prismatic_point: float
    joint_viscous: float
    joint_coulomb: float
    joint_radius: float
    prismatic_viscous: float
    prismatic_coulomb: float
    joint_eps: float
    prismatic_eps: float
    effects: dict


def parameters(platform: Platform) -> Parameters:
    """The numbers of ``platform`` that both implementations use."""

    q = {f"{name}.{p}": float(platform.effects.get(name, {}).get(p, default))
         for name, params in EFFECTS.items() for p, default in params.items()}
    g, body, legs, fr = platform.geometry, platform.platform, platform.legs, platform.friction
    l4, k4, l2, k2 = legs.com_placement()
    weight = float(legs.weight)
    offset = np.array([q["payload_offset.x"], q["payload_offset.y"], q["payload_offset.z"]])
    return Parameters(
        gravity=np.array([0.0, 0.0, -platform.gravity]),
        base_joints=np.asarray(g.base_joints, float),
        platform_joints=np.asarray(g.platform_joints, float),
        universal_axes=np.asarray(g.universal_axes, float),
        bodies=((body.mass, np.asarray(body.inertia, float), np.asarray(body.com, float)),
                (body.payload_mass, np.asarray(body.payload_inertia, float),
                 np.asarray(body.payload_com, float) + offset)),
        lower=dict(mass=legs.lower_mass, com=l4, frac=k4,
                   weight_mass=weight * legs.lower_mass + q["leg_weight.lower_mass"],
                   inertia=np.asarray(legs.lower_inertia, float)),
        upper=dict(mass=legs.upper_mass, com=l2, frac=k2,
                   weight_mass=weight * legs.upper_mass + q["leg_weight.upper_mass"],
                   inertia=np.asarray(legs.upper_inertia, float)),
        prismatic_point=PRISMATIC_POINT,
        joint_viscous=fr.joint_viscous, joint_coulomb=fr.joint_coulomb,
        joint_radius=fr.joint_radius, prismatic_viscous=fr.prismatic_viscous,
        prismatic_coulomb=fr.prismatic_coulomb, joint_eps=JOINT_EPS,
        prismatic_eps=PRISMATIC_EPS, effects=q)


def _prismatic_effects(q: dict, v, sgn_v, D, bending):
    """The effects' friction force on the upper part along u (docs/reference/effects.md).

    ``bending`` is ``|u x M_3|``, the part of the prismatic joint's moment across the leg. The
    Coulomb parts are summed and the sum kept non-negative (friction never pushes).
    """
    coulomb = np.maximum(0.0, q["stribeck.static"] * np.exp(-(v / q["stribeck.velocity"]) ** 2)
                         + q["seal_friction.force"]
                         + q["stroke_friction.slope"] * (D - q["stroke_friction.reference"])
                         + q["bushing_friction.coefficient"] * 2 * bending
                         / q["bushing_friction.spacing"])
    return -sgn_v * coulomb - q["quadratic_drag.coefficient"] * v * np.abs(v)


# ---------------------------------------------------------------------- vectorised over steps
# Vectors are stored component first: shape (3, ...), so that every operation on a component is
# one operation on a contiguous array; matrices are (3, 3, ...).

def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of vectors (3, ...), broadcasting the trailing axes."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product of vectors (3, ...); the result has the trailing axes only."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(_dot(a, a))


def _matvec(M: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``M a`` for matrices (3, 3, ...) and vectors (3, ...)."""
    return M[:, 0] * a[0] + M[:, 1] * a[1] + M[:, 2] * a[2]


def _rotated_inertia_times(R: np.ndarray, inertia: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``(R I R^T) a`` for rotations R (3, 3, ...), a body-frame inertia I (3, 3), vectors a."""
    body = R[0] * a[0] + R[1] * a[1] + R[2] * a[2]
    return _matvec(R, np.tensordot(inertia, body, axes=1))


def _inertial_moment(R, inertia, alpha, omega):
    """``J alpha + omega x (J omega)`` with ``J = R I R^T`` (Euler's equations, base frame)."""
    return (_rotated_inertia_times(R, inertia, alpha)
            + _cross(omega, _rotated_inertia_times(R, inertia, omega)))


def actuator_forces_numpy(platform: Platform, x: np.ndarray, chunk: int = 2048) -> np.ndarray:
    """Actuator forces with friction, vectorised NumPy over steps.

    Parameters
    ----------
    platform : Platform
    x : ndarray, shape (N, 24)
        States as ``gsfric.evaluation.state_array``: p (m), T row-major, v (m/s), omega (rad/s),
        a (m/s^2), alpha (rad/s^2), base frame.
    chunk : int
        Steps evaluated together (bounds the temporary arrays; about 20 kB per step).

    Returns
    -------
    ndarray, shape (N, 6), N
        Actuator forces F (positive pushing the platform away from the base), friction and the
        platform's effects included: ``Evaluator.actuator_forces``.
    """
    prm = parameters(platform)
    x = np.asarray(x, dtype=float)
    out = np.empty((x.shape[0], N_LEGS))
    for start in range(0, x.shape[0], chunk):
        out[start:start + chunk] = _forces_block(prm, x[start:start + chunk])
    return out


@dataclass
class _LegMotion:
    """The six legs' kinematics over a block of n steps: vectors (3, n, 6), scalars (n, 6).

    (1), (8)-(10), with the spin the universal joint allows: ``r_E = E_i - p``, ``E`` the
    platform joints, ``D``, ``u`` (unit, C_i to E_i), ``n`` the universal joint's torsion
    direction, ``a2`` its second axis, ``D_dot``, ``u_dot``, ``D_ddot``, ``u_ddot``, ``aE`` the
    acceleration of E_i, ``w_L`` and ``al_L`` the leg's angular velocity and acceleration.
    """

    r_E: np.ndarray
    E: np.ndarray
    D: np.ndarray
    u: np.ndarray
    n: np.ndarray
    a2: np.ndarray
    D_dot: np.ndarray
    u_dot: np.ndarray
    D_ddot: np.ndarray
    u_ddot: np.ndarray
    aE: np.ndarray
    w_L: np.ndarray
    al_L: np.ndarray


def _platform_loads(prm: Parameters, T, w, a, al, like: np.ndarray):
    """Resultant force and moment about p that platform and payload need, (2)-(7), (3, n)."""
    g = prm.gravity
    F_req = np.zeros_like(like)
    M_req = np.zeros_like(like)
    for mass, inertia, com in prm.bodies:
        r = np.tensordot(com, T, axes=([0], [1]))
        a_c = a + _cross(al, r) + _cross(w, _cross(w, r))
        force = mass * (a_c - g[:, None])
        F_req += force
        M_req += _cross(r, force) + _inertial_moment(T, inertia, al, w)
    return F_req, M_req


def _leg_motion(prm: Parameters, p, T, v, wl, a, al_l) -> _LegMotion:
    """The legs' kinematics for platform states over a block (``wl``, ``al_l``: (3, n, 1))."""
    C, a1 = prm.base_joints.T[:, None], prm.universal_axes.T[:, None]
    r_E = np.einsum("ijn,kj->ink", T, prm.platform_joints)
    E = p[..., None] + r_E
    D = _norm(E - C)
    u = (E - C) / D
    vE = v[..., None] + _cross(wl, r_E)
    D_dot = _dot(u, vE)
    u_dot = (vE - D_dot * u) / D
    c = _dot(u, a1)
    s2 = 1 - c**2
    a2 = _cross(a1, u) / np.sqrt(s2)
    n = (u - c * a1) / np.sqrt(s2)
    u_x_ud = _cross(u, u_dot)
    qq = _dot(u_x_ud, a1)
    lam = c * qq / s2
    w_L = u_x_ud + lam * u
    aE = a[..., None] + _cross(al_l, r_E) + _cross(wl, _cross(wl, r_E))
    D_ddot = _dot(u_dot, vE) + _dot(u, aE)
    u_ddot = (aE - D_ddot * u - 2 * D_dot * u_dot) / D
    u_x_udd = _cross(u, u_ddot)
    c_dot = _dot(u_dot, a1)
    lam_dot = (c_dot * qq + c * _dot(u_x_udd, a1)) / s2 + 2 * c**2 * c_dot * qq / s2**2
    al_L = u_x_udd + lam_dot * u + lam * u_dot
    return _LegMotion(r_E=r_E, E=E, D=D, u=u, n=n, a2=a2, D_dot=D_dot, u_dot=u_dot,
                      D_ddot=D_ddot, u_ddot=u_ddot, aE=aE, w_L=w_L, al_L=al_L)


def _leg_part_loads(prm: Parameters, m: _LegMotion):
    """The loads the leg parts need (11)-(17): the upper part's force ``f2``, its centre's
    distance from E_i ``s2E`` and inertial moment, the legs' force ``F_leg`` and moment about
    C_i ``K`` (B = the leg's body frame)."""
    u, D, D_dot, D_ddot, u_dot, u_ddot = m.u, m.D, m.D_dot, m.D_ddot, m.u_dot, m.u_ddot
    C = prm.base_joints.T[:, None]
    B = np.stack([m.a2, _cross(u, m.a2), u], axis=1)
    low, up = prm.lower, prm.upper
    s4 = low["com"] + low["frac"] * D
    s2E = up["com"] + up["frac"] * D
    a4 = low["frac"] * D_ddot * u + 2 * low["frac"] * D_dot * u_dot + s4 * u_ddot
    a2c = m.aE - (up["frac"] * D_ddot * u + 2 * up["frac"] * D_dot * u_dot + s2E * u_ddot)
    g_l = prm.gravity[:, None, None]
    f4 = low["mass"] * a4 - low["weight_mass"] * g_l
    f2 = up["mass"] * a2c - up["weight_mass"] * g_l
    inertial2 = _inertial_moment(B, up["inertia"], m.al_L, m.w_L)
    F_leg = f4 + f2
    K = (_cross(s4 * u, f4) + _cross(m.E - s2E * u - C, f2)
         + _inertial_moment(B, low["inertia"], m.al_L, m.w_L) + inertial2)
    return f2, s2E, inertial2, F_leg, K


def _forces_block(prm: Parameters, x: np.ndarray) -> np.ndarray:
    """``actuator_forces_numpy`` for one block of steps x (n, 24)."""
    xt = np.ascontiguousarray(x.T)
    states = state_layout()
    p, v, w = xt[states.position], xt[states.velocity], xt[states.omega]
    a, al = xt[states.acceleration], xt[states.alpha]
    T = xt[states.rotation].reshape(3, 3, -1)
    q = prm.effects
    F_req, M_req = _platform_loads(prm, T, w, a, al, like=p)
    wl = w[..., None]
    m = _leg_motion(prm, p, T, v, wl, a, al[..., None])
    u, n, D, r_E = m.u, m.n, m.D, m.r_E
    f2, s2E, inertial2, F_leg, K = _leg_part_loads(prm, m)

    # the reduction: M_C and the transverse part of R_E per leg; a 6x6 system in the axial forces
    n_u = _dot(n, u)
    M_C = _dot(K, u) / n_u
    t_E = _cross(u, K - M_C * n) / D
    A = np.concatenate([u, _cross(r_E, u)]).transpose(1, 0, 2)
    rhs = np.concatenate([F_req - t_E.sum(-1), M_req - _cross(r_E, t_E).sum(-1)]).T
    f = np.linalg.solve(A, rhs[..., None])[..., 0]
    R_E = f * u + t_E
    R_C = R_E + F_leg

    # prismatic joint (28)-(32)
    total = R_E + f2
    F0 = _dot(u, total)
    R_3 = total - F0 * u
    to_P3 = D * (1 - prm.prismatic_point) * u
    M_3 = _cross(to_P3, R_E) + _cross(to_P3 - s2E * u, f2) + inertial2

    # friction (33)-(35) and the catalog's prismatic effects
    MfrE = _joint_friction_block(prm, wl - m.w_L, R_E)
    MfrC = _joint_friction_block(prm, m.w_L, R_C)
    sgn_v = m.D_dot / np.sqrt(m.D_dot**2 + prm.prismatic_eps**2)
    Ffr = (-(prm.prismatic_viscous * m.D_dot + prm.prismatic_coulomb * _norm(R_3) * sgn_v)
           + _prismatic_effects(q, m.D_dot, sgn_v, D, _norm(_cross(u, M_3))))

    # joint friction moments carried by the actuators (joint_friction_coupling)
    dK = MfrE - MfrC
    dt = _cross(u, dK - (_dot(dK, u) / n_u) * n) / D
    rhs = np.concatenate([-dt.sum(-1), -(_cross(r_E, dt) + MfrE).sum(-1)]).T
    df = np.linalg.solve(A, rhs[..., None])[..., 0]

    bias = np.array([q[f"sensor_bias.b{i}"] for i in range(1, N_LEGS + 1)])
    return F0 + q["joint_friction_coupling.scale"] * df - Ffr + bias


def _joint_friction_block(prm: Parameters, omega, R):
    """(33)-(34): a joint's friction moment for relative angular velocities (3, n, 6)."""
    c_s, mu_r = prm.joint_viscous, prm.joint_coulomb * prm.joint_radius
    speed = np.sqrt(_dot(omega, omega) + prm.joint_eps**2)
    return -(c_s * omega + (mu_r * _norm(R) / speed) * omega)


# ------------------------------------------------------------------------ one step at a time
def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of two 3-vectors."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _norm3(a: np.ndarray) -> float:
    return math.sqrt(a @ a)


def _skew(a: np.ndarray) -> np.ndarray:
    """The matrix [a x] with ``[a x] b = a x b``."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


@dataclass
class _Leg:
    """One leg at one step: kinematics and the loads its parts need (3-vectors, base frame)."""

    r_E: np.ndarray      # E_i - p
    D: float
    u: np.ndarray
    n: np.ndarray        # torsion direction of the universal joint
    D_dot: float
    omega: np.ndarray    # leg angular velocity
    f2: np.ndarray       # m_2 a_2 - (weight mass) g of the upper part
    c2_E: np.ndarray     # centre of the upper part minus E_i
    inertial2: np.ndarray  # J_2 alpha + omega x J_2 omega of the upper part
    F_leg: np.ndarray    # (11)-(13) right-hand side
    K: np.ndarray        # (14)-(16) right-hand side, moments about C_i


def _leg_step(prm: Parameters, i: int, p, T, v, w, a, al) -> _Leg:
    C, a1 = prm.base_joints[i], prm.universal_axes[i]
    r_E = T @ prm.platform_joints[i]
    E = p + r_E
    D = _norm3(E - C)
    u = (E - C) / D
    vE = v + _cross3(w, r_E)
    aE = a + _cross3(al, r_E) + _cross3(w, _cross3(w, r_E))
    D_dot = u @ vE
    u_dot = (vE - D_dot * u) / D
    D_ddot = u_dot @ vE + u @ aE
    u_ddot = (aE - D_ddot * u - 2 * D_dot * u_dot) / D

    # universal joint: the leg turns about a1 and a2 = a1 x u / |a1 x u| only
    c = u @ a1
    s2 = 1 - c * c
    a2 = _cross3(a1, u) / np.sqrt(s2)
    n = (u - c * a1) / np.sqrt(s2)
    q = _cross3(u, u_dot) @ a1
    lam = c * q / s2
    omega = _cross3(u, u_dot) + lam * u
    c_dot = u_dot @ a1
    q_dot = _cross3(u, u_ddot) @ a1
    lam_dot = (c_dot * q + c * q_dot) / s2 + 2 * c * c * c_dot * q / s2**2
    alpha = _cross3(u, u_ddot) + lam_dot * u + lam * u_dot

    B = np.column_stack([a2, _cross3(u, a2), u])
    F_leg = np.zeros(3)
    K = np.zeros(3)
    parts = {}
    for name, sign in (("lower", 1.0), ("upper", -1.0)):
        part = prm.lower if name == "lower" else prm.upper
        s = part["com"] + part["frac"] * D
        k = part["frac"]
        along = k * D_ddot * u + 2 * k * D_dot * u_dot + s * u_ddot
        centre, acc = (C + s * u, along) if sign > 0 else (E - s * u, aE - along)
        force = part["mass"] * acc - part["weight_mass"] * prm.gravity
        J = B @ part["inertia"] @ B.T
        inertial = J @ alpha + _cross3(omega, J @ omega)
        F_leg += force
        K += _cross3(centre - C, force) + inertial
        parts[name] = (centre, force, inertial)
    c2, f2, inertial2 = parts["upper"]
    return _Leg(r_E=r_E, D=D, u=u, n=n, D_dot=D_dot, omega=omega, f2=f2, c2_E=c2 - E,
                inertial2=inertial2, F_leg=F_leg, K=K)


def _platform_step(prm: Parameters, T, w, a, al):
    """Resultant force and moment about p that platform and payload need, (2)-(7)."""
    F_req = np.zeros(3)
    M_req = np.zeros(3)
    for mass, inertia, com in prm.bodies:
        r = T @ com
        force = mass * (a + _cross3(al, r) + _cross3(w, _cross3(w, r))) - mass * prm.gravity
        J = T @ inertia @ T.T
        F_req += force
        M_req += _cross3(r, force) + J @ al + _cross3(w, J @ w)
    return F_req, M_req


def _matrix_42(legs: list[_Leg]) -> np.ndarray:
    """The coefficients of (2)-(16) in the unknowns (R_E, R_C, M_C).

    Rows 0-2: sum of R_Ei; rows 3-5: sum of (E_i - p) x R_Ei (moments about p); rows 6 + 6i ..
    6 + 6i + 2: R_Ci - R_Ei; rows 6 + 6i + 3 .. 6 + 6i + 5: -D_i u_i x R_Ei + M_Ci n_i (leg i's
    moments about C_i).
    """
    M = np.zeros((N_UNKNOWNS, N_UNKNOWNS))
    eye = np.eye(3)
    for i, L in enumerate(legs):
        e, c, row = slice(3 * i, 3 * i + 3), slice(18 + 3 * i, 21 + 3 * i), 6 + 6 * i
        M[0:3, e] = eye
        M[3:6, e] = _skew(L.r_E)
        M[row:row + 3, c] = eye
        M[row:row + 3, e] = -eye
        M[row + 3:row + 6, e] = -L.D * _skew(L.u)
        M[row + 3:row + 6, 36 + i] = L.n
    return M


def _rhs_42(F_req, M_req, legs: list[_Leg]) -> np.ndarray:
    return np.concatenate([F_req, M_req] + [np.concatenate([L.F_leg, L.K]) for L in legs])


def system_42(platform: Platform, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The dense system of (2)-(16) at one step.

    Parameters
    ----------
    platform : Platform
    state : ndarray, shape (24,)
        One state (``state_array`` layout).

    Returns
    -------
    A : ndarray, shape (42, 42)
    b : ndarray, shape (42,)
        ``A z = b`` for ``z = (R_E (6x3 row-major), R_C (6x3), M_C (6))``, N and N m.
    """
    prm = parameters(platform)
    p, T, v, w, a, al = state_layout().split(np.asarray(state, dtype=float))
    legs = [_leg_step(prm, i, p, T, v, w, a, al) for i in range(N_LEGS)]
    F_req, M_req = _platform_step(prm, T, w, a, al)
    return _matrix_42(legs), _rhs_42(F_req, M_req, legs)


def _joint_friction(prm: Parameters, omega, R):
    speed = np.sqrt(omega @ omega + prm.joint_eps**2)
    return -(prm.joint_viscous * omega
             + prm.joint_coulomb * prm.joint_radius * _norm3(R) * omega / speed)


def actuator_forces_loop(platform: Platform, x: np.ndarray) -> np.ndarray:
    """Actuator forces with friction, one step at a time with the dense 42x42 system.

    At every step: the legs' kinematics, the system of (2)-(16) solved with
    ``numpy.linalg.solve``, the prismatic joint (28)-(32), friction (33)-(35) and the catalog's
    effects; the joints' friction moments carried by the actuators
    (``joint_friction_coupling``) come from a second solve of the same system.

    Parameters
    ----------
    platform : Platform
    x : ndarray, shape (N, 24)
        States (``state_array`` layout).

    Returns
    -------
    ndarray, shape (N, 6), N
        The same forces as ``actuator_forces_numpy`` and ``Evaluator.actuator_forces``.
    """
    prm = parameters(platform)
    q = prm.effects
    scale = q["joint_friction_coupling.scale"]
    bias = np.array([q[f"sensor_bias.b{i}"] for i in range(1, N_LEGS + 1)])
    x = np.asarray(x, dtype=float)
    out = np.empty((x.shape[0], N_LEGS))
    for k in range(x.shape[0]):
        p, T, v, w, a, al = state_layout().split(x[k])
        legs = [_leg_step(prm, i, p, T, v, w, a, al) for i in range(N_LEGS)]
        F_req, M_req = _platform_step(prm, T, w, a, al)
        M = _matrix_42(legs)
        z = np.linalg.solve(M, _rhs_42(F_req, M_req, legs))
        R_E, R_C = z[:18].reshape(N_LEGS, 3), z[18:36].reshape(N_LEGS, 3)
        coupling = np.zeros(N_UNKNOWNS)
        for i, L in enumerate(legs):
            total = R_E[i] + L.f2
            F0 = L.u @ total
            R_3 = total - F0 * L.u
            P3_E = -(1 - prm.prismatic_point) * L.D * L.u
            M_3 = _cross3(-P3_E, R_E[i]) + _cross3(L.c2_E - P3_E, L.f2) + L.inertial2
            MfrE = _joint_friction(prm, w - L.omega, R_E[i])
            MfrC = _joint_friction(prm, L.omega, R_C[i])
            v_s = L.D_dot
            sgn_v = v_s / np.sqrt(v_s * v_s + prm.prismatic_eps**2)
            Ffr = (-(prm.prismatic_viscous * v_s
                     + prm.prismatic_coulomb * _norm3(R_3) * sgn_v)
                   + _prismatic_effects(q, v_s, sgn_v, L.D,
                                        _norm3(_cross3(L.u, M_3))))
            out[k, i] = F0 - Ffr + bias[i]
            coupling[3:6] -= MfrE
            coupling[6 + 6 * i + 3:6 + 6 * i + 6] = MfrE - MfrC
        dz = np.linalg.solve(M, coupling)
        for i, L in enumerate(legs):
            out[k, i] += scale * (L.u @ dz[3 * i:3 * i + 3])
    return out
