"""The paper's 40-step evaluation, set beside the paper's Tables 1-3.

This module evaluates and compares (the paper's tables as printed, the misprints in them, the
reactions their values imply, ``evaluate_paper``); ``gsfric.paper.report`` writes the results
(plots, ``report.md``, ``run_paper``).

``run_paper`` evaluates a platform (default ``gsfric.models.paper_platform()``) over the paper's
motion (``gsfric.models.paper_motion()``) and writes, into one directory:

* ``table1.csv``, ``table2.csv``, ``table3.csv``: our friction moments in the spherical joints
  E_i (``pos, MfrE1..MfrE6``, N m), in the universal joints C_i (``pos, MfrC1..MfrC6``, N m) and
  our friction forces in the prismatic joints (``pos, Ffr1..Ffr6``, N): the columns of the
  paper's tables, the paper's sign convention (negative = opposing), four significant digits;
* ``platform.toml``: the platform used;
* ``table1.png``, ``table2.png``, ``table3.png``: ours against the paper's, one panel per joint;
* ``report.md``: the comparison, the misprints found in the paper's tables, the reactions the
  paper's values imply, why ours differ, and the actuator forces (which the paper does not give).

The paper's tables are kept here as printed (``paper_table``), so that the comparison needs no
file besides the package; they are the transcription in ``paper/table*.csv`` of the project's
shared folder, whose Table 1 header reads ``MfrE`` where the paper misprints ``MfrC``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from gsfric import models
from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.paper_constants import PAPER_JOINT_SPEED
from gsfric.evaluation.result import Result
from gsfric.platform.description import Friction, Platform
from gsfric.trajectory import Motion

DATA = Path(__file__).resolve().parent.parent / "data"
"""The paper's Tables 1-3 as printed (copies of shared/paper/table*.csv, shipped with the package)."""

DIGITS = 4
"""Significant digits of the values in our tables."""

PAPER_FRICTION = Friction()
"""The paper's friction constants: c_s = 0.02 N m s/rad, mu = 0.04, r = 0.05 m (prismatic
joint: 0.02 N s/m and 0.04)."""

SMALL_FRACTION = 0.5
"""A printed value below this fraction of its table's 10th percentile (in magnitude) is a
misprint: an order of magnitude off the rest of the table."""

LARGE_FACTOR = 1.2
"""A printed value more than this factor above every other value of its table is a misprint."""

@dataclass(frozen=True)
class TableSpec:
    """One of the paper's tables.

    Attributes
    ----------
    number : int
        1, 2 or 3.
    prefix : str
        Column prefix: ``MfrE``, ``MfrC`` or ``Ffr`` (columns ``pos, {prefix}1..{prefix}6``).
    result : str
        The ``Result`` array with our values, (N, 6).
    reaction : str
        The ``Result`` array of the reaction in the friction law, (N, 6, 3), N.
    title : str
    unit : str
    """

    number: int
    prefix: str
    result: str
    reaction: str
    title: str
    unit: str

    @property
    def columns(self) -> list[str]:
        """``["pos", prefix1, ..., prefix6]``."""
        return ["pos"] + [f"{self.prefix}{i}" for i in range(1, 7)]


TABLES = {
    1: TableSpec(1, "MfrE", "MfrE_s", "R_E",
                 "friction moments in the spherical joints E_i (moving platform)", "N m"),
    2: TableSpec(2, "MfrC", "MfrC_s", "R_C",
                 "friction moments in the universal joints C_i (fixed platform)", "N m"),
    3: TableSpec(3, "Ffr", "Ffr_s", "R_3", "friction forces in the prismatic joints", "N"),
}


# -- numbers as the tables print them -------------------------------------------------------------


def format_significant(value: float, digits: int = DIGITS) -> str:
    """``value`` with ``digits`` significant digits, positional (``-0.04553``, ``-1.690``)."""
    return np.format_float_positional(float(value), precision=digits, unique=False,
                                      fractional=False, trim="k")


def round_significant(values, digits: int = DIGITS) -> np.ndarray:
    """``values`` rounded to ``digits`` significant digits, exactly as ``format_significant``.

    Parameters
    ----------
    values : array_like, any shape

    Returns
    -------
    ndarray, same shape
    """
    values = np.asarray(values, dtype=float)
    flat = [float(format_significant(v, digits)) for v in values.ravel()]
    return np.array(flat).reshape(values.shape)


