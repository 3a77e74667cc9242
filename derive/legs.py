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

from .vectors import cross, dot


def leg_required(parts, C, g_vec):
    """Force and moment about C that the two parts of a leg need (right-hand sides above).

    ``parts`` is a list of dicts with keys m, m_weight, c (centre), a_c and moment (the
    moment about the centre that the part's rotation needs, ``platform.inertial_moment``).
    """
    force = sp.zeros(3, 1)
    moment = sp.zeros(3, 1)
    for k in parts:
        f = k["m"] * k["a_c"] - k["m_weight"] * g_vec
        force += f
        moment += cross(k["c"] - C, f) + k["moment"]
    return force, moment


def torsion_moment(K, u, n):
    """The universal joint's constraint moment along n: ``M_C = (K.u) / (n.u)``."""
    return dot(K, u) / dot(n, u)


def transverse_end_force(K, M_C, u, n, D):
    """The part of R_E perpendicular to the leg: ``u x (K - M_C n) / D``."""
    return cross(u, K - M_C * n) / D


def leg_residual(R_E, R_C, M_C, u, n, D, F_leg, K):
    """Residual of (11)-(16) for one leg; zero at equilibrium."""
    return sp.Matrix.vstack(R_C - R_E - F_leg, -D * cross(u, R_E) + M_C * n - K)
