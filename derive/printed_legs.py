"""The paper's leg equations (11)-(35) as printed, term by term, with each erratum's fix.

The conventions are those of derive/printed.py (which holds the errata, ``EQUATION_ERRATA``, and
the platform's equations (1)-(7)): every equation is a function returning its terms, a dict
``{name: value}`` adding up to the left-hand side of the printed ``... = 0`` (``residual``), or a
list of them; ``fix`` names the errata to correct; every value may be a SymPy expression or a
NumPy array (the state axis last); the reactions are read as derive/printed.py's "Reading"
states: each the load that the body nearer the platform puts on the body nearer the base.
"""

from __future__ import annotations

from dataclasses import dataclass

from .printed import absolute, check_fix, cross, inertial_moment, need, norm

# ----------------------------------------------------------------------------- (11)-(17)


def eq11_13_terms(R_C, R_E, F2, F4, fix=(), *, W2=None, W4=None) -> list[dict]:
    """(11), (12), (13): the force equations of leg i, as printed.

    ``R_XCi - R_XEi + F_X2i + F_X4i = 0`` and likewise for y and z.

    Parameters
    ----------
    R_C, R_E : 3-vectors
        ``R^O_Ci`` (force of the leg on the base) and ``R^O_Ei`` (force of the platform on the
        leg).
    F2, F4 : 3-vectors
        Inertial forces ``m a`` of zones 2 and 4 (17).
    fix : subset of ``("E13",)``
        E13 adds the weights (needs ``W2``, ``W4``: the weight vectors ``m g_vec``, base frame).
    """
    fix = check_fix(fix, "11-13")
    out = []
    for j, axis in enumerate("XYZ"):
        terms = {"R_C": R_C[j], "R_E": -R_E[j], "F_2": F2[j], "F_4": F4[j]}
        if "E13" in fix:
            terms["W_2"] = -need(W2, "W2", "E13")[j]
            terms["W_4"] = -need(W4, "W4", "E13")[j]
        out.append(terms)
    return out


def _levers(fix, D, cos, r2, r4):
    """Lever arms of zones 2 and 4 from C_i: printed ``0.75 D cos``, ``0.25 D cos``, or E19's."""
    if "E19" in fix:
        return need(r2, "r2", "E19"), need(r4, "r4", "E19")
    return [0.75 * D * c for c in cos], [0.25 * D * c for c in cos]


def eq14_16_terms(R_E, E, C, D, F2, F4, M2, M4, M_C, fix14=(), fix15=(), fix16=(), *,
                  W2=None, W4=None, r2=None, r4=None) -> list[dict]:
    """(14), (15), (16): the moment equations of leg i about C_i, as printed.

    (14) ``R_ZEi (Y_Ei - Y_Ci) - F_Z2i (0.75 D_i cos th_Y) - F_Z4i (0.25 D_i cos th_Y)
    - R_YEi (Z_Ei - Z_Ci) + F_Y2i (0.75 D_i cos th_Z) + F_Y4i (0.25 D_i cos th_Z)
    M_X2i + M_X4i = 0``

    (15) ``R_XEi (Z_Ei - Z_Ci) - F_X2i (0.75 D_i cos th_Z) - F_X4i (0.25 D_i cos th_Z)
    + R_ZEi (X_Ei - X_Ci) - F_Z2i (0.75 D_i cos th_X) - F_Z4i (0.25 D_i cos th_X)
    M_Y2i + M_Y4i = 0``

    (16) ``- R_YEi (X_Ei - X_Ci) + F_Y2i (0.75 cos th_X) + F_Y4i (0.25 D_i cos th_X)
    R_XEi (Y_Ei - Y_Ci) + F_X2i (0.75 cos th_Y) + F_X4i (0.25 cos th_Y) + M_ZCi
    M_Z2i + M_Z4i``

    The operators missing before the last lines are read as ``+`` and (16) as ``... = 0``. The
    direction cosines are (8)-(10): ``cos th = (E - C) / D``.

    Parameters
    ----------
    R_E, E, C : 3-vectors
        ``R^O_Ei``, the joints E_i and C_i.
    D : scalar
        Leg length.
    F2, F4, M2, M4 : 3-vectors
        Inertial forces and moments of zones 2 and 4 (17).
    M_C : 3-vector
        ``M^O_Ci``, the moment of the leg on the base; (16) prints its z component ``M_ZCi``.
    fix14, fix15, fix16 : subsets of ``EQUATION_ERRATA["14"]``, ``["15"]``, ``["16"]``
        E13 (needs ``W2``, ``W4``), E14, E15, E16, E17, E18, E19 (needs ``r2``, ``r4``: the
        centres of zones 2 and 4 relative to C_i).
    """
    fixes = [check_fix(fix14, "14"), check_fix(fix15, "15"), check_fix(fix16, "16")]
    d = [E[k] - C[k] for k in range(3)]
    leg = _LegMoments(R_E, d, [dk / D for dk in d], D, F2, F4, M2, M4, M_C, W2, W4, r2, r4)
    return [_eq14_15_terms(leg, 0, fixes[0]), _eq14_15_terms(leg, 1, fixes[1]),
            _eq16_terms(leg, fixes[2])]


