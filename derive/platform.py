"""Platform equilibrium, equations (2)-(7), from Newton-Euler.

The moving platform and its payload are two rigid bodies fixed to each other. Each body b of mass
``m_b``, centre of mass ``c_b`` (base frame), inertia ``I_b`` about ``c_b`` (platform frame) needs a
resultant external force ``m_b (a_b - g)`` and a resultant moment about its centre of mass
``J_b alpha + omega x (J_b omega)`` with ``J_b = T I_b T^T``. The legs supply the forces ``R_Ei``
at the joints ``E_i``; gravity ``g = (0, 0, -g)`` acts on every body. Moments are taken about the
platform frame's origin ``p``:

    sum_i R_Ei                 = sum_b m_b (a_b - g)                                   (2)-(4)
    sum_i (E_i - p) x R_Ei     = sum_b [(c_b - p) x m_b (a_b - g) + J_b alpha + omega x J_b omega]
                                                                                        (5)-(7)
"""

import sympy as sp

from .vectors import cross


def inertial_moment(R, I, alpha, omega):
    """``J alpha + omega x J omega`` with ``J = R I R^T``, computed in the body frame.

    ``R`` turns body axes into base axes, ``I`` is the inertia about the centre of mass in
    body axes; ``alpha`` and ``omega`` are in base axes. Working in body axes,
    ``R (I a_b + w_b x I w_b)`` with ``a_b = R^T alpha`` and ``w_b = R^T omega``, avoids forming J.
    """
    a_b = R.T * alpha
    w_b = R.T * omega
    return R * (I * a_b + cross(w_b, I * w_b))


def body_required_wrench(m, m_weight, r_c, a_c, g_vec, moment_c):
    """Force and moment (about the point from which ``r_c`` is measured) a body needs.

    Parameters: ``m`` inertial mass, ``m_weight`` gravitational mass (the same for a real body),
    ``r_c`` centre of mass relative to the reference point, ``a_c`` its acceleration,
    ``moment_c`` the moment about the centre of mass that the body's rotation needs
    (``inertial_moment``).
    """
    force = m * a_c - m_weight * g_vec
    return force, cross(r_c, force) + moment_c


def platform_residual(R_E, E, p, F_req, M_req, M_joint=None):
    """Residual of (2)-(7) for forces R_E[i] at points E[i]; zero at equilibrium.

    ``M_joint`` are moments the joints put on the platform besides the forces (friction).
    """
    force = sp.zeros(3, 1)
    moment = sp.zeros(3, 1)
    for i in range(len(R_E)):
        force += R_E[i]
        moment += cross(E[i] - p, R_E[i])
        if M_joint is not None:
            moment += M_joint[i]
    return sp.Matrix.vstack(force - F_req, moment - M_req)
