"""What a load envelope holds and how one case's envelope is reduced, block by block.

Per step, the generated function ``envelope`` (derive/envelope.py) writes the values ``G``
(rows, 6) every one of which is maximised over the steps; its rows are named in the manifest
(``envelope_rows``). ``Envelope`` folds blocks of ``G`` into the running extremes of a case,
with the step, time and pose of each, and integrates the friction powers into energies;
``Envelope.rows`` turns them into the rows of ``envelopes.parquet`` (``ENVELOPE_COLUMNS``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping

import numpy as np

from gsfric.compiled.manifest import function
from gsfric.compiled.state import state_layout
from gsfric.errors import GsfricError
from gsfric.evaluation.parameters import model_function
from gsfric.signal.rotations import rpy_from_rotation
from gsfric.sweep.workspace import POSE

QUANTITIES: dict[str, tuple[str, str, str]] = {
    "R_E": ("max", "N", "spherical joint load |R_E|"),
    "R_C": ("max", "N", "universal joint load |R_C|"),
    "M_C": ("max", "N m", "universal joint torsion moment |M_C|"),
    "R_3": ("max", "N", "prismatic joint transverse force |R_3|"),
    "M_3": ("max", "N m", "prismatic joint moment |M_3|"),
    "F_max": ("max", "N", "largest actuator force (pushing)"),
    "F_min": ("min", "N", "smallest actuator force (pulling when negative)"),
    "Ffr": ("max", "N", "prismatic friction force |Ffr|"),
    "MfrE": ("max", "N m", "spherical joint friction moment |MfrE|"),
    "MfrC": ("max", "N m", "universal joint friction moment |MfrC|"),
    "P_E": ("max", "W", "friction power dissipated in the spherical joint"),
    "P_C": ("max", "W", "friction power dissipated in the universal joint"),
    "P_3": ("max", "W", "friction power dissipated in the prismatic joint"),
    "W_E": ("sum", "J", "friction energy dissipated in the spherical joint (motions only)"),
    "W_C": ("sum", "J", "friction energy dissipated in the universal joint (motions only)"),
    "W_3": ("sum", "J", "friction energy dissipated in the prismatic joint (motions only)"),
}
"""Envelope quantities: name -> (reduction, unit, meaning). Loads and moments are magnitudes;
powers are dissipated (positive), ``-MfrE . omega_rel``, ``-MfrC . omega_leg``, ``-Ffr D_dot``;
energies are their trapezoidal time integrals (NaN for workspace samples, which are no motion)."""

ENVELOPE_COLUMNS = ("motion", "variant", "quantity", "leg", "value", "step", "t", *POSE,
                    "steps", "flagged", "at_rest")
"""Columns of ``envelopes.parquet``: ``step`` is the 0-based step of the motion (for the
workspace, ``pose * states + state``), -1 for sums; ``steps`` and ``flagged`` count the
case's evaluated and flagged steps (flagged steps are left out of the envelope); ``at_rest``
its steps with a leg possibly at rest (a motion differentiated from a file:
``gsfric.evaluation.uncertainty.possibly_at_rest``; friction there is bounded by its Coulomb
level, so the friction extremes of such steps are upper bounds; 0 for the workspace)."""

LIMIT_QUANTITY = {"spherical_load": "R_E", "universal_load": "R_C", "universal_moment": "M_C",
                  "prismatic_load": "R_3", "prismatic_moment": "M_3"}
"""The quantity each rating of a platform's ``[limits]`` bounds (``actuator_force`` bounds
``F_min`` and ``F_max``)."""

ENERGIES = {"W_E": "P_E", "W_C": "P_C", "W_3": "P_3"}
"""Energy quantity -> the row of ``G`` whose time integral it is."""

SQUARED = ("R_E", "R_C", "R_3", "M_3", "MfrE", "MfrC")
"""Rows of ``G`` that are squared magnitudes of vector outputs (N, 6, 3) of the same name: the
square root is taken of the extremes only."""

_POWERS = {"P_E": ("MfrE", "omega_rel"), "P_C": ("MfrC", "omega_leg")}
"""Friction powers ``-M . omega`` of the joints, from (moment, angular velocity) outputs."""

VALUE_INPUTS = ("F", "M_C", "Ffr", "D_dot", "omega_rel", "omega_leg", *SQUARED)
"""Outputs of ``Evaluator.evaluate_quiet`` that ``values`` reads."""


class _Arrays:
    """Outputs of ``n`` steps as (n, 6, 3) vectors and (n, 6) per-leg values."""

    def __init__(self, arrays: Mapping[str, np.ndarray], n: int) -> None:
        self.arrays, self.n = arrays, n

    def vector(self, name: str) -> np.ndarray:
        return np.asarray(self.arrays[name], float).reshape(self.n, 6, 3)

    def scalar(self, name: str) -> np.ndarray:
        return np.asarray(self.arrays[name], float).reshape(self.n, 6)


def _square(name: str) -> Callable[[_Arrays], np.ndarray]:
    def row(a: _Arrays) -> np.ndarray:
        v = a.vector(name)
        return np.einsum("nij,nij->ni", v, v)
    return row


def _power(moment: str, omega: str) -> Callable[[_Arrays], np.ndarray]:
    def row(a: _Arrays) -> np.ndarray:
        return -np.einsum("nij,nij->ni", a.vector(moment), a.vector(omega))
    return row


_RECIPES: dict[str, Callable[[_Arrays], np.ndarray]] = {
    **{name: _square(name) for name in SQUARED},
    "M_C": lambda a: np.abs(a.scalar("M_C")),
    "F_max": lambda a: a.scalar("F"),
    "F_min": lambda a: -a.scalar("F"),
    "Ffr": lambda a: np.abs(a.scalar("Ffr")),
    **{name: _power(*pair) for name, pair in _POWERS.items()},
    "P_3": lambda a: -(a.scalar("Ffr") * a.scalar("D_dot")),
}
"""Each row of ``G`` in NumPy, from evaluated outputs: what derive/envelope.py computes."""


@functools.lru_cache(maxsize=None)
def envelope_rows() -> tuple[str, ...]:
    """Names of the rows of the generated ``envelope``'s output ``G`` (rows, 6), in order, as
    the manifest records them (derive/envelope.py): R_E, R_C, R_3, M_3, MfrE, MfrC, M_C, F_max,
    F_min, Ffr, P_E, P_C, P_3."""
    meta = function(model_function("envelope", "coupled"))
    G = next(o for o in meta["outputs"] if o["name"] == "G")
    names = tuple(G.get("rows", ()))
    if len(names) != G["shape"][0] or set(names) != set(_RECIPES):
        raise GsfricError(f"generated/manifest.json: the rows of {meta['name']}'s G are not "
                          f"those of a load envelope ({names}); run `gsfric derive`")
    return names


def values(arrays: Mapping[str, np.ndarray], out: np.ndarray | None = None) -> np.ndarray:
    """The values ``G`` (N, 13, 6) (rows ``envelope_rows()``) of evaluated outputs ``arrays``
    (those of ``Evaluator.evaluate_quiet``, at least ``VALUE_INPUTS``): what the generated
    function ``envelope`` computes, in NumPy (the path of platforms with sensor effects)."""
    rows = envelope_rows()
    n = len(arrays["F"])
    G = np.empty((n, len(rows), 6)) if out is None else out
    outputs = _Arrays(arrays, n)
    for k, name in enumerate(rows):
        G[:, k] = _RECIPES[name](outputs)
    return G


_NONE = np.zeros(0, dtype=np.int64)
_NONE.flags.writeable = False      # shared by every envelope of a process


class Envelope:
    """Running extremes of one case, block by block in step order (deterministic: ties go to
    the earlier step).

    Attributes
    ----------
    best : ndarray (rows, 6)
        Largest value of each row of ``G`` and leg so far (-inf before any unflagged step).
    step : ndarray (rows, 6) int
        Step of each extreme (-1 before any).
    t : ndarray (rows, 6)
        Time of each extreme, s.
    state : ndarray (rows, 6, 12)
        Position (m) and rotation (row-major) of each extreme's step.
    energy : ndarray (3, 6)
        Dissipated friction energies ``ENERGIES`` so far, J.
    steps, flagged : int
        Evaluated and flagged steps so far.
    at_rest : int
        Steps with a leg possibly at rest so far (counted by the caller).
    last : (float, ndarray (3, 6)) or None
        Time and friction powers of the previous step (the trapezoid across blocks).
    """

    def __init__(self) -> None:
        rows = envelope_rows()
        shape = (len(rows), 6)
        self.best = np.full(shape, -np.inf)
        self.step = np.full(shape, -1, dtype=np.int64)
        self.t = np.full(shape, np.nan)
        self.state = np.full(shape + (12,), np.nan)
        self.energy = np.zeros((len(ENERGIES), 6))
        self.steps = 0
        self.flagged = 0
        self.at_rest = 0
        self.last = None
        self._powers = np.array([rows.index(p) for p in ENERGIES.values()])
        layout = state_layout()
        self._pose = np.r_[layout.position, layout.rotation]   # what locates a step

    def add(self, G: np.ndarray, flag: np.ndarray, x: np.ndarray, t: np.ndarray, step0: int,
            timed: bool, work: np.ndarray) -> None:
        """Fold in a block: values ``G`` (n, rows, 6) (flagged steps are set to -inf in place),
        step flags (n,), states x (n, 24), times t (n,), first step ``step0``; ``work`` holds at
        least 18 (n - 1) values for the energies.

        One pass over the block for the largest value of each column; the step of a column's
        largest value is searched only where it beats the running extreme, which becomes rare
        as the case goes on."""
        n = len(G)
        bad = np.flatnonzero(flag) if np.count_nonzero(flag) else _NONE
        self.steps += n
        self.flagged += bad.size
        if timed:
            self._integrate(G[:, self._powers], bad, t, work)
        if bad.size:
            G[bad] = -np.inf                    # flagged steps are left out of the envelope
        flat = G.reshape(n, -1)
        best = self.best.reshape(-1)
        better = np.flatnonzero(flat.max(axis=0) > best)
        if better.size:
            at = flat[:, better].argmax(axis=0)                     # the first largest
            best[better] = flat[at, better]
            q, leg = np.divmod(better, 6)
            self.step[q, leg] = step0 + at
            self.t[q, leg] = t[at]
            self.state[q, leg] = x[at][:, self._pose]

    def _integrate(self, P: np.ndarray, bad: np.ndarray, t: np.ndarray,
                   work: np.ndarray) -> None:
        """Trapezoid of the powers P (n, 3, 6) over t, across block boundaries (flagged: 0);
        ``work`` holds at least (n - 1) 3 6 values."""
        if bad.size:
            P = P.copy()
            P[bad] = 0.0
        if self.last is not None:
            self.energy += 0.5 * (t[0] - self.last[0]) * (P[0] + self.last[1])
        n = len(t)
        if n > 1:
            pairs = work[:(n - 1) * 18].reshape(n - 1, 18)
            np.add(P[1:].reshape(n - 1, 18), P[:-1].reshape(n - 1, 18), out=pairs)
            self.energy += 0.5 * (np.diff(t) @ pairs).reshape(3, 6)
        self.last = (t[-1], P[-1].copy())

    def _values(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(found, value, pose) per row and leg: whether an extreme was found, its value in
        the quantity's unit, its pose (rows, 6, 6) (``POSE``)."""
        rows = envelope_rows()
        found = self.step >= 0
        value = np.where(found, self.best, np.nan)
        squared = [rows.index(q) for q in SQUARED]
        value[squared] = np.sqrt(value[squared])
        for r, q in enumerate(rows):
            if QUANTITIES[q][0] == "min":
                value[r] = -value[r]
        pose = np.full((len(rows), 6, 6), np.nan)
        pose[found, 0:3] = self.state[found, 0:3]
        if found.any():
            pose[found, 3:6] = rpy_from_rotation(self.state[found, 3:12].reshape(-1, 3, 3))
        return found, value, pose

    def rows(self, motion: str, variant: int, timed: bool) -> list[tuple]:
        """The case's rows of ``envelopes.parquet`` (``ENVELOPE_COLUMNS``), quantities in the
        order of ``QUANTITIES``, legs 1-6."""
        rows = envelope_rows()
        found, value, pose = self._values()
        energies = list(ENERGIES)
        out = []
        for q in QUANTITIES:
            for leg in range(6):
                if q in ENERGIES:
                    w = float(self.energy[energies.index(q), leg]) if timed else math.nan
                    where = [-1] + [math.nan] * 7
                    out.append((motion, variant, q, leg + 1, w, *where, self.steps,
                                self.flagged, self.at_rest))
                    continue
                r = rows.index(q)
                where = [int(self.step[r, leg]),
                         float(self.t[r, leg]) if timed and found[r, leg] else math.nan,
                         *pose[r, leg].tolist()]
                out.append((motion, variant, q, leg + 1, float(value[r, leg]), *where,
                            self.steps, self.flagged, self.at_rest))
        return out