@dataclass(frozen=True)
class _LegMoments:
    """The quantities (14)-(16) combine: the arguments of ``eq14_16_terms`` of the same names,
    with ``d = E - C`` (3-vector) and the direction cosines ``cos = d / D`` (3-vector)."""

    R_E: object
    d: list
    cos: list
    D: object
    F2: object
    F4: object
    M2: object
    M4: object
    M_C: object
    W2: object
    W4: object
    r2: object
    r4: object


def _eq14_15_terms(leg: _LegMoments, eq: int, fix: frozenset) -> dict:
    """(14) (``eq`` 0) or (15) (``eq`` 1): moments on the leg about the x or y axis through C_i."""
    j, k, l = ((0, 1, 2), (1, 2, 0))[eq]
    R_E, d, F2, F4 = leg.R_E, leg.d, leg.F2, leg.F4
    l2, l4 = _levers(fix, leg.D, leg.cos, leg.r2, leg.r4)
    # component j of (d x R) = d_k R_l - d_l R_k
    name = "XYZ"
    terms = {
        f"R_{name[l]}E": R_E[l] * d[k],
        f"F_{name[l]}2": -F2[l] * l2[k],
        f"F_{name[l]}4": -F4[l] * l4[k],
        f"R_{name[k]}E": -R_E[k] * d[l],
        f"F_{name[k]}2": F2[k] * l2[l],
        f"F_{name[k]}4": F4[k] * l4[l],
    }
    if eq == 1 and "E15" not in fix:
        # (15) as printed: R_XE(Z) - F_X2 - F_X4 + R_ZE(X) - F_Z2 - F_Z4
        terms = {
            "R_XE": R_E[0] * d[2], "F_X2": -F2[0] * l2[2], "F_X4": -F4[0] * l4[2],
            "R_ZE": R_E[2] * d[0], "F_Z2": -F2[2] * l2[0], "F_Z4": -F4[2] * l4[0],
        }
    s = -1 if "E14" in fix else 1
    terms["M_2"] = s * leg.M2[j]
    terms["M_4"] = s * leg.M4[j]
    if "E18" in fix:
        terms["M_C"] = -leg.M_C[j]
    if "E13" in fix:
        W2v, W4v = need(leg.W2, "W2", "E13"), need(leg.W4, "W4", "E13")
        terms["W_2"] = cross(l2, W2v)[j]
        terms["W_4"] = cross(l4, W4v)[j]
    return terms


def _eq16_terms(leg: _LegMoments, fix: frozenset) -> dict:
    """(16): the negative of the moments on the leg about the z axis through C_i."""
    D = leg.D
    l2, l4 = _levers(fix, D, leg.cos, leg.r2, leg.r4)
    if "E17" not in fix:
        l2 = [l2[0] / D, l2[1] / D, l2[2]]
        l4 = [l4[0], l4[1] / D, l4[2]]
    sx = -1 if "E16" in fix else 1
    return {
        "R_YE": -leg.R_E[1] * leg.d[0],
        "F_Y2": leg.F2[1] * l2[0],
        "F_Y4": leg.F4[1] * l4[0],
        "R_XE": leg.R_E[0] * leg.d[1],
        "F_X2": sx * leg.F2[0] * l2[1],
        "F_X4": sx * leg.F4[0] * l4[1],
        "M_C": leg.M_C[2],
        "M_2": leg.M2[2],
        "M_4": leg.M4[2],
    }


