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
``R_Ei,perp = u x (K - M_Ci n) / D``. So ``R_Ei = f_i u + R_Ei,perp`` with one unknown f_i per leg,
and the platform's six equations (2)-(7) become a 6x6 linear system in f (the transpose of the
platform's Jacobian). R_Ci then follows from (11)-(13).
"""

import sympy as sp

from .mechanics import Wrench
from .vectors import cross, dot


def leg_required(wrenches, C):
    """The wrench, about C, that the leg's parts need: the sum of their required wrenches.

    Parameters
    ----------
    wrenches : sequence of mechanics.Wrench
        Required wrench of each part (``Body.required_wrench``), any reference point.
    C : sympy.Matrix, shape (3, 1)
        Base joint, base frame, m.

    Returns
    -------
    mechanics.Wrench
        ``F_leg`` (N) and ``K`` (N m, about C), base frame: the right-hand sides above.
    """
    total = Wrench(sp.zeros(3, 1), sp.zeros(3, 1), C)
    for w in wrenches:
        total = total + w
    return total


def torsion_moment(K, u, n_dot_u):
    """The universal joint's constraint moment along n: ``M_C = (K . u) / (n . u)``.

    Parameters
    ----------
    K : sympy.Matrix, shape (3, 1)
        Moment about C the leg needs, base frame, N m.
    u : sympy.Matrix, shape (3, 1)
        Unit leg direction, base frame, 1.
    n_dot_u : sympy.Expr
        ``n . u`` (``UniversalJoint.n_dot_u`` = ``sqrt(1 - (u . a1)^2)``), 1.

    Returns
    -------
    sympy.Expr
        N m.
    """
    return dot(K, u) / n_dot_u


def transverse_end_force(K, M_C, u, n, D):
    """The part of R_E perpendicular to the leg: ``u x (K - M_C n) / D``.

    Parameters
    ----------
    K : sympy.Matrix, shape (3, 1)
        Moment about C the leg needs, base frame, N m.
    M_C : sympy.Expr
        Torsion moment of the universal joint, N m.
    u, n : sympy.Matrix, shape (3, 1)
        Unit leg direction and torsion direction, base frame, 1.
    D : sympy.Expr
        Leg length, m.

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        N, base frame.
    """
    return cross(u, K - M_C * n) / D


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
