"""How close the platform is to a singular pose, from the factor the force solve already has.

The legs' axial forces ``f`` solve ``A f = b`` with ``A``'s column i the unit wrench of leg i on
the platform: its direction ``u_i`` (rows 0-2) and its moment about the platform origin
``(E_i - p) x u_i`` (rows 3-5, a length). ``A`` is singular where the six legs' lines of action
cannot resist some wrench (a linear line complex, Merlet's singularities): the forces grow
without bound there.

Measure (``h``, dimensionless, in [0, 1]): the Hadamard ratio of ``S A``, where
``S = diag(1, 1, 1, 1/L, 1/L, 1/L)`` expresses the moments in units of the platform's size
``L`` (the root mean square distance of the platform joints from the platform origin):

    h = |det(S A)| / prod_i |S a_i|

the volume spanned by the six scaled unit wrenches relative to the volume they would span if
they were mutually orthogonal. ``h = 1`` for orthogonal wrenches, ``h = 0`` at a singular pose.
Scaling a platform (every length times c) leaves ``h`` unchanged. The solve's factor is
``A = V U`` (modified Gram-Schmidt, ``U`` unit upper-triangular, ``V``'s columns orthogonal,
the factor keeps ``1 / (v_j . v_j)``), so ``|det A| = prod |v_j|``, and
``det(S A) = det(A) / L^3``: ``h`` costs six column norms and one square root per step, no
further factorisation.

Bound: the columns of ``S A`` scaled to unit length have a 2-norm condition number below
``2 / h`` (Guggenheimer, Edelman and Johnson, 1995), so a limit ``h >= 2 / kappa_max``
guarantees that every unflagged step's scaled, column-normalised force Jacobian has a condition
number below ``kappa_max``.
"""

from __future__ import annotations

import sympy as sp


def singularity_measure(ch, A: sp.Matrix, factor, platform_joints: sp.Matrix):
    """Define ``h`` (see the module) in chain ``ch`` and return its symbol.

    Parameters
    ----------
    ch : Chain
    A : Matrix (6, 6)
        Columns ``(u_i, (E_i - p) x u_i)``, as factored.
    factor : Factor
        ``ch.factor`` of ``A`` (its ``inv`` are ``1 / (v_j . v_j)``).
    platform_joints : Matrix (6, 3)
        The joints ``e_i`` in the platform frame, m.
    """
    L2 = ch.let("L2_A", sum((platform_joints[i, :] * platform_joints[i, :].T)[0, 0]
                            for i in range(6)) / 6, "L_{A}^{2}", "conditioning")
    product = sp.S.One
    for j in range(6):
        col = A[:, j]
        norm2 = sum(col[r] ** 2 for r in range(3)) + sum(col[r] ** 2 for r in range(3, 6)) / L2
        product *= factor.inv[j] * norm2
    return ch.let("h_A", 1 / sp.sqrt(L2 ** 3 * product), "h_{A}", "conditioning")