def eq17(m, a, I, alpha, fix=(), *, J=None, omega=None) -> tuple[list, list]:
    """(17): the inertial force and moment of a leg zone, as printed: ``m a`` and ``I_X alpha_X``...

    Parameters
    ----------
    m : scalar
    a, alpha : 3-vectors
        Acceleration of the zone's centre, angular acceleration (base frame).
    I : 3-vector
        The printed ``I_X, I_Y, I_Z``.
    fix : subset of ``("E20",)``
        E20: ``J alpha + omega x J omega`` (needs ``J``, the inertia about the centre in the
        base frame, and ``omega``).

    Returns
    -------
    (F, M) : two 3-lists
    """
    fix = check_fix(fix, "17")
    F = [m * a[j] for j in range(3)]
    if "E20" in fix:
        return F, inertial_moment(need(J, "J", "E20"), alpha, need(omega, "omega", "E20"))
    return F, [I[j] * alpha[j] for j in range(3)]


# ----------------------------------------------------------------------------- (18)-(27)


def leg_frame(E, C, E_next, fix=()) -> list[list]:
    """(18)-(24): the unit vectors U_X, U_Y, U_Z of leg i's frame, as printed.

    ``Z = C_i - E_i`` (18), ``X = Z x V_{Ei+1 Ei}`` (20), ``Y = Z x X`` (23). Read with the
    naming of (19) (``V_{E1E2} = E_2 - E_1``), ``V_{Ei+1 Ei} = E_i - E_{i+1}``.

    Parameters
    ----------
    E, C, E_next : 3-vectors
        E_i, C_i and E_{i+1} (E_1 for leg 6).
    fix : subset of ``("E21",)``
        E21: ``V = E_{i+1} - E_i`` as (19) defines it.

    Returns
    -------
    [U_X, U_Y, U_Z], three 3-lists
    """
    fix = check_fix(fix, "20")
    Z = [C[k] - E[k] for k in range(3)]
    V = [E_next[k] - E[k] for k in range(3)] if "E21" in fix else \
        [E[k] - E_next[k] for k in range(3)]
    X = cross(Z, V)
    Y = cross(Z, X)
    return [[v / norm(U) for v in U] for U in (X, Y, Z)]


def eq25_27(R, U, fix=()) -> list:
    """(25)-(27): the components of a base-frame vector R in leg i's frame, as printed.

    ``R^theta_Z = R^O_Z . U_Z + R^O_Y . U_Z + R^O_X . U_Z`` and likewise for Y and X: the three
    base components of R, each times the same unit vector. The resulting vector is
    ``(R_X + R_Y + R_Z) U_k``, so its component along U_k is ``R_X + R_Y + R_Z``, the same for
    all three axes.

    Parameters
    ----------
    R : 3-vector
        Base-frame vector.
    U : [U_X, U_Y, U_Z]
        The leg frame (``leg_frame``).
    fix : subset of ``("E22",)``
        E22: the dot products ``R . U_k``.

    Returns
    -------
    [R^theta_X, R^theta_Y, R^theta_Z]
    """
    fix = check_fix(fix, "25-27")
    if "E22" in fix:
        return [R[0] * Uk[0] + R[1] * Uk[1] + R[2] * Uk[2] for Uk in U]
    total = R[0] + R[1] + R[2]
    return [total for _ in U]


# ----------------------------------------------------------------------------- (28)-(32)


