"""The leg frames and the transformation of reactions into them, equations (18)-(27).

The paper's frame of leg i has ``Z`` along the leg from E_i to C_i (18), ``X = Z x V`` with
``V = E_{i+1} - E_i`` (19)-(20), and ``Y = Z x X`` (23); the unit vectors are (21), (22), (24).
A vector R (base frame) has the components ``R . U_X``, ``R . U_Y``, ``R . U_Z`` in that frame:
each component is the sum over the three base-frame components, ``R_x U_x + R_y U_y + R_z U_z``
(the printed (25)-(27) multiply every component with the same entry).
"""

import sympy as sp

from .vectors import cross, norm


def leg_frame(E_i, C_i, E_next):
    """The unit vectors (U_X, U_Y, U_Z) of the paper's frame of leg i, as the rows of a matrix.

    Parameters
    ----------
    E_i, C_i, E_next : sympy.Matrix, shape (3, 1)
        Platform joint and base joint of leg i and the platform joint of leg i + 1, base frame,
        m.

    Returns
    -------
    sympy.Matrix, shape (3, 3)
        Rows U_X, U_Y, U_Z (base frame components), 1.
    """
    Z = C_i - E_i
    V = E_next - E_i
    X = cross(Z, V)
    Y = cross(Z, X)
    return sp.Matrix.vstack((X / norm(X)).T, (Y / norm(Y)).T, (Z / norm(Z)).T)


def to_leg_frame(L, R):
    """Eqs. (25)-(27): components of the base-frame vector R in the leg frame with rows L.

    Parameters
    ----------
    L : sympy.Matrix, shape (3, 3)
        ``leg_frame(...)``.
    R : sympy.Matrix, shape (3, 1)
        A vector in the base frame (any unit).

    Returns
    -------
    sympy.Matrix, shape (3, 1)
        Its components along U_X, U_Y, U_Z, same unit.
    """
    return L * R