# -- the paper's tables ---------------------------------------------------------------------------


def paper_table(number: int, printed: bool = False) -> pd.DataFrame:
    """One of the paper's Tables 1-3, columns ``pos`` and the six joints, 40 rows.

    Parameters
    ----------
    number : {1, 2, 3}
    printed : bool
        True: the values as printed strings (``"-0.1430"``), to count printed digits;
        False: floats, N m (Tables 1-2) or N (Table 3).
    """
    spec = TABLES[number]
    frame = pd.read_csv(DATA / f"paper_table{number}.csv", dtype=str)
    if list(frame.columns) != spec.columns:
        raise AssertionError(f"table {number}: columns {list(frame.columns)}")
    frame["pos"] = frame["pos"].astype(int)
    if not printed:
        frame[spec.columns[1:]] = frame[spec.columns[1:]].astype(float)
    return frame


@dataclass(frozen=True)
class Misprint:
    """A value of the paper's tables that cannot be what the authors computed, or is printed
    unlike its column.

    Attributes
    ----------
    table : int
    pos : int
        Step (row), 1..40.
    column : str
    printed : str
        The value as printed.
    kinds : tuple of str
        ``"small"`` (an order of magnitude below the rest of the table: a lost digit),
        ``"large"`` (above every other value of the table by more than 20 %),
        ``"digits"`` (more printed decimals than the rest of its column).
    reason : str
        One sentence with the numbers.
    likely : str or None
        The value that was probably meant, where one can be told.
    """

    table: int
    pos: int
    column: str
    printed: str
    kinds: tuple[str, ...]
    reason: str
    likely: str | None

    @property
    def value(self) -> float:
        return float(self.printed)

    @property
    def excluded(self) -> bool:
        """True when the value is left out of the comparison (``small`` or ``large``)."""
        return "small" in self.kinds or "large" in self.kinds


def _decimals(text: str) -> int:
    return len(text.split(".", 1)[1]) if "." in text else 0


def find_misprints(number: int, printed: pd.DataFrame | None = None) -> list[Misprint]:
    """The misprints of one of the paper's tables, row by row.

    A value is a misprint when its magnitude is below ``SMALL_FRACTION`` of its table's 10th
    percentile (``small``), when it exceeds every other value of its table by more than
    ``LARGE_FACTOR`` (``large``), or when it is printed with more decimals than most of its
    column (``digits``). The references are table-wide because a column's values cluster in
    two groups (about 0.04 and 0.12 N m in Tables 1-2): a column's median lies in either, and
    a rule against it would flag ordinary values of the lower group.

    Parameters
    ----------
    number : {1, 2, 3}
    printed : DataFrame, optional
        The table as printed strings (default ``paper_table(number, printed=True)``).

    Returns
    -------
    list of Misprint, in row order, then column order
    """
    spec = TABLES[number]
    if printed is None:
        printed = paper_table(number, printed=True)
    columns = spec.columns[1:]
    text = printed[columns].astype(str)
    magnitude = text.astype(float).abs().to_numpy()
    decimals = text.map(_decimals).to_numpy()
    low = np.percentile(magnitude, 10)
    usual = np.array([np.bincount(decimals[:, j]).argmax() for j in range(len(columns))])
    ordered = np.sort(magnitude.ravel())
    found = []
    for r in range(magnitude.shape[0]):
        for j, column in enumerate(columns):
            value, shown = magnitude[r, j], text.iat[r, j]
            others_max = ordered[-2] if value == ordered[-1] else ordered[-1]
            kinds, reasons, likely = [], [], None
            if value < SMALL_FRACTION * low:
                kinds.append("small")
                likely = f"{-10 * value:.{usual[j]}f}"
                reasons.append(f"{value:g} is {low / value:.1f} times below the table's 10th "
                               f"percentile {low:.3g}: a digit lost ({likely} is a usual value)")
            if value > LARGE_FACTOR * others_max:
                kinds.append("large")
                reasons.append(f"{value:g} is {value / others_max:.2f} times the largest other "
                               f"value of the table, {others_max:g}")
            if decimals[r, j] > usual[j]:
                kinds.append("digits")
                reasons.append(f"printed with {decimals[r, j]} decimals where its column has "
                               f"{usual[j]}")
                if likely is None and "large" not in kinds:
                    likely = f"{-value:.{usual[j]}f}"
            if kinds:
                found.append(Misprint(number, int(printed["pos"].iat[r]), column, shown,
                                      tuple(kinds), "; ".join(reasons), likely))
    return found


