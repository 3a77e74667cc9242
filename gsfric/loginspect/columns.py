"""The column map of a log: which columns are the time, the pose, the log's own rates and the
forces, in which units, each with its evidence (``Assumption``).

Names come first (``gsfric.loginspect.names``), values check them and fill in what the names
leave open (``gsfric.loginspect.values``). Bad input is an ``InputError`` in one line naming
the file and the column or row.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gsfric._checks import suggest
from gsfric.errors import InputError
from gsfric.io.logs import RATES, UNITS
from gsfric.loginspect import values as V
from gsfric.loginspect.names import AXIS_WORDS, Role, role
from gsfric.loginspect.names import RATE_QUANTITY as QUANTITY_RATE
from gsfric.signal.rotations import MIN_QUATERNION_LENGTH, unit_quaternions
from gsfric.trajectory import MAX_POSITION

NUMERIC_SHARE = 0.9
"""A text column is read as numbers with a bad row (and that row named) when at least this
share of its values are numbers: one corrupt line in a numeric column, not a text column."""

SI = frozenset(unit for units in UNITS.values() for unit, factor in units.items()
               if factor == 1.0)
"""The units a log format need not list (``gsfric.io.logs.UNITS``' factor 1)."""

RATE_QUANTITY = {kind: quantity for quantity, kind in QUANTITY_RATE.items()}
"""The quantity (``gsfric.io.logs.UNITS``) of each kind of rate."""


@dataclass(frozen=True)
class Assumption:
    """One thing the inspection assumed.

    Attributes
    ----------
    topic : str
        What it is about ("time", "position", "frame", ...).
    value : str
        What was assumed.
    evidence : str
        Why: the names or values it rests on.
    """

    topic: str
    value: str
    evidence: str

    def line(self) -> str:
        """One line: ``topic: value (evidence)``."""
        return f"{self.topic}: {self.value} ({self.evidence})"


@dataclass
class ColumnMap:
    """A log's columns as gsfric's, being built.

    Attributes
    ----------
    columns : dict of str to str
        gsfric name -> the log's column.
    units : dict of str to str
        gsfric name -> the unit of the log's column (``gsfric.io.logs.UNITS``).
    assumptions : list of Assumption
    used : set of str
        The log's columns mapped.
    """

    columns: dict[str, str] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    assumptions: list[Assumption] = field(default_factory=list)
    used: set[str] = field(default_factory=set)

    def add(self, key: str, column: str, unit: str | None) -> None:
        """Map gsfric's ``key`` to the log's ``column`` in ``unit`` (listed unless SI)."""
        self.columns[key] = column
        self.used.add(column)
        if unit is not None and unit not in SI:
            self.units[key] = unit

    def assume(self, topic: str, value: str, evidence: str) -> None:
        """Record an ``Assumption``."""
        self.assumptions.append(Assumption(topic, value, evidence))


def numeric_frame(path: Path, frame: pd.DataFrame) -> dict[str, np.ndarray]:
    """The numeric columns of a log (name -> (N,) array, integers kept as integers).

    Raises ``InputError`` for a log without rows or without a numeric column, and for a
    column of numbers with a value that is not one (naming its row)."""
    if frame.shape[0] == 0:
        raise InputError(f"{path}: no data rows (only the header line)")
    out = {}
    for name in frame.columns:
        column = frame[name]
        if column.dtype.kind in "iuf":
            out[name] = column.to_numpy()
            continue
        if column.dtype.kind == "b":
            continue
        numbers = pd.to_numeric(column, errors="coerce")
        bad = numbers.isna() & column.notna()
        if bad.any() and (~bad).mean() >= NUMERIC_SHARE:
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise InputError(f"{path}: row {row + 1}: column {name!r} holds "
                             f"{str(column.iloc[row])[:30]!r}, not a number")
    if not out:
        raise InputError(f"{path}: no numeric column (columns "
                         f"{', '.join(repr(c) for c in list(frame.columns)[:6])} hold text)")
    if frame.shape[0] < V.MIN_ROWS:
        raise InputError(f"{path}: {frame.shape[0]} data rows; at least {V.MIN_ROWS} are "
                         "needed to tell a motion from its rates")
    return out


def time_column(path: Path, data: dict[str, np.ndarray], roles: Mapping[str, Role],
                given: str | None, cmap: ColumnMap) -> V.Clock:
    """The time column, read as a ``Clock``, mapped to ``t`` with its assumptions. Dropout
    rows (``_drop``) are taken out of ``data``."""
    if given is not None:
        if given not in data:
            raise InputError(f"--time: no numeric column {given!r}{suggest(given, list(data))}")
        name, how = given, "given with --time"
    else:
        named = [n for n in data if roles[n].kind == "time"]
        clocks = [n for n in named if V.looks_like_clock(data[n])] or named[:1]
        if not clocks:
            clocks = [n for n in data if roles[n].kind == "" and V.looks_like_clock(data[n])
                      and data[n].dtype.kind in "iu"]
            how = "no time-like name; it is the integer column that counts up"
        else:
            how = "its name, and it counts up"
        if not clocks:
            what = (f"column {named[0]!r} does not count up" if named
                    else "no column is named like a time (time, timestamp, t, ...) or counts up")
            raise InputError(f"{path}: no time-like column: {what}; name it with --time COLUMN")
        name = clocks[0]
    _drop(data, name, cmap)
    empty = np.flatnonzero(~np.isfinite(data[name].astype(float)))
    if len(empty):
        raise InputError(f"{path}: row {int(empty[0]) + 1}: column {name!r} is empty or NaN")
    if not np.median(np.diff(data[name].astype(float))) > 0:
        raise InputError(f"{path}: column {name!r}: does not count up, not a time")
    unit = roles[name].unit if roles[name].unit in UNITS["time"] else None  # F1's "1": no time
    clock = V.read_clock(data[name], unit)
    if clock.resets:
        row = clock.resets[0]
        before, after = data[name][row - 1], data[name][row]
        raise InputError(f"{path}: row {row + 1}: column {name!r} goes from {before} to {after}, "
                         "back or not at all and not the wrap of a counter (a reset? rows out "
                         "of order?); split the log there")
    cmap.add("t", name, clock.unit)
    cmap.assume("time", f"{name!r} in {clock.unit}", f"{how}; unit from {clock.unit_evidence}")
    cmap.assume("rate", f"{1.0 / clock.step:.4g} Hz",
                f"median step {clock.step * 1e3:.4g} ms; " + (
                    f"the stamps jitter by up to {100 * clock.jitter:.2g} % of it"
                    if clock.jitter > V.EVEN_STAMPS else "evenly spaced stamps"))
    if clock.wrap is not None:
        cmap.assume("wrap", f"the counter wraps at {clock.wrap}", clock.wrap_evidence)
    return clock


def _drop(data: dict[str, np.ndarray], time: str, cmap: ColumnMap) -> None:
    """Take out of ``data`` the rows whose every value but the time is 0 and whose time does
    not advance: a controller's dropout rows, which gsfric's reader leaves out too."""
    t = data[time].astype(float)
    others = [v for k, v in data.items() if k != time]
    if not others:
        return
    zero = np.all(np.stack(others, axis=1) == 0, axis=1)
    zero[1:] &= ~(t[1:] > t[:-1])
    zero[0] = False
    if not zero.any():
        return
    rows = np.flatnonzero(zero)
    for key in data:
        data[key] = data[key][~zero]
    shown = ", ".join(str(int(r) + 1) for r in rows[:5])
    cmap.assume("dropout", f"row {shown} left out",
                "every value but the time is 0 and the time stops; gsfric's reader leaves "
                "such rows out too")


def group(data: Mapping[str, np.ndarray], roles: Mapping[str, Role], kind: str
          ) -> dict[str, str] | None:
    """gsfric name -> column of the one complete set of pose columns of ``kind``, or None."""
    names = AXIS_WORDS[kind]
    found: dict[str, str] = {}
    for column in data:
        r = roles[column]
        if r.kind == kind and r.axis in names and r.axis not in found:
            found[r.axis] = column
    return found if len(found) == len(names) else None


def pose_units(path: Path, data, roles, columns: dict[str, str], kind: str,
               cmap: ColumnMap, mm_reach: float = V.MM_REACH) -> tuple[np.ndarray, str]:
    """The pose columns (N, k) in SI and their unit (from the names, or the values: positions
    beyond ``mm_reach`` are mm, ``values.length_unit``)."""
    raw = np.stack([data[c].astype(float) for c in columns.values()], axis=1)
    if not np.isfinite(raw).all():
        row, k = np.argwhere(~np.isfinite(raw))[0]
        raise InputError(f"{path}: row {row + 1}: column {list(columns.values())[k]!r} is "
                         f"{'empty or NaN' if np.isnan(raw[row, k]) else 'infinite'}")
    named = {roles[c].unit for c in columns.values()}
    shown = ", ".join(f"{k} = {c!r}" for k, c in columns.items())
    if kind == "quaternion":
        zero = np.flatnonzero(unit_quaternions(raw)[1] < MIN_QUATERNION_LENGTH)
        if len(zero):
            raise InputError(f"{path}: row {zero[0] + 1}: quaternion of zero length "
                             f"({', '.join(map(repr, columns.values()))})")
        for key, column in columns.items():
            cmap.add(key, column, None)
        cmap.assume("orientation", f"{shown}, a quaternion (w first)", "the columns' names")
        return raw, "1"
    if len(named) == 1 and None not in named:
        unit = named.pop()
        evidence = "the columns' names"
        if kind == "position" and unit not in UNITS["length"] or \
                kind != "position" and unit not in UNITS["angle"]:
            first = next(iter(columns.values()))
            raise InputError(f"{path}: column {first!r}: unit {unit!r} "
                             "is not a " + ("length" if kind == "position" else "an angle"))
    elif kind == "position":
        unit, evidence = V.length_unit(raw, mm_reach)
    else:
        unit, evidence = V.angle_unit(raw)
    factor = UNITS["length" if kind == "position" else "angle"][unit]
    if kind == "position" and np.abs(raw * factor).max() > MAX_POSITION:
        row, k = np.argwhere(np.abs(raw * factor) > MAX_POSITION)[0]
        raise InputError(f"{path}: row {row + 1}: column {list(columns.values())[k]!r} = "
                         f"{raw[row, k]:.4g} {unit}, farther than {MAX_POSITION:g} m from the "
                         "origin: no hexapod reaches it (a glitch, or another unit?)")
    cmap.assume(kind if kind != "angle" else "orientation", f"{shown} in {unit}", evidence)
    for key, column in columns.items():
        cmap.add(key, column, unit)
    return raw * factor, unit


def rate_columns(data, roles, reference: Mapping[str, np.ndarray], cmap: ColumnMap) -> None:
    """Map each complete group of the log's own rates whose every column matches the
    derivative of the poses (``values.match_rate``). ``reference``: the poses' velocity,
    acceleration, omega and alpha (N, 3 each, SI units, the log's frame), by ``RATES`` kind."""
    for kind, keys in RATES.items():
        found = {r.axis: c for c, r in roles.items() if r.kind == kind and c in data}
        if not found:
            continue
        if set(found) != {"x", "y", "z"}:
            cmap.assume(kind, "not mapped: " + ", ".join(map(repr, found.values())),
                        f"only {', '.join(sorted(found))} found; gsfric differentiates the "
                        "poses")
            continue
        _rate_group(data, roles, kind, keys, found, reference[kind], cmap)


def _rate_group(data, roles, kind, keys, found, reference, cmap: ColumnMap) -> None:
    matches = {axis: V.match_rate(data[found[axis]].astype(float), reference[:, k],
                                  RATE_QUANTITY[kind])
               for k, axis in enumerate("xyz")}
    what = {"velocity": "the differentiated position", "acceleration": "the position's "
            "second derivative", "omega": "the angular velocity of the angles",
            "alpha": "the derivative of that angular velocity"}[kind]
    evidence = "; ".join(f"{found[a]!r} correlation {m.correlation:.3f}, ratio {m.ratio:.4g}"
                         for a, m in matches.items())
    units = {m.unit for m in matches.values()}
    if None in units or len(units) > 1:
        cmap.assume(kind, "not mapped: " + ", ".join(map(repr, found.values())),
                    f"they do not match {what}: {evidence}; gsfric differentiates the "
                    "poses")
        return
    unit = units.pop()
    named = {roles[c].unit for c in found.values()} - {None}
    note = f"; the names say {named.pop()}" if named and named != {unit} else ""
    for key, axis in zip(keys, "xyz"):
        cmap.add(key, found[axis], unit)
    shown = ", ".join(f"{k} = {found[a]!r}" for k, a in zip(keys, "xyz"))
    cmap.assume(kind, f"{shown} in {unit}, the log's own, used instead of differentiating",
                f"against {what} in SI units: {evidence}{note}")


def force_columns(data, roles, cmap: ColumnMap) -> None:
    """F1..F6: six columns named as forces of legs 1..6 (N unless the names say kN)."""
    found = {r.axis: c for c, r in roles.items() if r.kind == "force" and c in data}
    if set(found) != set("123456"):
        return
    units = {roles[c].unit for c in found.values()}
    unit = units.pop() if len(units) == 1 and None not in units else "N"
    for leg in "123456":
        cmap.add(f"F{leg}", found[leg], unit)
    cmap.assume("forces", f"F1..F6 = {found['1']!r} .. {found['6']!r} in {unit}",
                "names of legs 1..6 with a force word or unit; measured forces: simulate "
                "writes the residuals, discover compares")


def roles_of(data: Mapping[str, np.ndarray]) -> dict[str, Role]:
    """The ``Role`` of each numeric column's name."""
    return {name: role(name) for name in data}
