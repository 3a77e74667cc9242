"""The paper's printed equations of each group (``printed``) and the errata that concern it
(``errata``), from derive/printed.py and derive/printed_legs.py exactly as printed."""

from __future__ import annotations

import re

import sympy as sp

from .. import printed as pp
from .. import printed_legs as pl
from .printer import _Printer

GROUP_RANGES = {"1": (1, 1), "2-7": (2, 7), "8-10": (8, 10), "11-17": (11, 16), "17": (17, 17),
                "18-27": (18, 27), "28-32": (28, 32), "33-35": (33, 35)}
"""The paper's equation numbers of each group (``"11-17"`` holds (11)-(16), (17) is its own)."""


def errata(group: str) -> list[pp.Erratum]:
    """The errata (``derive.printed.ERRATA``) whose equation numbers fall in a group.

    Parameters
    ----------
    group : str
        A key of ``GROUP_RANGES``; other groups have none.

    Returns
    -------
    list of Erratum
    """
    if group not in GROUP_RANGES:
        return []
    lo, hi = GROUP_RANGES[group]
    found = []
    for e in pp.ERRATA:
        for first, last in re.findall(r"\((\d+)\)(?:-\((\d+)\))?", e.where):
            if int(first) <= hi and int(last or first) >= lo:
                found.append(e)
                break
    return found


def _paper_vector(kernel: str, label: str, axes: str = "XYZ") -> sp.Matrix:
    """The paper's components of a leg quantity: ``R^O_{XEi}`` ... (``kernel``, ``label``)."""
    return sp.Matrix([sp.Symbol(f"{kernel}_{{{a}{label}}}", real=True) for a in axes])


def _latex(expr) -> str:
    return _Printer().doprint(expr)


def _equation(terms: dict) -> str:
    return _latex(sp.Eq(pp.residual(terms), 0, evaluate=False))


def _leg_point(kernel: str) -> sp.Matrix:
    """The paper's coordinates of a leg's point, ``X_{Ei}`` ... (``kernel`` ``"E"`` or ``"C"``)."""
    return sp.Matrix([sp.Symbol(f"{a}_{{{kernel}i}}", real=True) for a in "XYZ"])


def _printed_1() -> list[tuple[str, str]]:
    T = sp.Matrix(3, 3, lambda r, c: sp.Symbol(f"b_{{{r + 1}{c + 1}}}", real=True))
    e = sp.Matrix([sp.Symbol(f"{a}^{{l}}_{{Ei}}", real=True) for a in "XYZ"])
    point = sp.Matrix(pp.eq1_point(T, e))
    lhs = sp.Matrix([sp.Symbol(f"{a}^{{O}}_{{Ei}}", real=True) for a in "XYZ"])
    return [("(1)", _latex(sp.Eq(lhs, point, evaluate=False)))]


def _printed_2_7() -> list[tuple[str, str]]:
    out = []
    for number in ("2-4", "5", "6", "7"):
        forms = pp.printed_equation(number)
        forms = forms if isinstance(forms, list) else [forms]
        out += [(f"({number})", _latex(f)) for f in forms]
    return out


def _printed_11_17() -> list[tuple[str, str]]:
    R_E, R_C = _paper_vector("R^O", "Ei"), _paper_vector("R^O", "Ci")
    F2, F4 = _paper_vector("F", "2i"), _paper_vector("F", "4i")
    M2, M4 = _paper_vector("M", "2i"), _paper_vector("M", "4i")
    M_C = _paper_vector("M^O", "Ci")
    E, C, D = _leg_point("E"), _leg_point("C"), sp.Symbol("D_i", positive=True)
    out = [("(11)-(13)", _equation(t)) for t in pl.eq11_13_terms(R_C, R_E, F2, F4)]
    out += [(f"({n})", _equation(t))
            for n, t in zip((14, 15, 16), pl.eq14_16_terms(R_E, E, C, D, F2, F4, M2, M4, M_C))]
    return out