# -- what the paper's values imply ---------------------------------------------------------------


def implied_joint_reaction(moment, speed=PAPER_JOINT_SPEED,
                           viscous=PAPER_FRICTION.joint_viscous,
                           coulomb=PAPER_FRICTION.joint_coulomb,
                           radius=PAPER_FRICTION.joint_radius) -> np.ndarray:
    """The reaction magnitude that a friction moment implies, inverting (33)-(34).

    ``|R| = (|M| - c_s |omega|) / (mu r)``; negative where ``|M|`` is below the viscous part
    alone (no reaction can explain it).

    Parameters
    ----------
    moment : array_like, any shape
        Friction moments, N m (either sign).
    speed : float or array_like broadcastable to ``moment``
        Joint speed omega, rad/s (paper: 0.02).
    viscous, coulomb, radius : float
        c_s (N m s/rad), mu, r (m); the paper's by default.

    Returns
    -------
    ndarray, shape of ``moment``, N
    """
    return (np.abs(moment) - viscous * np.abs(speed)) / (coulomb * radius)


def implied_prismatic_reaction(force, speed, viscous=PAPER_FRICTION.prismatic_viscous,
                               coulomb=PAPER_FRICTION.prismatic_coulomb) -> np.ndarray:
    """The transverse force that a prismatic friction force implies, inverting (35).

    ``|R_3| = (|F_fr| - c |v|) / mu``.

    Parameters
    ----------
    force : array_like, any shape
        Friction forces, N (either sign).
    speed : array_like broadcastable to ``force``
        Sliding speeds v, m/s.
    viscous, coulomb : float
        c (N s/m) and mu; the paper's by default.

    Returns
    -------
    ndarray, shape of ``force``, N
    """
    return (np.abs(force) - viscous * np.abs(speed)) / coulomb


# -- the evaluation -------------------------------------------------------------------------------


@dataclass
class PaperRun:
    """Our evaluation of the paper's motion with the paper's tables beside it.

    Attributes
    ----------
    platform : Platform
    motion : Motion
        40 steps.
    result : Result
    mode : {"paper", "kinematic"}
    ours : dict[int, DataFrame]
        Our Tables 1-3 (columns of the paper's, values rounded as written), 40 rows.
    paper : dict[int, DataFrame]
        The paper's Tables 1-3 (floats).
    misprints : dict[int, list[Misprint]]
    """

    platform: Platform
    motion: Motion
    result: Result
    mode: str
    ours: dict[int, pd.DataFrame]
    paper: dict[int, pd.DataFrame]
    misprints: dict[int, list[Misprint]]

    def paper_values(self, number: int) -> np.ndarray:
        """The paper's values of a table, (40, 6), NaN where a misprint is left out."""
        spec = TABLES[number]
        values = self.paper[number][spec.columns[1:]].to_numpy(dtype=float).copy()
        for m in self.misprints[number]:
            if m.excluded:
                values[m.pos - 1, spec.columns.index(m.column) - 1] = np.nan
        return values

    def our_values(self, number: int) -> np.ndarray:
        """Our values of a table as written, (N, 6)."""
        return self.ours[number][TABLES[number].columns[1:]].to_numpy(dtype=float)

    def summary(self, number: int) -> pd.DataFrame:
        """Per column: min, median, max of |ours| and |paper| and the ratio of the medians.

        Magnitudes (every value is negative); the paper's misprints of kind ``small`` or
        ``large`` are left out. Index: the column names and ``all``.
        """
        ours, paper = np.abs(self.our_values(number)), np.abs(self.paper_values(number))
        rows = {}
        for j, column in enumerate(TABLES[number].columns[1:] + ["all"]):
            o = ours.ravel() if column == "all" else ours[:, j]
            p = paper.ravel() if column == "all" else paper[:, j]
            rows[column] = dict(ours_min=np.min(o), ours_median=np.median(o),
                                ours_max=np.max(o), paper_min=np.nanmin(p),
                                paper_median=np.nanmedian(p), paper_max=np.nanmax(p),
                                ratio=np.median(o) / np.nanmedian(p))
        return pd.DataFrame.from_dict(rows, orient="index")

    def implied_reaction(self, number: int) -> np.ndarray:
        """The reaction magnitudes the paper's values imply, (40, 6), N; NaN at misprints.

        Tables 1-2: ``implied_joint_reaction`` with the paper's joint speed 0.02 rad/s;
        Table 3: ``implied_prismatic_reaction`` with our sliding speeds.
        """
        values = self.paper_values(number)
        if number == 3:
            return implied_prismatic_reaction(values, self.result.D_dot)
        return implied_joint_reaction(values)

    def reaction(self, name: str) -> np.ndarray:
        """|R| of one of our reactions (``R_E``, ``R_C``, ``R_3``), (N, 6), N."""
        return np.linalg.norm(getattr(self.result, name), axis=2)

    def prismatic_friction_with(self, name: str) -> np.ndarray:
        """|F_fr| of (35) with our |``name``| in place of |R_3|, (N, 6), N."""
        fr = self.platform.friction
        return fr.prismatic_viscous * np.abs(self.result.D_dot) \
            + fr.prismatic_coulomb * self.reaction(name)


