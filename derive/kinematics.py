"""Kinematics: equations (1) and (8)-(10), and every velocity and acceleration the dynamics needs.

The platform frame has origin ``p`` and orientation ``T`` (platform -> base), with the platform's
angular velocity ``omega`` and angular acceleration ``alpha`` in the base frame. A leg runs from
the base joint ``C`` to the platform joint ``E``; its unit direction is ``u`` and its length ``D``.

The leg turns about the universal joint's two axes only: ``a1`` fixed in the base and
``a2 = (a1 x u) / |a1 x u|`` fixed in the leg. Its angular velocity therefore has no component
along ``n = (u - (u.a1) a1) / |u - (u.a1) a1|``, the direction of the joint's torsion moment.
Writing ``omega_L = u x u' + lam u`` (every angular velocity that turns u at the rate u') and
imposing ``omega_L . n = 0`` gives ``lam = c q / (1 - c^2)`` with ``c = u.a1`` and
``q = (u x u').a1``; differentiating gives the leg's angular acceleration.

Every function takes the chain's ``let`` (default ``inline``: plain expressions); the model
passes a ``Chain.scope`` so that each named quantity is computed once. Vectors are SymPy 3x1
matrices in the base frame, SI units.
"""

from typing import NamedTuple

import sympy as sp

from .chain import inline
from .vectors import cross, dot, norm


def rotation_zxz(alpha, beta, gamma) -> sp.Matrix:
    """``T = Rz(gamma) Rx(beta) Rz(alpha)``: the paper's matrix of entries b_ij (eq. 1).

    Parameters
    ----------
    alpha, beta, gamma : sympy.Expr
        The z-x-z Euler angles, rad.

    Returns
    -------
    sympy.Matrix, shape (3, 3)
        Rotation platform frame -> base frame, 1.
    """
    def rz(t):
        return sp.Matrix([[sp.cos(t), -sp.sin(t), 0], [sp.sin(t), sp.cos(t), 0], [0, 0, 1]])

    def rx(t):
        return sp.Matrix([[1, 0, 0], [0, sp.cos(t), -sp.sin(t)], [0, sp.sin(t), sp.cos(t)]])

    return rz(gamma) * rx(beta) * rz(alpha)


def paper_b_entries(alpha, beta, gamma) -> sp.Matrix:
    """The entries b_ij exactly as the paper prints them below eq. (1).

    Parameters
    ----------
    alpha, beta, gamma : sympy.Expr
        The z-x-z Euler angles, rad.

    Returns
    -------
    sympy.Matrix, shape (3, 3)
        The printed matrix [b_ij], 1 (equal to ``rotation_zxz``).
    """
    c, s = sp.cos, sp.sin
    return sp.Matrix([
        [c(alpha) * c(gamma) - c(beta) * s(alpha) * s(gamma),
         -s(alpha) * c(gamma) - c(beta) * c(alpha) * s(gamma), s(beta) * s(gamma)],
        [c(alpha) * s(gamma) + c(beta) * s(alpha) * c(gamma),
         -s(alpha) * s(gamma) + c(beta) * c(alpha) * c(gamma), -s(beta) * c(gamma)],
        [s(beta) * s(alpha), s(beta) * c(alpha), c(beta)],
    ])


def platform_point(p, T, e, let=inline, name="E"):
    """Eq. (1): a platform point in the base frame, ``E = p + T e``.

    Parameters
    ----------
    p : sympy.Matrix, shape (3, 1)
        Platform frame origin, base frame, m.
    T : sympy.Matrix, shape (3, 3)
        Rotation platform -> base, 1.
    e : sympy.Matrix, shape (3, 1)
        The point in the platform frame, m.
    let : callable
        The chain's ``let``; defines ``r_<name>`` and ``<name>``.

    Returns
    -------
    E : sympy.Matrix, shape (3, 1)
        The point, base frame, m.
    r : sympy.Matrix, shape (3, 1)
        Its offset ``T e`` from p, base frame, m (for velocities and moments about p).
    """
    r = let(f"r_{name}", T * e, f"r_{{{name}}}")
    return let(name, p + r, name), r


def point_velocity(v, omega, r):
    """Velocity of a point fixed to the platform: ``v + omega x r``.

    Parameters
    ----------
    v : sympy.Matrix, shape (3, 1)
        Velocity of the platform frame origin, base frame, m/s.
    omega : sympy.Matrix, shape (3, 1)
        Platform angular velocity, base frame, rad/s.
    r : sympy.Matrix, shape (3, 1)
        Offset of the point from the origin, base frame, m.

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        m/s, base frame.
    """
    return v + cross(omega, r)


def point_acceleration(a, alpha, omega, r):
    """Acceleration of a point fixed to the platform: ``a + alpha x r + omega x (omega x r)``.

    Parameters
    ----------
    a : sympy.Matrix, shape (3, 1)
        Acceleration of the platform frame origin, base frame, m/s^2.
    alpha, omega : sympy.Matrix, shape (3, 1)
        Platform angular acceleration (rad/s^2) and velocity (rad/s), base frame.
    r : sympy.Matrix, shape (3, 1)
        Offset of the point from the origin, base frame, m.

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        m/s^2, base frame.
    """
    return a + cross(alpha, r) + cross(omega, cross(omega, r))


