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
"""

import sympy as sp

from .vectors import cross, dot, norm


def rotation_zxz(alpha, beta, gamma) -> sp.Matrix:
    """``T = Rz(gamma) Rx(beta) Rz(alpha)``: the paper's matrix of entries b_ij (eq. 1)."""
    def rz(t):
        return sp.Matrix([[sp.cos(t), -sp.sin(t), 0], [sp.sin(t), sp.cos(t), 0], [0, 0, 1]])

    def rx(t):
        return sp.Matrix([[1, 0, 0], [0, sp.cos(t), -sp.sin(t)], [0, sp.sin(t), sp.cos(t)]])

    return rz(gamma) * rx(beta) * rz(alpha)


def paper_b_entries(alpha, beta, gamma) -> sp.Matrix:
    """The entries b_ij exactly as the paper prints them below eq. (1)."""
    c, s = sp.cos, sp.sin
    return sp.Matrix([
        [c(alpha) * c(gamma) - c(beta) * s(alpha) * s(gamma),
         -s(alpha) * c(gamma) - c(beta) * c(alpha) * s(gamma), s(beta) * s(gamma)],
        [c(alpha) * s(gamma) + c(beta) * s(alpha) * c(gamma),
         -s(alpha) * s(gamma) + c(beta) * c(alpha) * c(gamma), -s(beta) * c(gamma)],
        [s(beta) * s(alpha), s(beta) * c(alpha), c(beta)],
    ])


def platform_point(p: sp.Matrix, T: sp.Matrix, e: sp.Matrix) -> sp.Matrix:
    """Eq. (1): a platform point in the base frame, ``E = p + T e``."""
    return p + T * e


def point_velocity(v, omega, r):
    """Velocity of a platform point at offset ``r`` (base frame) from the frame origin."""
    return v + cross(omega, r)


def point_acceleration(a, alpha, omega, r):
    """Acceleration of a platform point at offset ``r``: ``a + alpha x r + omega x (omega x r)``."""
    return a + cross(alpha, r) + cross(omega, cross(omega, r))


def leg_length_and_direction(E, C):
    """Eqs. (8)-(10): the length D and the direction cosines u = (E - C) / D."""
    r = E - C
    D = norm(r)
    return D, r / D


def leg_rates(u, D, vE, aE):
    """First and second time derivatives of the leg's length and direction.

    From ``E - C = D u`` with C fixed: ``D' = u.vE``, ``u' = (vE - D' u) / D``,
    ``D'' = u'.vE + u.aE``, ``u'' = (aE - D'' u - 2 D' u') / D``.
    """
    D_dot = dot(u, vE)
    u_dot = (vE - D_dot * u) / D
    return D_dot, u_dot


def leg_second_rates(u, u_dot, D, D_dot, vE, aE):
    D_ddot = dot(u_dot, vE) + dot(u, aE)
    u_ddot = (aE - D_ddot * u - 2 * D_dot * u_dot) / D
    return D_ddot, u_ddot


def universal_joint_axes(u, a1):
    """The second axis ``a2`` (in the leg) and the torsion direction ``n``; ``s2 = 1 - (u.a1)^2``."""
    c = dot(u, a1)
    s2 = 1 - c**2
    a2 = cross(a1, u) / sp.sqrt(s2)
    n = (u - c * a1) / sp.sqrt(s2)
    return c, s2, a2, n


def leg_angular_velocity(u, u_dot, a1, c, s2):
    """``omega_L = u x u' + lam u`` with ``lam`` such that ``omega_L . n = 0``."""
    q = dot(cross(u, u_dot), a1)
    lam = c * q / s2
    return cross(u, u_dot) + lam * u, lam, q


def leg_angular_acceleration(u, u_dot, u_ddot, a1, c, s2, lam, q):
    """Time derivative of ``leg_angular_velocity`` (a1 is constant)."""
    c_dot = dot(u_dot, a1)
    q_dot = dot(cross(u, u_ddot), a1)
    lam_dot = (c_dot * q + c * q_dot) / s2 + 2 * c**2 * c_dot * q / s2**2
    return cross(u, u_ddot) + lam_dot * u + lam * u_dot


def point_on_leg_acceleration(s, s_dot, s_ddot, u, u_dot, u_ddot):
    """Acceleration of ``s(t) u(t)``, a point at a (possibly varying) distance s along the leg."""
    return s_ddot * u + 2 * s_dot * u_dot + s * u_ddot
