"""Prismatic friction from two bushings fixed in the cylinder (the coupled friction model).

The upper part (rod) of leg i slides in the lower part (cylinder) through two bushings, fixed in
the cylinder at the distances ``s_a = bushing_offset`` and ``s_b = bushing_offset +
bushing_spacing`` from C_i along u: their distance from C_i does not change with the stroke. The
prismatic joint's transverse force ``R_3`` and moment ``M_3`` (about the joint point P_3 at
``k_3 D`` from C_i, (28)-(32)) are the resultant of the two bushings' normal forces ``N_a``,
``N_b`` (perpendicular to u) on the rod. With ``s = s_a - k_3 D`` the position of bushing a
relative to P_3 and ``b`` the spacing, moments about P_3 give

    N_a + N_b = R_3,        s u x N_a + (s + b) u x N_b = M_3,perp = M_3 - (M_3.u) u

so ``u x N_b = (M_3,perp - s u x R_3) / b`` and, as N_b is perpendicular to u,

    N_b = (M_3,perp - s u x R_3) x u / b,        N_a = R_3 - N_b.

This is the beam on two supports: a transverse load P at a distance x from C_i, beyond the
bushings, gives ``N_b = P (x - s_a) / b`` and ``N_a = -P (x - s_b) / b``. The moment's axial part
(torsion about u) is carried by the joint's anti-rotation key and causes no sliding friction.

The friction force on the rod along u, opposing the sliding speed v:

    F_fr = -(c v + (mu_p (|N_a| + |N_b|) + F_seal) sgn(v))

(viscous, Coulomb at both bushings, load-independent seal friction).
"""

from .vectors import cross, dot, norm


def bushing_forces(R_3, M_3, u, s, b):
    """Normal forces (N_a, N_b) of the two bushings on the rod, base frame, N.

    ``s``: position of bushing a along u relative to P_3 (m, may be negative); ``b``: spacing
    of the bushings (m, > 0).
    """
    M_perp = M_3 - dot(M_3, u) * u
    N_b = cross(M_perp - s * cross(u, R_3), u) / b
    return R_3 - N_b, N_b


def bushing_friction_parts(v, N_a, N_b, c, mu, seal, sgn):
    """The friction force on the rod along u in its parts: (viscous, bushing Coulomb, seal), N.

    ``sgn``: the regularised sign of v (``friction.smooth_sign(v, eps)``).
    """
    return -c * v, -mu * (norm(N_a) + norm(N_b)) * sgn, -seal * sgn
