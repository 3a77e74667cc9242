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


def upper_part_loads(R_E, force2, rotation2, u, s_E, s_2, s_3):
    """Axial force F_ax, transverse force R_3 and moment M_3 of the prismatic joint.

    The points involved lie on the leg's axis, at distances from C: E at ``s_E`` (= D), the upper
    part's centre at ``s_2`` and the joint point P_3 at ``s_3``; so the moment arms about P_3
    are multiples of u and ``M_3 = u x ((s_E - s_3) R_E + (s_2 - s_3) F_2) + M_rot2``.

    Parameters
    ----------
    R_E : sympy.Matrix, shape (3, 1)
        Force of the leg on the platform at E, base frame, N.
    force2 : sympy.Matrix, shape (3, 1)
        The upper part's required force ``m_2 (a_2 - g)``, base frame, N.
    rotation2 : sympy.Matrix, shape (3, 1)
        Its rotation moment ``J_2 alpha_L + omega_L x J_2 omega_L``, base frame, N m.
    u : sympy.Matrix, shape (3, 1)
        Unit leg direction, base frame, 1.
    s_E, s_2, s_3 : sympy.Expr
        Distances from C of E, the upper centre and P_3, m.

    Returns
    -------
    F_ax : sympy.Expr
        Axial force, N (positive pushes the platform away: the frictionless actuator force).
    R_3 : sympy.Matrix, shape (3, 1)
        Transverse force on the upper part, base frame, N.
    M_3 : sympy.Matrix, shape (3, 1)
        Moment on the upper part about P3, base frame, N m.
    """
    total = R_E + force2
    F_ax = dot(u, total)
    M_3 = cross(u, (s_E - s_3) * R_E + (s_2 - s_3) * force2) + rotation2
    return F_ax, total - F_ax * u, M_3
