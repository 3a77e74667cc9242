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

from .mechanics import Wrench
from .vectors import dot


def upper_part_loads(on_platform: Wrench, required: Wrench, u, P3):
    """Axial force F_ax, transverse force R_3 and moment M_3 of the prismatic joint.

    The upper part carries the reaction of ``on_platform`` and the lower part's joint wrench at
    P3; Newton-Euler gives that joint wrench as ``required - reaction(on_platform)`` about P3.

    Parameters
    ----------
    on_platform : mechanics.Wrench
        What the leg puts on the platform at E (force ``R_E``, and any joint moment), base frame.
    required : mechanics.Wrench
        The upper part's required wrench (``Body.required_wrench``).
    u : sympy.Matrix, shape (3, 1)
        Unit leg direction, base frame, 1.
    P3 : sympy.Matrix, shape (3, 1)
        The prismatic joint point, base frame, m.

    Returns
    -------
    F_ax : sympy.Expr
        Axial force, N (positive pushes the platform away: the frictionless actuator force).
    R_3 : sympy.Matrix, shape (3, 1)
        Transverse force on the upper part, base frame, N.
    M_3 : sympy.Matrix, shape (3, 1)
        Moment on the upper part about P3, base frame, N m.
    """
    joint = (required - on_platform.reaction()).about(P3)
    F_ax = dot(u, joint.force)
    return F_ax, joint.force - F_ax * u, joint.moment