def leg_length_and_direction(E, C, let=inline):
    """Eqs. (8)-(10): the leg's length ``D = |E - C|`` and direction cosines ``u = (E - C) / D``.

    Parameters
    ----------
    E, C : sympy.Matrix, shape (3, 1)
        Platform joint and base joint, base frame, m.
    let : callable
        The chain's ``let``; defines ``D`` and ``u``.

    Returns
    -------
    D : sympy.Expr
        Leg length, m.
    u : sympy.Matrix, shape (3, 1)
        Unit vector from C to E, base frame, 1.
    """
    r = E - C
    D = let("D", norm(r), "D")
    return D, let("u", r / D, "u")


def leg_rates(u, D, vE, let=inline):
    """First time derivatives of the leg's length and direction (C is fixed).

    From ``E - C = D u``: ``D' = u . vE`` and ``u' = (vE - D' u) / D``.

    Parameters
    ----------
    u : sympy.Matrix, shape (3, 1)
        Unit leg direction, base frame, 1.
    D : sympy.Expr
        Leg length, m.
    vE : sympy.Matrix, shape (3, 1)
        Velocity of the platform joint E, base frame, m/s.
    let : callable
        The chain's ``let``; defines ``D_dot`` and ``u_dot``.

    Returns
    -------
    D_dot : sympy.Expr
        Sliding speed of the prismatic joint, m/s.
    u_dot : sympy.Matrix, shape (3, 1)
        Rate of the direction, base frame, 1/s.
    """
    D_dot = let("D_dot", dot(u, vE), r"\dot{D}")
    return D_dot, let("u_dot", (vE - D_dot * u) / D, r"\dot{u}")


def leg_second_rates(u, u_dot, D, D_dot, vE, aE, let=inline):
    """Second time derivatives of the leg's length and direction.

    ``D'' = u' . vE + u . aE`` and ``u'' = (aE - D'' u - 2 D' u') / D``.

    Parameters
    ----------
    u, u_dot : sympy.Matrix, shape (3, 1)
        Leg direction (1) and its rate (1/s), base frame.
    D, D_dot : sympy.Expr
        Leg length (m) and its rate (m/s).
    vE, aE : sympy.Matrix, shape (3, 1)
        Velocity (m/s) and acceleration (m/s^2) of E, base frame.
    let : callable
        The chain's ``let``; defines ``D_ddot`` and ``u_ddot``.

    Returns
    -------
    D_ddot : sympy.Expr
        m/s^2.
    u_ddot : sympy.Matrix, shape (3, 1)
        1/s^2, base frame.
    """
    D_ddot = let("D_ddot", dot(u_dot, vE) + dot(u, aE), r"\ddot{D}")
    return D_ddot, let("u_ddot", (aE - D_ddot * u - 2 * D_dot * u_dot) / D, r"\ddot{u}")


class UniversalJoint(NamedTuple):
    """The universal joint's geometry for one leg (see ``universal_joint_axes``)."""

    cos: sp.Expr          #: ``c = u . a1``, 1
    sin2: sp.Expr         #: ``s^2 = 1 - c^2``, 1 (zero where the torsion moment is undefined)
    inv_sin: sp.Expr      #: ``1 / s``, 1
    a2: sp.Matrix         #: second axis, fixed in the leg, (3, 1), 1
    n: sp.Matrix          #: torsion direction, (3, 1), 1
    frame: sp.Matrix      #: leg body axes ``[a2, u x a2, u]`` as columns, (3, 3), 1

    @property
    def b(self) -> sp.Matrix:
        """``u x a2``, the leg's second body axis, (3, 1), 1."""
        return self.frame[:, 1]


def universal_joint_axes(u, a1, let=inline) -> UniversalJoint:
    """The universal joint's second axis, torsion direction and the leg's body axes.

    With ``c = u . a1`` and ``s = sqrt(1 - c^2)``: ``a2 = (a1 x u) / s`` (fixed in the leg),
    ``n = (u - c a1) / s`` (the direction of the joint's torsion moment, perpendicular to a1 and
    a2) and ``u x a2 = (a1 - c u) / s``. The leg's body axes are ``[a2, u x a2, u]``.

    Parameters
    ----------
    u : sympy.Matrix, shape (3, 1)
        Unit leg direction, base frame, 1.
    a1 : sympy.Matrix, shape (3, 1)
        Unit first axis of the joint (fixed in the base), base frame, 1.
    let : callable
        The chain's ``let``; defines ``cos_a1``, ``sin2_a1``, ``inv_sin_a1``, ``a2``, ``n`` and
        ``b`` (= u x a2).

    Returns
    -------
    UniversalJoint
    """
    c = let("cos_a1", dot(u, a1), "c")
    s2 = let("sin2_a1", 1 - c**2, "s^{2}")
    inv_s = let("inv_sin_a1", 1 / sp.sqrt(s2), "s^{-1}")
    a2 = let("a2", cross(a1, u) * inv_s, "a_{2}")
    n = let("n", (u - c * a1) * inv_s, "n")
    b = let("b", (a1 - c * u) * inv_s, "b")
    return UniversalJoint(c, s2, inv_s, a2, n, sp.Matrix.hstack(a2, b, u))


