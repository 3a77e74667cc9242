"""The paper's errata, and its platform equations (1)-(7) as printed with each erratum's fix.

The project derives its mechanics from vectors (the other modules of derive/); this module and
derive/printed_legs.py keep the paper's printed equations, so that every difference between a
printed equation and the derived one is written down, named (``E01``, ``E02``, ... in ``ERRATA``
and docs/reference/errata.md) and tested (tests/test_errata.py). This module holds the errata, the terms'
arithmetic, the platform's equations (1)-(7), the tables and their display; derive/printed_legs.py
the legs' equations (11)-(35).

Every equation is a function returning its terms: a dict ``{name: value}`` whose values add up to
the left-hand side of the printed ``... = 0`` (``residual``). With ``fix=()`` a function gives the
equation exactly as printed; every erratum id in ``fix`` replaces the printed term(s) it concerns
by the derived one(s), and with all the ids of ``EQUATION_ERRATA[eq]`` the equation is the one that
follows from Newton-Euler. Arguments that only a correction needs are keyword-only and may be
omitted while that correction is not asked for.

The functions are generic: every value may be a SymPy expression (to display an equation, see
``printed_equation``) or a NumPy array (to evaluate it at many states at once, the state axis
last). Indexing: ``X[i, j]`` is component j (x, y, z) of joint i (0..5) for the six-joint
arrays, shape (6, 3, ...), or a 6x3 SymPy Matrix; ``v[j]`` is component j of a vector, shape
(3, ...), or a 3x1 Matrix; ``J[j, k]`` an entry of a 3x3 matrix, shape (3, 3, ...).

Reading
-------
The paper states no sign convention. Its force equations (2)-(4), (11)-(13), (28)-(29) hold as
printed (leg weights aside, E13) under one reading, which every function here takes:

* ``R^O_Ei``: the force that the platform exerts on leg i at E_i (the project's ``R_E``, the force
  on the platform, is ``-R^O_Ei``);
* ``R^O_Ci``, ``M^O_Ci``: the force and moment that leg i exerts on the base at C_i (the
  project's ``R_C`` and ``M_C n_i`` act on the leg: ``R^O_Ci = -R_C``, ``M^O_Ci = -M_C n_i``);
* ``R^θ_3i``, ``M^θ_3i``: the force and moment (about the joint point P_3i) that the upper part
  of leg i exerts on the lower part at the prismatic joint (``-R_3``, ``-M_3`` of the project,
  with the axial force: ``R^θ_Z3i`` is the actuator force ``F0``);
* ``W_T = (m_M + m_E) g``, the weight as a positive number;
* ``F = m a`` and ``M = I α`` (17), the effective forces and moments, entering with the signs
  printed.

In words: each reaction is the load that the body nearer the platform puts on the body nearer
the base. Under any other reading (``R -> -R``, ``W_T -> -W_T``) more terms are wrong, and the
tests evaluate the printed equations under those readings too.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .kinematics import paper_b_entries

# ----------------------------------------------------------------------------- the errata


@dataclass(frozen=True)
class Erratum:
    """One difference between a printed equation (or table, or text) and the derivation.

    Attributes
    ----------
    id : str
        ``E01``, ``E02``, ...: the name used in docs/reference/errata.md and in the test's name.
    where : str
        Equation numbers, or the table or section of the paper.
    kind : str
        ``sign``, ``lever`` (wrong lever arm), ``omission`` (a term or equation left out),
        ``symbol`` (a wrong quantity in a term), ``notation`` (labels, operators, conventions),
        ``model`` (a modelling assumption the derivation does not share), ``table`` (a value or
        header of Tables 1-3).
    summary : str
        One line.
    """

    id: str
    where: str
    kind: str
    summary: str


ERRATA: tuple[Erratum, ...] = (
    Erratum("E01", "(1)", "notation",
            "the printed matrices are labelled Ry(beta) and Rx(alpha); T = Rz(gamma) Rx(beta) "
            "Rz(alpha), whose entries are the printed b_ij"),
    Erratum("E02", "(1)", "omission",
            "[E]^O = T [E]^l omits the platform's position: E_i = p + T e_i"),
    Erratum("E03", "(2)-(4)", "notation",
            "signs of R^O_Ei and W_T unstated (and the weights given in kg): the equations hold "
            "only if R^O_Ei is the force on the leg and W_T = +(m_M + m_E) g"),
    Erratum("E04", "(5)", "sign",
            "the terms of R_ZE2, R_ZE3, R_ZE4 and R_YE2..R_YE6 have the wrong sign"),
    Erratum("E05", "(6)", "sign",
            "the terms of R_ZE4, R_ZE5, R_ZE6, R_XE2 and R_XE3 have the wrong sign (X_XE4 is "
            "X_E4)"),
    Erratum("E06", "(6)", "omission", "the term R_XE4 (Z_E4 - Z_E1) is missing"),
    Erratum("E07", "(6)", "lever",
            "W_T (X_E6 - X_E1) where -W_T (X_o - X_E1) belongs: lever arm and sign"),
    Erratum("E08", "(7)", "sign",
            "every reaction term has the wrong sign (opposite to the I_Z alpha_Z term)"),
    Erratum("E09", "(7)", "symbol", "R_XE6 (X_E6 - X_E1) where R_YE6 (X_E6 - X_E1) belongs"),
    Erratum("E10", "(7)", "omission", "the term R_YE4 (X_E4 - X_E1) is missing"),
    Erratum("E11", "(5)-(7)", "omission",
            "no moment of the platform's inertial force, (o - E_1) x (m_M + m_E) a"),
    Erratum("E12", "(5)-(7)", "omission",
            "inertial moment I_X alpha_X etc.: no omega x J omega, and the inertia taken in "
            "the base axes (J = T I T^T)"),
    Erratum("E13", "(11)-(16), (28)-(31)", "omission", "no weight of the leg parts"),
    Erratum("E14", "(14)-(16)", "notation",
            "operator missing before M_X2i + M_X4i (and '= 0' in (16)); the derived sign is "
            "minus in (14) and (15)"),
    Erratum("E15", "(15)", "sign",
            "the terms R_ZEi (X_Ei - X_Ci), F_Z2i and F_Z4i have the wrong sign"),
    Erratum("E16", "(16)", "sign", "the terms of F_X2i and F_X4i have the wrong sign"),
    Erratum("E17", "(16)", "lever",
            "D_i missing from the lever arms 0.75 cos(theta_X), 0.75 cos(theta_Y), "
            "0.25 cos(theta_Y)"),
    Erratum("E18", "(14)-(16)", "model",
            "the universal joint's moment taken about the base's Z axis only; it acts along "
            "n_i, with components in (14) and (15)"),
    Erratum("E19", "(14)-(16), (30)-(31)", "model",
            "zone centres at 0.25 D_i and 0.75 D_i from C_i move along the part: the lever "
            "arms hold for that placement only, not for rigid leg parts"),
    Erratum("E20", "(17)", "omission",
            "inertial moments I alpha in base axes: no omega x J omega, J = B I B^T"),
    Erratum("E21", "(19)-(20)", "notation",
            "(20) uses V_{Ei+1 Ei}, the reverse of (19)'s V = E_{i+1} - E_i (read literally, X "
            "and Y flip); E_7 = E_1 for leg 6 unstated"),
    Erratum("E22", "(25)-(27)", "symbol",
            "each leg-frame component is the sum of the base components times one unit "
            "vector; the component is the dot product R . U"),
    Erratum("E23", "(30)-(31)", "notation",
            "R_Y2i, R_X2i stand for the inertial force F_Y2i, F_X2i of zone 2"),
    Erratum("E24", "(28)-(32)", "omission",
            "the axial equation is left out: it gives the actuator force, never reported"),
    Erratum("E25", "(33)-(34)", "symbol",
            "the sign function printed omega / omega (= 1); it is omega / |omega|"),
    Erratum("E26", "(33)", "model",
            "omega_1i is called the projection of the relative angular speed onto the leg; "
            "the friction opposes the whole relative angular velocity"),
    Erratum("E27", "(35)", "notation",
            "c_s, the joints' coefficient in N m s/rad, used for the prismatic joint, which "
            "needs N s/m"),
    Erratum("E28", "RESULTS", "notation",
            "'inertia tensor unit matrix = 0.07 kg m^2' is 0.07 times the identity: the only "
            "reading under which I alpha needs no frame and omega x I omega = 0"),
    Erratum("E29", "RESULTS", "model",
            "one acceleration for zones 2 and 4 of every leg; the parts' accelerations differ "
            "between legs and zones"),
    Erratum("E30", "Tables 1-2", "table",
            "Table 1's header reads MfrC1..MfrC6 for the joints E_i (MfrE); 'MfrC.3' in both"),
    Erratum("E31", "text", "notation",
            "the joints C_i are called spherical in three places; they are universal joints"),
    Erratum("E32", "Tables 1-3", "table",
            "eight misprinted cells: seven with an extra digit (three of them a decade too "
            "small), one above every other value of its table"),
    Erratum("E33", "Tables 1-2", "table",
            "by (11)-(13) and (33)-(34) Tables 1 and 2 must agree to 1.5e-4 N m; 91 % of the "
            "cells differ by more"),
    Erratum("E34", "Table 3", "table",
            "the values imply |R_3| of 10-42 N, the size of the whole joint force; (28)-(29) "
            "give a transverse force below 0.01 N"),
)

EQUATION_ERRATA: dict[str, tuple[str, ...]] = {
    "1": ("E02",),
    "2-4": (),
    "5": ("E04", "E11", "E12"),
    "6": ("E05", "E06", "E07", "E11", "E12"),
    "7": ("E08", "E09", "E10", "E11", "E12"),
    "11-13": ("E13",),
    "14": ("E13", "E14", "E18", "E19"),
    "15": ("E13", "E14", "E15", "E18", "E19"),
    "16": ("E16", "E17", "E18", "E19"),
    "17": ("E20",),
    "20": ("E21",),
    "25-27": ("E22",),
    "28-32": ("E13", "E19", "E24"),
    "33-34": ("E25",),
}
"""The errata that each equation function knows how to correct (its ``fix`` ids)."""


# ----------------------------------------------------------------------------- helpers


def _sym(*xs) -> bool:
    return any(isinstance(x, sp.Basic) for x in xs)


def _sqrt(x):
    return sp.sqrt(x) if _sym(x) else np.sqrt(x)


def absolute(x):
    """``|x|`` of a SymPy expression or a NumPy array (elementwise)."""
    return sp.Abs(x) if _sym(x) else np.abs(x)


def cross(a, b) -> list:
    """``a x b`` of two 3-vectors (indexable by component: lists, arrays, 3x1 Matrices)."""
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _matvec(J, v) -> list:
    return [J[j, 0] * v[0] + J[j, 1] * v[1] + J[j, 2] * v[2] for j in range(3)]


def norm(v):
    """``|v|`` of a 3-vector (SymPy or NumPy components)."""
    return _sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2)


def inertial_moment(J, alpha, omega) -> list:
    """``J alpha + omega x (J omega)``: the moment a body's rotation needs about its centre.

    Parameters
    ----------
    J : 3x3
        Inertia about the centre of mass, base frame.
    alpha, omega : 3-vectors
        Angular acceleration and velocity, base frame.
    """
    Jw = _matvec(J, omega)
    gyro = cross(omega, Jw)
    Ja = _matvec(J, alpha)
    return [Ja[j] + gyro[j] for j in range(3)]


def residual(terms: dict):
    """Sum of an equation's terms: the left-hand side of ``... = 0``.

    Parameters
    ----------
    terms : dict
        Term name -> value (scalars or arrays of one shape, in the equation's unit).

    Returns
    -------
    The sum, same shape and unit.
    """
    return sum(terms.values())


def magnitude(terms: dict):
    """Sum of the terms' absolute values: the scale against which a residual is small.

    Parameters
    ----------
    terms : dict
        Term name -> value (scalars or arrays of one shape, in the equation's unit).

    Returns
    -------
    The sum of magnitudes, same shape and unit.
    """
    return sum(absolute(v) for v in terms.values())


def check_fix(fix, eq: str) -> frozenset:
    """The erratum ids ``fix`` as a set; ValueError unless ``EQUATION_ERRATA[eq]`` has them all."""
    fix = frozenset(fix)
    unknown = fix - set(EQUATION_ERRATA[eq])
    if unknown:
        raise ValueError(f"equation ({eq}) has no erratum {sorted(unknown)}")
    return fix


def need(value, name: str, eid: str):
    """``value``; ValueError when it is None, since correcting ``eid`` needs ``name``."""
    if value is None:
        raise ValueError(f"correcting {eid} needs {name}")
    return value


# ----------------------------------------------------------------------------- (1)


def rz(angle) -> sp.Matrix:
    """The rotation about z printed beside (1) as ``Rz(gamma)``.

    Parameters
    ----------
    angle : sympy.Expr
        rad.

    Returns
    -------
    sympy.Matrix, shape (3, 3)
    """
    c, s = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def eq1_printed_matrices(alpha, beta, gamma) -> dict[str, sp.Matrix]:
    """The three matrices printed beside (1), under their printed labels.

    ``"Ry(beta)"`` is a rotation about y and ``"Rx(alpha)"`` a rotation about x with the angle
    alpha, although the text defines ``T = Rz(gamma) Rx(beta) Rz(alpha)`` (E01).
    """
    cb, sb = sp.cos(beta), sp.sin(beta)
    ca, sa = sp.cos(alpha), sp.sin(alpha)
    return {
        "Ry(beta)": sp.Matrix([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]]),
        "Rz(gamma)": rz(gamma),
        "Rx(alpha)": sp.Matrix([[1, 0, 0], [0, ca, -sa], [0, sa, ca]]),
    }


def eq1_printed_b(alpha, beta, gamma) -> sp.Matrix:
    """The entries b_ij of T as printed below (1).

    Parameters
    ----------
    alpha, beta, gamma : sympy.Expr
        Euler angles, rad.

    Returns
    -------
    sympy.Matrix, shape (3, 3)
        Platform -> base rotation, 1.
    """
    return paper_b_entries(alpha, beta, gamma)


def eq1_point(T, e, fix=(), *, p=None) -> list:
    """(1) as printed: ``[E_i]^O = [T] [E_i]^l``, a platform point in the base frame.

    Parameters
    ----------
    T : 3x3
        Rotation platform -> base.
    e : 3-vector
        The point in the platform frame.
    fix : subset of ``("E02",)``
        E02: add the platform frame's origin ``p`` (needs ``p``).
    """
    fix = check_fix(fix, "1")
    point = _matvec(T, e)
    if "E02" in fix:
        origin = need(p, "p", "E02")
        return [point[k] + origin[k] for k in range(3)]
    return point


# ----------------------------------------------------------------------------- (2)-(7)


def eq2_4_terms(R_E, W_T, m_M, m_E, a, fix=()) -> list[dict]:
    """(2), (3), (4): the platform's force equations, as printed.

    ``R_XE1 + ... + R_XE6 + (m_M + m_E) a_x = 0`` and likewise for y; (4) adds ``W_T``.

    Parameters
    ----------
    R_E : (6, 3)
        ``R^O_Ei`` (force of the platform on leg i, see Reading).
    W_T : scalar
        Total weight, ``(m_M + m_E) g`` under the reading.
    m_M, m_E : scalar
        Masses of the platform and of the payload.
    a : 3-vector
        Acceleration of their (common) centre of mass.
    fix : ()
        (2)-(4) need no correction under the reading (E03 concerns the reading itself).

    Returns
    -------
    list of three term dicts (x, y, z)
    """
    check_fix(fix, "2-4")
    out = []
    for j, axis in enumerate("XYZ"):
        terms = {f"R_{axis}E{i + 1}": R_E[i, j] for i in range(6)}
        if axis == "Z":
            terms["W_T"] = W_T
        terms["inertial force"] = (m_M + m_E) * a[j]
        out.append(terms)
    return out


def _inertial_force_term(fix, m, a, o, E1, axis) -> dict:
    """E11's term of (5)-(7): component ``axis`` of ``(o - E_1) x m a``, when E11 is fixed."""
    if "E11" not in fix:
        return {}
    m = need(m, "m", "E11")
    a = need(a, "a", "E11")
    r = [o[k] - E1[k] for k in range(3)]
    return {"inertial force": m * cross(r, a)[axis]}


def eq5_terms(R_E, E, W_T, o, I, alpha, fix=(), *, m=None, a=None, J=None, omega=None) -> dict:
    """(5), the platform's moments about the x axis through E_1, as printed.

    ``-R_ZE2 (Y_E2 - Y_E1) - R_ZE3 (..) - R_ZE4 (..) + R_ZE5 (..) + R_ZE6 (..) + W_T (Y_o - Y_E1)
    + R_YE2 (Z_E2 - Z_E1) + ... + R_YE6 (Z_E6 - Z_E1) + I_X alpha_X = 0``

    Parameters
    ----------
    R_E, E : (6, 3)
        ``R^O_Ei`` and the joints E_i (base frame).
    W_T : scalar
        Total weight (positive).
    o : 3-vector
        Centre of mass of platform and payload (the printed ``Y_o`` is ``o[1]``).
    I : 3-vector
        The printed ``I_X, I_Y, I_Z``: principal moments of inertia.
    alpha : 3-vector
        The platform's angular acceleration.
    fix : subset of ``EQUATION_ERRATA["5"]``
        E04 (signs), E11 (needs ``m``, ``a``), E12 (needs ``J``, ``omega``).
    m, a : scalar, 3-vector
        Mass of platform and payload, acceleration of ``o``.
    J : 3x3
        Their inertia about ``o`` in the base frame, ``T I T^T``.
    omega : 3-vector
        The platform's angular velocity.
    """
    fix = check_fix(fix, "5")
    Y1, Z1 = E[0, 1], E[0, 2]
    sign_z = (-1, -1, -1, 1, 1)
    terms = {}
    for k, i in enumerate(range(1, 6)):
        s = 1 if "E04" in fix else sign_z[k]
        terms[f"R_ZE{i + 1}"] = s * R_E[i, 2] * (E[i, 1] - Y1)
    terms["W_T"] = W_T * (o[1] - Y1)
    for i in range(1, 6):
        s = -1 if "E04" in fix else 1
        terms[f"R_YE{i + 1}"] = s * R_E[i, 1] * (E[i, 2] - Z1)
    terms.update(_inertial_force_term(fix, m, a, o, [E[0, k] for k in range(3)], 0))
    terms["inertial moment"] = _rotation_term(fix, I, alpha, J, omega, 0)
    return terms


def _rotation_term(fix, I, alpha, J, omega, axis):
    if "E12" in fix:
        return inertial_moment(need(J, "J", "E12"), alpha, need(omega, "omega", "E12"))[axis]
    return I[axis] * alpha[axis]


def eq6_terms(R_E, E, W_T, o, I, alpha, fix=(), *, m=None, a=None, J=None, omega=None) -> dict:
    """(6), the platform's moments about the y axis through E_1, as printed.

    ``-R_ZE2 (X_E2 - X_E1) - R_ZE3 (..) + R_ZE4 (X_XE4 - X_E1) + R_ZE5 (..) + R_ZE6 (..)
    + W_T (X_E6 - X_E1) - R_XE2 (Z_E2 - Z_E1) - R_XE3 (..) + R_XE5 (..) + R_XE6 (..)
    + I_Y alpha_Y = 0``, with ``X_XE4`` read as ``X_E4``.

    Parameters as ``eq5_terms``; ``fix`` from E05 (signs), E06 (the R_XE4 term), E07 (the weight's
    lever arm), E11, E12.
    """
    fix = check_fix(fix, "6")
    X1, Z1 = E[0, 0], E[0, 2]
    sign_z = (-1, -1, 1, 1, 1)
    sign_x = (-1, -1, None, 1, 1)
    terms = {}
    for k, i in enumerate(range(1, 6)):
        s = -1 if "E05" in fix else sign_z[k]
        terms[f"R_ZE{i + 1}"] = s * R_E[i, 2] * (E[i, 0] - X1)
    if "E07" in fix:
        terms["W_T"] = -W_T * (o[0] - X1)
    else:
        terms["W_T"] = W_T * (E[5, 0] - X1)
    for k, i in enumerate(range(1, 6)):
        if sign_x[k] is None:
            if "E06" in fix:
                terms[f"R_XE{i + 1}"] = R_E[i, 0] * (E[i, 2] - Z1)
            continue
        s = 1 if "E05" in fix else sign_x[k]
        terms[f"R_XE{i + 1}"] = s * R_E[i, 0] * (E[i, 2] - Z1)
    terms.update(_inertial_force_term(fix, m, a, o, [E[0, k] for k in range(3)], 1))
    terms["inertial moment"] = _rotation_term(fix, I, alpha, J, omega, 1)
    return terms


def eq7_terms(R_E, E, W_T, o, I, alpha, fix=(), *, m=None, a=None, J=None, omega=None) -> dict:
    """(7), the platform's moments about the z axis through E_1, as printed.

    ``R_XE2 (Y_E2 - Y_E1) - R_YE2 (X_E2 - X_E1) + R_XE3 (..) - R_YE3 (..) + R_XE4 (..)
    + R_XE5 (..) - R_YE5 (..) + R_XE6 (Y_E6 - Y_E1) - R_XE6 (X_E6 - X_E1) + I_Z alpha_Z = 0``

    The weight has no moment about a vertical axis, so ``W_T`` does not enter. Parameters as
    ``eq5_terms``; ``fix`` from E08 (signs), E09 (R_YE6 for R_XE6), E10 (the R_YE4 term), E11,
    E12.
    """
    fix = check_fix(fix, "7")
    X1, Y1 = E[0, 0], E[0, 1]
    sx, sy = (-1, 1) if "E08" in fix else (1, -1)
    terms = {}
    for i in range(1, 6):
        terms[f"R_XE{i + 1}"] = sx * R_E[i, 0] * (E[i, 1] - Y1)
        if i == 3 and "E10" not in fix:
            continue
        force = R_E[i, 1] if (i != 5 or "E09" in fix) else R_E[i, 0]
        terms[f"R_YE{i + 1}"] = sy * force * (E[i, 0] - X1)
    terms.update(_inertial_force_term(fix, m, a, o, [E[0, k] for k in range(3)], 2))
    terms["inertial moment"] = _rotation_term(fix, I, alpha, J, omega, 2)
    return terms


# ----------------------------------------------------------------------------- the tables


def read_table(path) -> tuple[list[str], list[list[str]]]:
    """One of the paper's tables (paper/table*.csv) as printed strings.

    The misprinted cells of the tables are found by ``gsfric.paper.find_misprints`` (the one
    detector; derive/ does not import the runtime, the errata tests call it).

    Parameters
    ----------
    path : path-like
        A CSV with a ``pos`` column and six value columns.

    Returns
    -------
    header : list of str
    rows : list of list of str
        40 rows of 7 printed cells.
    """
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], rows[1:]


# ----------------------------------------------------------------------------- display


def _vector_symbol(name: str) -> sp.Matrix:
    return sp.Matrix([sp.Symbol(f"{name}_{{{a}}}", real=True) for a in "XYZ"])


def _paper_symbols():
    """SymPy symbols named as in the paper, for ``printed_equation``."""
    R = sp.Matrix(6, 3, lambda i, j: sp.Symbol(f"R^O_{{{'XYZ'[j]}E{i + 1}}}", real=True))
    E = sp.Matrix(6, 3, lambda i, j: sp.Symbol(f"{'XYZ'[j]}_{{E{i + 1}}}", real=True))
    return dict(R=R, E=E, W_T=sp.Symbol("W_T", positive=True),
                o=_vector_symbol("o"), I=_vector_symbol("I"), alpha=_vector_symbol(r"\alpha"),
                a=_vector_symbol("a"),
                m_M=sp.Symbol("m_M", positive=True), m_E=sp.Symbol("m_E", positive=True))


def printed_equation(number: str) -> sp.Eq | list[sp.Eq]:
    """A platform equation as printed, as a SymPy equation (for a notebook).

    Parameters
    ----------
    number : {"2-4", "5", "6", "7"}
    """
    s = _paper_symbols()
    if number == "2-4":
        return [sp.Eq(residual(t), 0) for t in eq2_4_terms(s["R"], s["W_T"], s["m_M"], s["m_E"],
                                                          s["a"])]
    f = {"5": eq5_terms, "6": eq6_terms, "7": eq7_terms}[number]
    return sp.Eq(residual(f(s["R"], s["E"], s["W_T"], s["o"], s["I"], s["alpha"])), 0)
