"""The output columns of ``gsfric simulate`` and ``Result.to_frame``: names, units, meanings.

The one list of the output columns (``COLUMNS``): their names, order, Result arrays, output
groups (``simulate --columns``), units and meanings. ``Result.to_frame`` and ``simulate`` build
their columns from it (``plan``); it gives the units that travel with the data
(``DataFrame.attrs["units"]``, the Parquet field metadata ``unit`` and ``description``),
``gsfric columns`` and the README's output table.

Legs are numbered 1..6 in column names (index 0..5 in arrays). Frames: "base" is the fixed
base frame. Sign conventions are stated per column; note that ``Ffr1..Ffr6``, ``MfrE1..``
and ``MfrC1..`` are the paper's scalars (never positive: negative = opposing the motion),
``Result.Ffr_s``, ``Result.MfrE_s`` and ``Result.MfrC_s``, while ``Result.Ffr`` is the signed
friction force along the leg and ``Result.MfrE`` / ``Result.MfrC`` are vectors.
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
    Column("MfrE{i}", "N m", "friction moment of spherical joint E_i, the paper's scalar of "
           "(33): <= 0, negative = opposing (Result.MfrE_s; the vector is Result.MfrE)",
           "friction", "MfrE_s"),
    Column("MfrC{i}", "N m", "friction moment of universal joint C_i, the paper's scalar of "
           "(34): <= 0, negative = opposing (Result.MfrC_s; the vector is Result.MfrC)",
           "friction", "MfrC_s"),
    Column("Ffr{i}", "N", "friction force of prismatic joint i, the paper's scalar of (35): "
           "<= 0, negative = opposing (Result.Ffr_s; the signed force along the leg is "
           "Result.Ffr)", "friction", "Ffr_s"),
    Column("RE{a}{i}", "N", "force of leg i on the platform at E_i, base frame "
           "components x, y, z (Result.R_E)", "reactions", "R_E"),
    Column("RC{a}{i}", "N", "force of the base on leg i at C_i, base frame "
           "components x, y, z (Result.R_C)", "reactions", "R_C"),
    Column("MC{i}", "N m", "constraint moment of universal joint i along its normal n_i "
           "(Result.M_C)", "reactions", "M_C"),
    Column("F0_{i}", "N", "actuator force of leg i with frictionless joints; + pushes the "
           "platform away (Result.F0)", "frictionless", "F0"),
    Column("D{i}", "m", "length of leg i, C_i to E_i (Result.D)", "lengths", "D"),
    Column("FfrS{i}", "N", "signed friction force of prismatic joint i on the rod along the "
           "leg direction u_i (C_i to E_i): negative while the leg extends, positive while it "
           "retracts (Result.Ffr)", "friction_detail", "Ffr"),
    Column("Fjoint{i}", "N", "part of F_i that carries the spherical and universal joints' "
           "friction moments (coupled model; zero in the paper's post-hoc model)",
           "friction_detail", "F_joint"),
    Column("MfrE{a}{i}", "N m", "friction moment vector of spherical joint E_i on the platform, "
           "opposing the platform's rotation relative to the leg; base frame components x, y, z "
           "(Result.MfrE)", "friction_detail", "MfrE"),
    Column("MfrC{a}{i}", "N m", "friction moment vector of universal joint C_i on the leg, "
           "opposing the leg's rotation relative to the base; base frame components x, y, z "
           "(Result.MfrC)", "friction_detail", "MfrC"),
    Column("flag", "1", "0 for a sound step; else the sum of 1 (non-finite value), 2 (leg "
           "length outside the stroke), 4 (near-singular platform Jacobian), 8 (leg near its "
           "universal joint's first axis), 16 (coupled friction solve not converged)", "flags"),
)
"""Every column of ``Result.to_frame``, in order."""

MEASURED: tuple[Column, ...] = (
    Column("F{i}_measured", "N", "actuator force of leg i as measured (the input's F1..F6, "
           "converted to N); simulate of a measured-data file only", "measured"),
    Column("F{i}_residual", "N", "measured minus model actuator force of leg i "
           "(Fi_measured - Fi); simulate of a measured-data file only", "measured"),
)
"""The columns ``simulate`` adds for an input with measured forces F1..F6."""


GROUPS = {
    "forces": "F1..F6: actuator forces with friction, N",
    "uncertainty": "sigma_F1..6 (N): one standard deviation of F from the differentiation; "
                   "rest: the legs possibly at rest (a motion differentiated from poses)",
    "friction": "MfrE1..6, MfrC1..6 (N m), Ffr1..6 (N): the paper's friction scalars "
                "(<= 0, negative = opposing)",
    "reactions": "REx1..REz6, RCx1..RCz6 (N), MC1..MC6 (N m): joint reactions",
    "friction_detail": "FfrS1..6, Fjoint1..6 (N), MfrEx1..MfrEz6, MfrCx1..MfrCz6 (N m): signed "
                       "prismatic friction, the joints' share of F, friction moment vectors",
    "frictionless": "F0_1..F0_6: actuator forces of frictionless joints, N",
    "lengths": "D1..D6: leg lengths, m",
}
"""Output groups of ``simulate --columns``; ``t`` and ``flag`` are always written."""

DEFAULT_GROUPS = ("forces", "uncertainty", "friction", "reactions")
"""The groups ``simulate`` writes unless ``--columns`` says otherwise: with ``t`` and ``flag``
(``t``, F, the paper's friction scalars, the joint reactions, the flag: ``len(plan(DEFAULT_GROUPS)) + 2``
values a step); every other group is one ``--columns`` away (``all``: every group)."""


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
