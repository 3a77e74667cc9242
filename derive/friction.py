"""Friction in every joint, equations (33)-(35), as vectors and as the paper's signed scalars.

Spherical joint E_i: the friction moment on the platform opposes the platform's angular velocity
relative to the leg, ``w = omega - omega_L``:

    M_frE = -(c_s w + mu r |R_E| sgn(w))                                          (33)

Universal joint C_i: the friction moment on the leg opposes the leg's angular velocity relative to
the base, ``omega_L``, with |R_C| in place of |R_E|                                 (34)

Prismatic joint: the friction force on the upper part, along u, opposes the sliding speed
``v = D'``:

    F_fr = -(c v + mu_p |R_3| sgn(v))                                              (35)

``sgn`` is the vector sign ``w / |w|`` (the printed (33)-(35) write ``w / w``). It is regularised as
``w / sqrt(|w|^2 + eps^2)``: exact to a relative 1e-6 above 1000 eps, zero at zero speed, never
NaN. The paper's tables give scalars, negative = opposing: ``-(c_s |w| + mu r |R| |sgn(w)|)``.
"""

import sympy as sp

from .vectors import dot, norm


def smooth_sign(w, eps):
    """Regularised sign of a scalar, or unit vector of a vector: ``w / sqrt(w.w + eps^2)``.

    Parameters
    ----------
    w : sympy.Expr or sympy.Matrix, shape (3, 1)
        A speed (m/s) or an angular velocity (rad/s, base frame).
    eps : sympy.Expr
        Regularisation speed, same unit as w.

    Returns
    -------
    sympy.Expr or sympy.Matrix, shape (3, 1)
        Dimensionless, magnitude below 1.
    """
    if isinstance(w, sp.MatrixBase):
        return w / sp.sqrt(dot(w, w) + eps**2)
    return w / sp.sqrt(w**2 + eps**2)


def joint_friction_scalar(w, R, c_s, mu, r, eps):
    """The paper's signed scalar of (33)/(34): ``-(c_s |w| + mu r |R| |w| / sqrt(|w|^2 + eps^2))``.

    Parameters
    ----------
    w : sympy.Matrix, shape (3, 1)
        Relative angular velocity in the joint, base frame, rad/s.
    R : sympy.Matrix, shape (3, 1)
        Reaction force carried by the joint, base frame, N.
    c_s : sympy.Expr
        Viscous coefficient, N m s/rad.
    mu : sympy.Expr
        Coulomb coefficient, 1.
    r : sympy.Expr
        Joint radius, m.
    eps : sympy.Expr
        Regularisation speed, rad/s.

    Returns
    -------
    sympy.Expr
        N m (negative = opposing).
    """
    speed2 = dot(w, w)
    return -(c_s * sp.sqrt(speed2) + mu * r * norm(R) * sp.sqrt(speed2 / (speed2 + eps**2)))


def prismatic_friction(v, R_3, c, mu, sign):
    """Eq. (35): friction force on the upper part along u, opposing the sliding speed v.

    ``-(c v + mu |R_3| sgn(v))``.

    Parameters
    ----------
    v : sympy.Expr
        Sliding speed ``D'``, m/s.
    R_3 : sympy.Matrix, shape (3, 1)
        Transverse force of the prismatic joint, base frame, N.
    c : sympy.Expr
        Viscous coefficient, N s/m.
    mu : sympy.Expr
        Coulomb coefficient, 1.
    sign : sympy.Expr
        ``smooth_sign(v, eps)``, 1 (passed in so that the catalog's effects share it).

    Returns
    -------
    sympy.Expr
        N, along u.
    """
    return -(c * v + mu * norm(R_3) * sign)


def prismatic_friction_scalar(v, R_3, c, mu, eps):
    """The paper's signed scalar of (35): ``-(c |v| + mu |R_3| |sgn(v)|)``.

    Parameters are those of ``prismatic_friction`` with ``eps`` (m/s) the regularisation speed.
    Returns a sympy.Expr, N (negative = opposing).
    """
    return -(c * sp.sqrt(v**2) + mu * norm(R_3) * sp.sqrt(v**2 / (v**2 + eps**2)))