class LegSpin(NamedTuple):
    """The leg's angular velocity, in base and in its own axes (see ``leg_angular_velocity``)."""

    omega: sp.Matrix        #: base frame, (3, 1), rad/s
    omega_body: sp.Matrix   #: leg axes ``[a2, u x a2, u]``, (3, 1), rad/s
    lam: sp.Expr            #: spin about u, ``omega . u``, rad/s
    a2_u_dot: sp.Expr       #: ``a2 . u'``, 1/s
    b_u_dot: sp.Expr        #: ``(u x a2) . u'``, 1/s


def leg_angular_velocity(u, u_dot, joint: UniversalJoint, let=inline) -> LegSpin:
    """The leg's angular velocity ``omega_L = u x u' + lam u`` with ``omega_L . n = 0``.

    ``lam = c q / s^2`` with ``q = (u x u') . a1 = s (a2 . u')``, so ``lam = c (a2 . u') / s``.
    In the leg's axes ``[a2, b = u x a2, u]`` the same vector is ``(-b . u', a2 . u', lam)``.

    Parameters
    ----------
    u, u_dot : sympy.Matrix, shape (3, 1)
        Leg direction (1) and its rate (1/s), base frame.
    joint : UniversalJoint
    let : callable
        The chain's ``let``; defines ``a2_u_dot``, ``b_u_dot``, ``lam`` and ``omega_leg``.

    Returns
    -------
    LegSpin
    """
    a2_du = let("a2_u_dot", dot(joint.a2, u_dot), r"a_{2} \cdot \dot{u}")
    b_du = let("b_u_dot", dot(joint.b, u_dot), r"b \cdot \dot{u}")
    lam = let("lam", joint.cos * joint.inv_sin * a2_du, r"\lambda")
    omega = let("omega_leg", cross(u, u_dot) + lam * u, r"\omega_{L}")
    return LegSpin(omega, sp.Matrix([-b_du, a2_du, lam]), lam, a2_du, b_du)


def leg_angular_acceleration(u_dot, u_ddot, a1, joint: UniversalJoint, spin: LegSpin,
                             let=inline):
    """Time derivative of ``leg_angular_velocity`` (a1 is constant), in the leg's axes.

    ``alpha_L = u x u'' + lam' u + lam u'``; with ``c' = u' . a1`` and ``q' = s (a2 . u'')``,
    ``lam' = (c' (a2 . u') + c (a2 . u'')) / s + 2 c c' lam / s^2``. In the leg's axes
    ``[a2, b, u]``: ``(-b . u'' + lam a2 . u', a2 . u'' + lam b . u', lam')``.

    Parameters
    ----------
    u_dot, u_ddot : sympy.Matrix, shape (3, 1)
        First (1/s) and second (1/s^2) rates of the leg direction, base frame.
    a1 : sympy.Matrix, shape (3, 1)
        First axis of the universal joint, base frame, 1.
    joint : UniversalJoint
    spin : LegSpin
        From ``leg_angular_velocity``.
    let : callable
        The chain's ``let``; defines ``lam_dot`` and ``alpha_leg_body``.

    Returns
    -------
    alpha_body : sympy.Matrix, shape (3, 1)
        Leg axes, rad/s^2 (what the rotation moments need).
    alpha : sympy.Matrix, shape (3, 1)
        The same in the base frame, rad/s^2 (an expression, for reading and tests).
    """
    c, inv_s = joint.cos, joint.inv_sin
    c_dot = dot(u_dot, a1)
    a2_ddu, b_ddu = dot(joint.a2, u_ddot), dot(joint.b, u_ddot)
    lam_dot = let("lam_dot", inv_s * (c_dot * spin.a2_u_dot + c * a2_ddu
                                      + 2 * c * c_dot * spin.lam * inv_s), r"\dot{\lambda}")
    alpha_body = let("alpha_leg_body", sp.Matrix([-b_ddu + spin.lam * spin.a2_u_dot,
                                                  a2_ddu + spin.lam * spin.b_u_dot, lam_dot]),
                     r"\alpha_{L}^{leg}")
    return alpha_body, joint.frame * alpha_body


def point_on_leg_acceleration(s, s_dot, s_ddot, u, u_dot, u_ddot):
    """Acceleration of the point ``C + s(t) u(t)`` at a (possibly varying) distance s from C.

    ``s'' u + 2 s' u' + s u''``.

    Parameters
    ----------
    s, s_dot, s_ddot : sympy.Expr
        Distance from C (m) and its rates (m/s, m/s^2).
    u, u_dot, u_ddot : sympy.Matrix, shape (3, 1)
        Leg direction and its rates, base frame (1, 1/s, 1/s^2).

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        m/s^2, base frame.
    """
    return s_ddot * u + 2 * s_dot * u_dot + s * u_ddot
