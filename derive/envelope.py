"""The per-step values a load envelope maximises, computed with the model (``envelope``).

A sizing sweep (gsfric/sweep/) keeps, per leg, the largest magnitude of each joint load and
friction over all steps. Rather than writing every output of ``eval`` and taking the norms in
NumPy, ``envelope`` computes, from the same expressions as ``eval``, one row ``G`` (13, 6) per
step, every entry to be maximised over the steps:

=====  ======================================================  =====
row    value (leg i)                                           unit
=====  ======================================================  =====
0-5    ``|R_E|^2, |R_C|^2, |R_3|^2, |M_3|^2, |MfrE|^2, |MfrC|^2``  N^2, (N m)^2
6      ``|M_C|``                                               N m
7, 8   ``F``, ``-F`` (the largest -F is the smallest F)        N
9      ``|Ffr|``                                               N
10-12  dissipated friction powers ``-MfrE . omega_rel``,       W
       ``-MfrC . omega_leg``, ``-Ffr D_dot``
=====  ======================================================  =====

(the square root is left to the few extremes), with the outputs the step flags read (``D``,
``s2``, ``h``, ``coupling_change``, ``F0``) under their ``eval`` names.
"""

import casadi as ca

ROWS = ("R_E", "R_C", "R_3", "M_3", "MfrE", "MfrC", "M_C", "F_max", "F_min", "Ffr", "P_E",
        "P_C", "P_3")
"""Rows of ``G``: the squared magnitudes of the first six vectors, then the scalars."""

FLAG_OUTPUTS = ("D", "s2", "h", "coupling_change", "F0")
"""Outputs of ``eval`` the step flags read, passed through."""


def _dot(a, b, leg: int):
    """a_i . b_i of row-major (6, 3) columns a, b for leg i."""
    return sum(a[3 * leg + j] * b[3 * leg + j] for j in range(3))


def rows(kin: dict) -> list:
    """The 78 entries of ``G`` (row-major (13, 6)) from the kinematic model's outputs."""
    G = []
    for name in ROWS[:6]:
        G += [_dot(kin[name], kin[name], i) for i in range(6)]
    G += [ca.fabs(kin["M_C"][i]) for i in range(6)]
    G += [kin["F"][i] for i in range(6)]
    G += [-kin["F"][i] for i in range(6)]
    G += [ca.fabs(kin["Ffr"][i]) for i in range(6)]
    G += [-_dot(kin["MfrE"], kin["omega_rel"], i) for i in range(6)]
    G += [-_dot(kin["MfrC"], kin["omega_leg"], i) for i in range(6)]
    G += [-(kin["Ffr"][i] * kin["D_dot"][i]) for i in range(6)]
    return G


def function(name: str, kin: dict, x, P, Q):
    """The CasADi function ``name``: (x, P, Q) -> G (78,), then ``FLAG_OUTPUTS``."""
    return ca.Function(name, [x, P, Q], [ca.vertcat(*rows(kin))] +
                       [kin[n] for n in FLAG_OUTPUTS], ["x", "P", "Q"], ["G", *FLAG_OUTPUTS])


SHAPES = {"G": [len(ROWS), 6]}
ROW_NAMES = {"G": ROWS}
UNITS = {"G": "N^2, (N m)^2, N m, N, W (per row)"}
DESCRIPTIONS = {"G": "per-step values a load envelope maximises, rows " + ", ".join(ROWS) +
                " (derive/envelope.py)"}
