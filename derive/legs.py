"""Leg equilibrium, equations (11)-(17), and the reduction of the 42 unknowns.

Each leg i is two rigid bodies sharing one orientation (angular velocity ``omega_L``, angular
acceleration ``alpha_L``): the lower part (zone 4) and the upper part (zone 2). The forces on the
whole leg are ``-R_Ei`` from the platform at E_i, ``R_Ci`` from the base at C_i, the universal
joint's constraint moment ``M_Ci n_i`` and gravity on both parts. Newton-Euler for the leg, with
moments about C_i:

    R_Ci - R_Ei                          = F_leg = sum_k m_k (a_k - g)               (11)-(13)
    -D u x R_Ei + M_Ci n                 = K     = sum_k [(c_k - C) x m_k (a_k - g)
                                                          + J_k alpha_L + omega_L x J_k omega_L]
                                                                                      (14)-(16)

The moment equation fixes everything in R_Ei but its axial part: its component along u gives
``M_Ci = (K.u) / (n.u)``, and crossing with u gives the transverse part
``R_Ei,perp = u x (K - M_Ci n) / D``. Both are cheapest in the leg's own axes ``[a2, u x a2, u]``
(kinematics.universal_joint_axes), where u and n have constant components. So ``R_Ei = f_i u + R_Ei,perp`` with one unknown f_i per leg,
and the platform's six equations (2)-(7) become a 6x6 linear system in f (the transpose of the
platform's Jacobian). R_Ci then follows from (11)-(13).
"""

import sympy as sp

from .vectors import cross, dot


def leg_moment(distances, forces, rotation_moments, joint):
    """K, the moment about C the leg's parts need, in the leg's axes ``[a2, b, u]``.

    A part whose centre is at ``C + s_k u`` needs the force ``F_k`` and the rotation moment
    ``M_k`` (``Inertia.rotation_moment_in_body``, leg axes):
    ``K = sum_k (s_k u x F_k) + R M_k`` with R the leg's axes. With ``S = sum_k s_k F_k``,
    ``u x S`` has the leg-axes components ``(-S . b, S . a2, 0)``.

    Parameters
    ----------
    distances : sequence of sympy.Expr
        Distances of the parts' centres from C along u, m.
    forces : sequence of sympy.Matrix, shape (3, 1)
        The parts' required forces (``Body.required_force``), base frame, N.
    rotation_moments : sequence of sympy.Matrix, shape (3, 1)
        The parts' rotation moments, leg axes, N m.
    joint : kinematics.UniversalJoint

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        K in leg axes, N m (``joint.frame * K`` in the base frame).
    """
    S = sum((s * F for s, F in zip(distances, forces)), sp.zeros(3, 1))
    M = sum(rotation_moments, sp.zeros(3, 1))
    return sp.Matrix([M[0] - dot(S, joint.b), M[1] + dot(S, joint.a2), M[2]])


def torsion_moment(K_leg, joint):
    """The universal joint's constraint moment along n: ``M_C = (K . u) / (n . u)``.

    In the leg's axes ``u = (0, 0, 1)`` and ``n = (0, -c, s)`` (c = u . a1, s^2 = 1 - c^2),
    so ``M_C = K_z / s``.

    Parameters
    ----------
    K_leg : sympy.Matrix, shape (3, 1)
        Moment about C the leg needs, leg axes, N m.
    joint : kinematics.UniversalJoint

    Returns
    -------
    sympy.Expr
        N m.
    """
    return K_leg[2] * joint.inv_sin


def transverse_end_force(K_leg, M_C, joint, D):
    """The part of R_E perpendicular to the leg: ``u x (K - M_C n) / D``.

    In the leg's axes ``K - M_C n = (K_x, K_y + c M_C, 0)`` and ``u x`` that is
    ``(-(K_y + c M_C), K_x, 0)``; in the base frame ``(K_x b - (K_y + c M_C) a2) / D``.

    Parameters
    ----------
    K_leg : sympy.Matrix, shape (3, 1)
        Moment about C the leg needs, leg axes, N m.
    M_C : sympy.Expr
        Torsion moment of the universal joint, N m.
    joint : kinematics.UniversalJoint
    D : sympy.Expr
        Leg length, m.

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        N, base frame.
    """
    return joint.b * (K_leg[0] / D) - joint.a2 * ((K_leg[1] + joint.cos * M_C) / D)


def leg_residual(R_E, R_C, M_C, u, n, D, F_leg, K):
    """Residual of (11)-(16) for one leg; zero at equilibrium.

    Parameters
    ----------
    R_E, R_C : sympy.Matrix, shape (3, 1)
        Force of the leg on the platform at E, of the base on the leg at C, base frame, N.
    M_C : sympy.Expr
        Torsion moment, N m.
    u, n : sympy.Matrix, shape (3, 1)
        Leg direction and torsion direction, base frame, 1.
    D : sympy.Expr
        Leg length, m.
    F_leg, K : sympy.Matrix, shape (3, 1)
        Required force (N) and moment about C (N m), base frame.

    Returns
    -------
    sympy.Matrix, shape (6, 1)
        Force (N) and moment (N m) residuals.
    """
    return sp.Matrix.vstack(R_C - R_E - F_leg, -D * cross(u, R_E) + M_C * n - K)
