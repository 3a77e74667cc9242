"""The output columns of ``gsfric simulate`` and ``Result.to_frame``: names, units, meanings.

The one list of the output columns (``COLUMNS``): their names, order, Result arrays, output
groups (``simulate --columns``), units and meanings. ``Result.to_frame`` and ``simulate`` build
their columns from it (``plan``); it gives the units that travel with the data
(``DataFrame.attrs["units"]``, the Parquet field metadata ``unit`` and ``description``),
``gsfric columns`` and the README's output table.

Legs are numbered 1..6 in column names (index 0..5 in arrays). Frames: "base" is the fixed
base frame. One name means one quantity: a column ``X1..X6`` (``X_1..X_6`` when X ends in a
digit, ``Xx1..Xz6`` for a vector) holds ``Result.X``; the reactions keep the contract's names
``REx1..``, ``RCx1..`` and ``MC1..`` (``Result.R_E``, ``R_C``, ``M_C``). The suffix ``_s``
marks the paper's post-hoc scalars (never positive: negative = opposing the motion):
``MfrE_s1..``, ``MfrC_s1..``, ``Ffr_s1..`` hold ``Result.MfrE_s``, ``MfrC_s``, ``Ffr_s``,
while ``Ffr1..Ffr6`` is the signed prismatic friction that loads the actuators
(``Result.Ffr``) and ``MfrEx1..``, ``MfrCx1..`` the friction moment vectors.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from gsfric._optional import optional


@dataclass(frozen=True)
class Column:
    """One output column (or family of six, ``name`` with ``i`` = 1..6).

    ``group``: the output group of ``simulate --columns`` (``GROUPS``; "time", "flags" and
    "measured" are always written); ``array``: the Result array the values come from (leg i
    at index i - 1 of a step's row, the components x, y, z of leg i at 3 (i - 1) + 0, 1, 2),
    None for ``t``, ``flag`` and the measured columns.
    """

    name: str
    unit: str
    description: str
    group: str
    array: str | None = None

    @property
    def label(self) -> str:
        """``F1..F6``, ``REx1..REz6``, ``t``: the family as it is listed."""
        names = self.names()
        return names[0] if len(names) == 1 else f"{names[0]}..{names[-1]}"

    def names(self) -> list[str]:
        """The concrete column names: ``F{i}`` -> F1..F6, ``RE{a}{i}`` -> REx1..REz6."""
        return [name for name, _ in self.entries()]

    def entries(self) -> list[tuple[str, int]]:
        """(column name, index in a step's row of ``array``) of every concrete column."""
        if "{a}" in self.name:
            return [(self.name.format(a=a, i=i), 3 * (i - 1) + j)
                    for i in range(1, 7) for j, a in enumerate("xyz")]
        if "{i}" in self.name:
            return [(self.name.format(i=i), i - 1) for i in range(1, 7)]
        return [(self.name, 0)]


COLUMNS: tuple[Column, ...] = (
    Column("t", "s", "time of the step (as read from the input, converted to s)", "time"),
    Column("F{i}", "N", "actuator force of leg i with friction and effects; + pushes the "
           "platform away from the base (Result.F)", "forces", "F"),
    Column("sigma_F{i}", "N", "one standard deviation of F_i from the differentiation of the "
           "recorded poses (their noise through the smoother, the stamps' jitter included), "
           "linearised in the rates (Result.sigma_F; gsfric.evaluation.uncertainty)",
           "uncertainty", "sigma_F"),
    Column("rest", "1", "legs whose speed is within 2 standard deviations of zero, possibly "
           "at rest: their friction may be anything within the Coulomb level, not the "
           "sliding value in F; the sum of 2^(i-1) over those legs i, 0 when all slide "
           "(Result.rest)", "uncertainty", "rest"),
    Column("Ffr{i}", "N", "friction force of prismatic joint i on the rod along the leg "
           "direction u_i (C_i to E_i), the friction that loads actuator i: negative while "
           "the leg extends, positive while it retracts (Result.Ffr)", "friction", "Ffr"),
    Column("MfrE_s{i}", "N m", "the paper's post-hoc scalar (33) of the friction moment of "
           "spherical joint E_i: <= 0, negative = opposing (Result.MfrE_s; the vector is "
           "MfrEx1..MfrEz6, Result.MfrE)", "friction", "MfrE_s"),
    Column("MfrC_s{i}", "N m", "the paper's post-hoc scalar (34) of the friction moment of "
           "universal joint C_i: <= 0, negative = opposing (Result.MfrC_s; the vector is "
           "MfrCx1..MfrCz6, Result.MfrC)", "friction", "MfrC_s"),
    Column("Ffr_s{i}", "N", "the paper's post-hoc scalar (35) of the friction force of "
           "prismatic joint i, from the leg's reaction R_3 as (35) has it: <= 0, negative = "
           "opposing (Result.Ffr_s; the friction that loads actuator i is Ffr1..Ffr6)",
           "friction", "Ffr_s"),
    Column("RE{a}{i}", "N", "force of leg i on the platform at E_i, base frame "
           "components x, y, z (Result.R_E)", "reactions", "R_E"),
    Column("RC{a}{i}", "N", "force of the base on leg i at C_i, base frame "
           "components x, y, z (Result.R_C)", "reactions", "R_C"),
    Column("MC{i}", "N m", "constraint moment of universal joint i along its normal n_i "
           "(Result.M_C)", "reactions", "M_C"),
    Column("F0_{i}", "N", "actuator force of leg i with frictionless joints; + pushes the "
           "platform away (Result.F0)", "frictionless", "F0"),
    Column("D{i}", "m", "length of leg i, C_i to E_i (Result.D)", "lengths", "D"),
    Column("F_joint{i}", "N", "part of F_i that carries the spherical and universal joints' "
           "friction moments (coupled model; zero in the paper's post-hoc model; "
           "Result.F_joint)", "friction_detail", "F_joint"),
    Column("MfrE{a}{i}", "N m", "friction moment vector of spherical joint E_i on the platform, "
           "opposing the platform's rotation relative to the leg; base frame components x, y, z "
           "(Result.MfrE)", "friction_detail", "MfrE"),
    Column("MfrC{a}{i}", "N m", "friction moment vector of universal joint C_i on the leg, "
           "opposing the leg's rotation relative to the base; base frame components x, y, z "
           "(Result.MfrC)", "friction_detail", "MfrC"),
    Column("flag", "1", "0 for a sound step; else the sum of 1 (non-finite value), 2 (leg "
           "length outside the stroke), 4 (near-singular platform Jacobian), 8 (leg near its "
           "universal joint's first axis), 16 (coupled friction solve not converged), 32 "
           "(rotation block of the state not a rotation matrix)", "flags"),
)
"""Every column of ``Result.to_frame``, in order."""

MEASURED: tuple[Column, ...] = (
    Column("F{i}_measured", "N", "actuator force of leg i as measured (the input's F1..F6, "
           "converted to N); simulate of a measured-data file only", "measured"),
    Column("F{i}_residual", "N", "measured minus model actuator force of leg i "
           "(Fi_measured - Fi); simulate of a measured-data file only", "measured"),
)
"""The columns ``simulate`` adds for an input with measured forces F1..F6."""


GROUP_MEANINGS = {
    "forces": "actuator forces with friction and effects",
    "uncertainty": "one standard deviation of F from the differentiation of the poses, and "
                   "the legs possibly at rest (a motion differentiated from poses)",
    "friction": "the prismatic friction that loads the actuators (Ffr) and the paper's "
                "post-hoc friction scalars (_s: <= 0, negative = opposing)",
    "reactions": "joint reactions (base frame) and the universal joints' constraint moments",
    "friction_detail": "the joints' share of F and the friction moment vectors",
    "frictionless": "actuator forces with frictionless joints",
    "lengths": "leg lengths",
}
"""What each output group of ``simulate --columns`` is for."""


def _group_text(group: str) -> str:
    """``Ffr1..Ffr6 (N), MfrE_s1..MfrE_s6 (N m), ...: meaning``, from ``COLUMNS``."""
    labels = ", ".join(f"{c.label} ({c.unit})" for c in COLUMNS if c.group == group)
    return f"{labels}: {GROUP_MEANINGS[group]}"


GROUPS = {group: _group_text(group) for group in GROUP_MEANINGS}
"""Output groups of ``simulate --columns`` (their columns and meaning); ``t`` and ``flag`` are
always written."""

DEFAULT_GROUPS = ("forces", "uncertainty", "friction", "reactions")
"""The groups ``simulate`` writes unless ``--columns`` says otherwise: with ``t`` and ``flag``
(``t``, F, its standard deviation and the legs possibly at rest, the prismatic friction that
loads the actuators, the paper's post-hoc friction scalars, the joint reactions, the flag: ``len(plan(DEFAULT_GROUPS)) + 2`` values a step);
every other group is one ``--columns`` away (``all``: every group)."""


def plan(groups=tuple(GROUPS)) -> list[tuple[str, str, int, str]]:
    """(column, Result array, index in a step's row of it, group) of every column of the
    chosen groups from a Result, in ``COLUMNS``' order (``t`` and ``flag`` not included)."""
    chosen = set(groups)
    return [(name, c.array, index, c.group) for c in COLUMNS
            if c.array is not None and c.group in chosen for name, index in c.entries()]


def all_columns(measured: bool = True) -> tuple[Column, ...]:
    return COLUMNS + (MEASURED if measured else ())


def units(measured: bool = True) -> dict[str, str]:
    """{column name: unit} of every concrete output column (``"1"`` for a pure number)."""
    return {name: c.unit for c in all_columns(measured) for name in c.names()}


def descriptions(measured: bool = True) -> dict[str, str]:
    """{column name: description} of every concrete output column."""
    return {name: c.description for c in all_columns(measured) for name in c.names()}


def listing(measured: bool = True) -> str:
    """The plain-text listing of ``gsfric columns``: column, unit, group, meaning."""
    rows = [(c.label, c.unit, c.group, c.description) for c in all_columns(measured)]
    widths = [max(len(r[k]) for r in rows) for k in range(3)]
    return "\n".join("  ".join(f"{v:<{w}}" for v, w in zip(r[:3], widths)) + f"  {r[3]}"
                     for r in rows)


def markdown_table(measured: bool = True) -> str:
    """The README's output table (between its ``columns`` markers)."""
    lines = ["| Column | Unit | Meaning |", "|---|---|---|"]
    for c in all_columns(measured):
        lines.append(f"| `{c.label}` | {c.unit} | {c.description} |")
    return "\n".join(lines)


@functools.lru_cache(maxsize=1)
def _known() -> tuple:
    """``(units(), descriptions())``, built once: annotate and arrow_table run per chunk.
    Private and never mutated (the public functions return fresh dicts)."""
    return units(), descriptions()


def annotate(frame):
    """``frame`` with ``attrs["units"]`` (and ``attrs["descriptions"]``) for its known columns."""
    known_units, known_text = _known()
    frame.attrs["units"] = {c: known_units[c] for c in frame.columns if c in known_units}
    frame.attrs["descriptions"] = {c: known_text[c] for c in frame.columns if c in known_text}
    return frame


def arrow_table(frame):
    """A pyarrow Table of ``frame`` (a DataFrame or a dict of column arrays) with field metadata
    ``unit`` and ``description``."""
    pa = optional("pyarrow")
    table = pa.table(frame) if isinstance(frame, dict) else \
        pa.Table.from_pandas(frame, preserve_index=False)
    known_units, known_text = _known()
    fields = []
    for f in table.schema:
        if f.name in known_units:
            f = f.with_metadata({"unit": known_units[f.name],
                                 "description": known_text[f.name]})
        fields.append(f)
    return table.cast(pa.schema(fields, metadata=table.schema.metadata))