def _printed_17() -> list[tuple[str, str]]:
    m, a = sp.Symbol("m", positive=True), _paper_vector("a", "")
    I, alpha = _paper_vector("I", ""), _paper_vector(r"\alpha", "")
    F, M = pl.eq17(m, a, I, alpha)
    return [("(17)", _latex(sp.Eq(_paper_vector("F", ""), sp.Matrix(F), evaluate=False))),
            ("(17)", _latex(sp.Eq(_paper_vector("M", ""), sp.Matrix(M), evaluate=False)))]


def _printed_18_27() -> list[tuple[str, str]]:
    E_next = sp.Matrix([sp.Symbol(f"{a}_{{Ei+1}}", real=True) for a in "XYZ"])
    U = pl.leg_frame(_leg_point("E"), _leg_point("C"), E_next)
    out = [(f"({n})", _latex(sp.Eq(sp.Symbol(f"U_{axis}"), sp.Matrix(u), evaluate=False)))
           for n, axis, u in zip((21, 22, 24), "XYZ", U)]
    R = _paper_vector("R^O", "")
    theta = sp.Matrix([sp.Symbol(rf"R^{{\theta}}_{{{a}}}") for a in "XYZ"])
    U_symbols = [sp.Matrix([sp.Symbol(f"U_{{{axis}{a}}}") for a in "xyz"]) for axis in "XYZ"]
    out.append(("(25)-(27)", _latex(sp.Eq(theta, sp.Matrix(pl.eq25_27(R, U_symbols)),
                                            evaluate=False))))
    return out


def _printed_28_32() -> list[tuple[str, str]]:
    R3, RE = _paper_vector(r"R^{\theta}", "3i"), _paper_vector(r"R^{\theta}", "Ei")
    F2t, M2t = _paper_vector(r"F^{\theta}", "2i"), _paper_vector(r"M^{\theta}", "2i")
    M3, D = _paper_vector(r"M^{\theta}", "3i"), sp.Symbol("D_i", positive=True)
    numbers = ("(28)", "(29)", "(30)", "(31)", "(32)")
    return [(n, _equation(t))
            for n, t in zip(numbers, pl.eq28_32_terms(R3, RE, F2t, M2t, M3, D))]


def _printed_33_35() -> list[tuple[str, str]]:
    c_s, mu, r = sp.symbols("c_s mu r", positive=True)
    out = []
    for n, joint, point in (("(33)", "1", "E"), ("(34)", "0", "C")):
        omega = _paper_vector(r"\omega", f"{joint}i", "xyz")
        moment = _paper_vector("M^{fr}", f"{point}i", "xyz")
        friction = sp.Matrix(pl.eq33_34(c_s, omega, mu, r, _paper_vector("R^O", f"{point}i")))
        out.append((n, _latex(sp.Eq(moment, friction, evaluate=False))))
    v, R3 = sp.Symbol("v_i", real=True), _paper_vector("R", "3i")
    out.append(("(35)", _latex(sp.Eq(sp.Symbol("F^{fr}_{i}"), pl.eq35(c_s, v, mu, R3),
                                       evaluate=False))))
    return out


_PRINTED = {"1": _printed_1, "2-7": _printed_2_7, "11-17": _printed_11_17, "17": _printed_17,
            "18-27": _printed_18_27, "28-32": _printed_28_32, "33-35": _printed_33_35}
"""The printed equations of each group, on symbols named as in the paper (leg i)."""


def printed(group: str) -> list[tuple[str, str]]:
    """The paper's printed equations of a group, exactly as printed, in LaTeX.

    Each comes from the equation functions of derive/printed.py and derive/printed_legs.py
    with no erratum fixed, on symbols named as in the paper (leg i).

    Parameters
    ----------
    group : str
        ``"1"``, ``"2-7"``, ``"11-17"``, ``"17"``, ``"18-27"``, ``"28-32"`` or ``"33-35"``;
        other groups print nothing.

    Returns
    -------
    list of (str, str)
        The equation number as printed, ``"(5)"``, and the equation.
    """
    return _PRINTED[group]() if group in _PRINTED else []
