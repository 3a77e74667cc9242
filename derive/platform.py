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

from .mechanics import Inertia, Wrench


def inertial_moment(R, I, alpha, omega):
    """``J alpha + omega x J omega`` with ``J = R I R^T``, computed in the body frame.

    ``R`` turns body axes into base axes, ``I`` is the inertia about the centre of mass in
    body axes; ``alpha`` and ``omega`` are in base axes. Working in body axes,
    ``R (I a_b + w_b x I w_b)`` with ``a_b = R^T alpha`` and ``w_b = R^T omega``, avoids forming J.
    (``mechanics.Inertia.rotation_moment`` is the same with the chain's ``let``.)

    Parameters
    ----------
    R : sympy.Matrix, shape (3, 3)
        Rotation body -> base, 1.
    I : sympy.Matrix, shape (3, 3)
        Inertia about the centre of mass, body axes, kg m^2.
    alpha, omega : sympy.Matrix, shape (3, 1)
        Angular acceleration (rad/s^2) and velocity (rad/s), base frame.

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        N m, base frame.
    """
    return Inertia(I, R, sp.zeros(3, 1)).rotation_moment(alpha, omega)


def platform_residual(R_E, E, p, F_req, M_req, M_joint=None):
    """Residual of (2)-(7) for forces R_E[i] at points E[i]; zero at equilibrium.

    Parameters
    ----------
    R_E, E : sequence of sympy.Matrix, shape (3, 1)
        Force of each leg on the platform (N) and its point (m), base frame.
    p : sympy.Matrix, shape (3, 1)
        Platform frame origin (the moments' reference point), base frame, m.
    F_req, M_req : sympy.Matrix, shape (3, 1)
        Required force (N) and moment about p (N m) of platform and payload.
    M_joint : sequence of sympy.Matrix, shape (3, 1), optional
        Moments the joints put on the platform besides the forces (friction), N m.

    Returns
    -------
    sympy.Matrix, shape (6, 1)
        Force (N) and moment (N m) residuals.
    """
    on_platform = Wrench(sp.zeros(3, 1), sp.zeros(3, 1), p)
    for i in range(len(R_E)):
        moment = M_joint[i] if M_joint is not None else sp.zeros(3, 1)
        on_platform = on_platform + Wrench(R_E[i], moment, E[i])
    return sp.Matrix.vstack(on_platform.force - F_req, on_platform.moment - M_req)
