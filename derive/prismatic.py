"""The prismatic joint, equations (28)-(32), and the actuator force.

The upper part of leg i (zone 2) carries ``-R_Ei`` from the platform, gravity, and from the lower
part: the joint's transverse force ``R_3i`` (perpendicular to the leg), its constraint moment
``M_3i`` (three components, taken about the joint point P_3 at ``C + k_3 D u``; the paper places
it at 0.5 D) and the axial force along u. Newton-Euler for the upper part gives

    R_3 + F_ax u = R_E + m_2 (a_2 - g)                                          (28), (29)
    M_3          = (E - P_3) x R_E + (c_2 - P_3) x m_2 (a_2 - g)
                   + J_2 alpha_L + omega_L x J_2 omega_L                         (30)-(32)

The axial part ``F_ax = u . (R_E + m_2 (a_2 - g))`` is the actuator force of a frictionless joint
(positive pushing the platform away from the base); the paper does not report it. Moments about
E_i (as the paper takes them) give the same M_3: the two differ by ``(E - P_3) x`` the balanced
force.
"""

from .vectors import cross, dot


def upper_part_loads(R_E, u, E, P3, m2, m2_weight, a2, c2, moment2, g_vec, M_joint_E=None):
    """Axial force F_ax, transverse force R_3 and moment M_3 of the prismatic joint.

    ``moment2`` is the moment about its centre that the part's rotation needs
    (``J_2 alpha_L + omega_L x J_2 omega_L``). ``M_joint_E`` is a moment that the platform's
    joint puts on the upper part besides R_E (the spherical joint's friction moment, with the sign
    it has on the leg).
    """
    total = R_E + m2 * a2 - m2_weight * g_vec
    F_ax = dot(u, total)
    R_3 = total - F_ax * u
    M_3 = cross(E - P3, R_E) + cross(c2 - P3, m2 * a2 - m2_weight * g_vec) + moment2
    if M_joint_E is not None:
        M_3 = M_3 - M_joint_E
    return F_ax, R_3, M_3