def _evaluate(platform: Platform, motion: Motion, mode: str) -> tuple[Result, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = Evaluator(platform, mode=mode).evaluate(motion)
    return result, [str(w.message) for w in caught]


def our_table(result: Result, number: int) -> pd.DataFrame:
    """Our values of Table ``number`` with the paper's columns, rounded to ``DIGITS``.

    Returns
    -------
    DataFrame, columns ``pos`` (1..N) and the six joints, N rows
    """
    spec = TABLES[number]
    values = round_significant(getattr(result, spec.result))
    frame = pd.DataFrame(values, columns=spec.columns[1:])
    frame.insert(0, "pos", np.arange(1, len(frame) + 1))
    return frame


def evaluate_paper(platform: Platform | None = None, mode: str = "paper") -> PaperRun:
    """Evaluate ``platform`` (default ``paper_platform()``) over the paper's 40-step motion.

    Parameters
    ----------
    platform : Platform, optional
    mode : {"paper", "kinematic"}
        See ``gsfric.evaluation.Evaluator``.
    """
    platform = models.paper_platform() if platform is None else platform
    motion = models.paper_motion()
    result, notes = _evaluate(platform, motion, mode)
    result.notes.extend(notes)
    return PaperRun(platform=platform, motion=motion, result=result, mode=mode,
                    ours={n: our_table(result, n) for n in TABLES},
                    paper={n: paper_table(n) for n in TABLES},
                    misprints={n: find_misprints(n) for n in TABLES})


def geometry_sensitivity(platform: Platform, mode: str = "paper") -> pd.DataFrame:
    """How much our tables move when the unknown dimensions or the leg masses change.

    Variants of ``platform`` on the paper's motion: base joints and platform joints 20 % farther
    from the centre, the motion started 0.1 m higher, the lower leg part twice as heavy.

    Returns
    -------
    DataFrame, one row per variant: medians of |MfrE|, |MfrC|, |Ffr| (N m, N m, N) and of |R_3|
    (N) over all joints and steps
    """
    g = platform.geometry
    radial = np.array([1.2, 1.2, 1.0])
    t = models.paper_motion().t
    start = np.array([0.0, 0.0, models.HOME_HEIGHT])
    variants = [
        ("as used", platform, models.paper_motion()),
        ("base joints 20 % farther out",
         platform.with_geometry(base_joints=g.base_joints * radial), models.paper_motion()),
        ("platform joints 20 % farther out",
         platform.with_geometry(platform_joints=g.platform_joints * radial),
         models.paper_motion()),
        ("motion started 0.1 m higher", platform,
         models.constant_acceleration(t, start=start + [0.0, 0.0, 0.1])),
        ("lower leg part twice as heavy",
         platform.with_legs(lower_mass=2 * platform.legs.lower_mass), models.paper_motion()),
    ]
    rows = {}
    for name, variant, motion in variants:
        result, _ = _evaluate(variant, motion, mode)
        rows[name] = {"|MfrE|": np.median(np.abs(result.MfrE_s)),
                      "|MfrC|": np.median(np.abs(result.MfrC_s)),
                      "|Ffr|": np.median(np.abs(result.Ffr_s)),
                      "|R_3|": np.median(np.linalg.norm(result.R_3, axis=2))}
    return pd.DataFrame.from_dict(rows, orient="index")