def eq28_32_terms(R3, RE, F2, M2, M3, D, fix=(), *, W2=None, s2=None, s3=None) -> list[dict]:
    """(28)-(32): the upper part of leg i (zone 2 with E_i), in the leg frame, as printed.

    ``R_X3i + F_X2i - R_XEi = 0`` (28), ``R_Y3i + F_Y2i - R_YEi = 0`` (29),
    ``-R_Y3i (0.5 D_i) - R_Y2i (0.25 D_i) + M_X2i + M_X3i = 0`` (30),
    ``R_X3i (0.5 D_i) + R_X2i (0.25 D_i) + M_Y2i + M_Y3i = 0`` (31),
    ``M_Z2i + M_Z3i = 0`` (32), all components in the leg frame (z from E_i to C_i), moments
    about E_i; ``R_Y2i``, ``R_X2i`` are the inertial force of zone 2 (E23).

    Parameters
    ----------
    R3, RE, F2, M2, M3 : 3-vectors, leg frame
        ``R^theta_3i`` (with the axial force as z component), ``R^theta_Ei``, the inertial
        force and moment of zone 2, ``M^theta_3i``.
    D : scalar
        Leg length.
    fix : subset of ``EQUATION_ERRATA["28-32"]``
        E13 (needs ``W2``, zone 2's weight in the leg frame), E19 (needs ``s2``, ``s3``: the
        distances of zone 2's centre and of the joint point P_3i from E_i), E24 (adds the
        axial equation as a sixth).

    Returns
    -------
    list of term dicts: (28), (29), (30), (31), (32) [, axial]
    """
    fix = check_fix(fix, "28-32")
    if "E19" in fix:
        l2, l3 = need(s2, "s2", "E19"), need(s3, "s3", "E19")
    else:
        l2, l3 = 0.25 * D, 0.5 * D
    W = need(W2, "W2", "E13") if "E13" in fix else None
    out = []
    axes = [0, 1] + ([2] if "E24" in fix else [])
    forces = []
    for j in axes:
        a = "XYZ"[j]
        terms = {f"R_{a}3": R3[j], f"F_{a}2": F2[j], f"R_{a}E": -RE[j]}
        if W is not None:
            terms["W_2"] = -W[j]
        forces.append(terms)
    out += forces[:2]
    t30 = {"R_Y3": -R3[1] * l3, "F_Y2": -F2[1] * l2, "M_X2": M2[0], "M_X3": M3[0]}
    t31 = {"R_X3": R3[0] * l3, "F_X2": F2[0] * l2, "M_Y2": M2[1], "M_Y3": M3[1]}
    if W is not None:
        t30["W_2"] = W[1] * l2
        t31["W_2"] = -W[0] * l2
    out += [t30, t31, {"M_Z2": M2[2], "M_Z3": M3[2]}]
    if "E24" in fix:
        out.append(forces[2])
    return out


# ----------------------------------------------------------------------------- (33)-(35)


def eq33_34(c_s, omega, mu, r, R, fix=()) -> list:
    """(33) and (34): the friction moment of a spherical or universal joint, as printed.

    ``M_fr = -[c_s omega + mu r sqrt(R^T R) omega / omega]``, componentwise for a vector omega
    (so ``omega / omega`` is 1 in every component; a SymPy symbol cancels to 1 likewise).

    Parameters
    ----------
    c_s, mu, r : scalars
    omega : 3-vector
        Relative angular velocity of the joint.
    R : 3-vector
        The joint's reaction force.
    fix : subset of ``("E25",)``
        E25: the sign function ``omega / |omega|``.

    Returns
    -------
    3-list
    """
    fix = check_fix(fix, "33-34")
    size = norm(R)
    if "E25" in fix:
        w = norm(omega)
        return [-(c_s * omega[j] + mu * r * size * omega[j] / w) for j in range(3)]
    return [-(c_s * omega[j] + mu * r * size * (omega[j] / omega[j])) for j in range(3)]


def eq35(c_s, v, mu, R_3):
    """(35): the friction force of a prismatic joint, as printed: ``-[c_s v + mu |R_3| v/|v|]``.

    ``c_s`` is the printed symbol, the joints' viscous coefficient (E27); the derivation uses the
    prismatic joint's own coefficient in its place.
    """
    return -(c_s * v + mu * norm(R_3) * v / absolute(v))
