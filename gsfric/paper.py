"""The paper's 40-step evaluation, set beside the paper's Tables 1-3.

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

import io
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from gsfric import models
from gsfric.errors import InputError
from gsfric.evaluation import Evaluator, Result
from gsfric.io import atomic_write
from gsfric.platform import Friction, Platform
from gsfric.trajectory import Motion

DATA = Path(__file__).resolve().parent / "data"
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


def implied_joint_reaction(moment, speed=models.PAPER_JOINT_SPEED,
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


# -- plots ----------------------------------------------------------------------------------------


def plot_table(run: PaperRun, number: int):
    """Ours against the paper's for one table: |value| against the step, one panel per joint.

    Log scale, so that values an order of magnitude apart and the misprints (red crosses) show.
    For Table 3 a dashed line shows (35) with our |R_E| in place of |R_3|.

    Returns
    -------
    matplotlib.figure.Figure (Agg canvas; no pyplot state)
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    spec = TABLES[number]
    ours = np.abs(run.our_values(number))
    paper = np.abs(run.paper[number][spec.columns[1:]].to_numpy(dtype=float))
    steps = np.arange(1, len(ours) + 1)
    alternative = run.prismatic_friction_with("R_E") if number == 3 else None
    fig = Figure(figsize=(11, 6.5))
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.16, top=0.9, wspace=0.08, hspace=0.2)
    axes = fig.subplots(2, 3, sharex=True, sharey=True)
    for j, ax in enumerate(axes.flat):
        column = spec.columns[j + 1]
        ax.semilogy(steps, ours[:, j], "-", color="C0", label=f"ours ({run.mode} mode)")
        ax.semilogy(np.arange(1, len(paper) + 1), paper[:, j], "o-", color="C1", ms=3, lw=0.6,
                    label="paper")
        if alternative is not None:
            ax.semilogy(steps, alternative[:, j], "--", color="C2",
                        label="ours with |R_E| in place of |R_3|")
        bad = [m for m in run.misprints[number] if m.column == column]
        if bad:
            ax.semilogy([m.pos for m in bad], [abs(m.value) for m in bad], "x", color="red",
                        ms=9, mew=2, label="misprint")
        ax.set_title(column)
        ax.grid(True, alpha=0.3)
    handles = {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    fig.legend(list(handles.values()), list(handles), loc="lower center", ncol=len(handles),
               frameon=False)
    fig.supxlabel("step", y=0.07)
    fig.supylabel(f"|{spec.prefix}| ({spec.unit}), log scale")
    fig.suptitle(f"Table {number}: {spec.title}")
    return fig


def figure_png(fig) -> bytes:
    """A figure as PNG bytes."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    return buffer.getvalue()


# -- the report -----------------------------------------------------------------------------------


def _n(x: float, digits: int = 3) -> str:
    if not np.isfinite(x):
        return "-"
    return np.format_float_positional(float(x), precision=digits, unique=True,
                                      fractional=False, trim="-")


def _markdown_table(header: list[str], rows: list[list[str]]) -> str:
    def cells(row):
        return "| " + " | ".join(str(c).replace("|", "\\|") for c in row) + " |"

    lines = [cells(header), "|" + "---|" * len(header)] + [cells(row) for row in rows]
    return "\n".join(lines)


def _stats(x: np.ndarray) -> str:
    x = np.asarray(x, float).ravel()
    x = x[np.isfinite(x)]
    return f"{_n(x.min())} / {_n(np.median(x))} / {_n(x.max())}"


def _jumps(values: np.ndarray) -> tuple[int, int, float]:
    """Step-to-step changes larger than half the column's median magnitude: count, pairs, max."""
    v = np.abs(values)
    change = np.abs(np.diff(v, axis=0))
    relative = change / np.nanmedian(v, axis=0)
    finite = np.isfinite(relative)
    return int(np.sum(relative[finite] > 0.5)), int(finite.sum()), float(np.nanmax(relative))


def report_text(run: PaperRun, sensitivity: pd.DataFrame | None = None,
                files: list[str] | None = None, source: str | None = None) -> str:
    """The Markdown report of a ``PaperRun``.

    Parameters
    ----------
    run : PaperRun
    sensitivity : DataFrame, optional
        ``geometry_sensitivity(run.platform, run.mode)``; computed when not given.
    files : list of str, optional
        Names of the files written beside the report (plots are linked).
    source : str, optional
        Where the platform came from (a file name); default the built-in paper platform.
    """
    if sensitivity is None:
        sensitivity = geometry_sensitivity(run.platform, run.mode)
    files = files or []
    res = run.result
    n = len(res)
    mode_text = {
        "paper": ("paper mode: the paper's constant accelerations of platform and leg parts, no "
                  "gyroscopic terms, joint speed 0.02 rad/s in (33)-(34); positions and sliding "
                  "speeds from the motion"),
        "kinematic": "kinematic mode: every velocity and acceleration from the motion itself",
    }[run.mode]
    out = [
        "# The paper's Tables 1-3, reproduced",
        "",
        f"- Platform: {source or 'the built-in paper platform (`gsfric.models.paper_platform()`)'}"
        ", written to `platform.toml`. The paper's dimensions (its figures 6-7) are missing, so "
        "the geometry is the project's reference geometry (docs/reference.md).",
        f"- Motion: {n} steps from rest at the home pose with constant accelerations "
        f"a = {models.PAPER_ACCELERATION} m/s^2, alpha = {models.PAPER_ANGULAR_ACCELERATION} "
        f"rad/s^2, t_j = {models.PAPER_DT} j s.",
        f"- Mode: {mode_text}.",
        f"- Flagged steps: {len(res.flagged())} of {n}.",
        "- Every value of every table is negative (friction opposes the motion); the "
        "comparisons below are of magnitudes, with the paper's misprints left out.",
        "",
        "## Summary",
        "",
    ]
    rows = []
    for number, spec in TABLES.items():
        s = run.summary(number).loc["all"]
        rows.append([f"Table {number}", f"|{spec.prefix}| ({spec.unit})", _n(s.ours_median),
                     _n(s.paper_median), _n(s.ratio)])
    out += [_markdown_table(["table", "quantity", "ours, median", "paper, median",
                             "ratio ours/paper"], rows), ""]
    out += _summary_text(run, sensitivity)

    for number, spec in TABLES.items():
        out += [f"## Table {number}: {spec.title} ({spec.unit})", ""]
        rows = [[c, _n(r.ours_min), _n(r.ours_median), _n(r.ours_max), _n(r.paper_min),
                 _n(r.paper_median), _n(r.paper_max), _n(r.ratio)]
                for c, r in run.summary(number).iterrows()]
        out += [_markdown_table(["column", "ours min", "ours median", "ours max", "paper min",
                                 "paper median", "paper max", "ratio of medians"], rows), ""]
        if f"table{number}.png" in files:
            out += [f"![Table {number}: ours against the paper's](table{number}.png)", ""]

    out += _misprint_section(run)
    out += _implied_section(run)
    out += _why_section(run, sensitivity)

    out += ["## Actuator forces (not in the paper)", "",
            "F: the axial force of each actuator, friction included, positive pushing the "
            "platform away from the base; F0: the same with frictionless joints.", ""]
    rows = [[f"leg {i + 1}", _n(res.F[:, i].min()), _n(res.F[:, i].max()),
             _n(res.F0[:, i].min()), _n(res.F0[:, i].max())] for i in range(6)]
    out += [_markdown_table(["leg", "F min (N)", "F max (N)", "F0 min (N)", "F0 max (N)"],
                            rows), ""]
    if files:
        out += ["## Files", ""] + [f"- `{f}`" for f in files] + [""]
    return "\n".join(out)


def _geometry_spread(sensitivity: pd.DataFrame) -> float:
    """Largest relative change of the friction medians over the geometry variants."""
    geometric = [name for name in sensitivity.index[1:] if "leg" not in name]
    cols = ["|MfrE|", "|MfrC|"]
    ratio = sensitivity.loc[geometric, cols] / sensitivity.iloc[0][cols]
    return float(np.abs(ratio.to_numpy() - 1).max())


def _summary_text(run: PaperRun, sensitivity: pd.DataFrame) -> list[str]:
    ratio = {k: run.summary(k).loc["all", "ratio"] for k in TABLES}
    return [
        f"Tables 1-2: our friction moments are of the paper's size (medians {_n(ratio[1], 2)} "
        f"and {_n(ratio[2], 2)} of the paper's) but not equal to it: the geometry is not the "
        f"paper's (changing it by 20 % moves our medians by up to "
        f"{_geometry_spread(sensitivity):.0%}), and the paper's values jump from step to step "
        "as no smooth motion can make them. Table 3: ours are about "
        f"{_n(1 / ratio[3], 2)} times smaller. Our (35) uses the transverse force R_3 of the "
        "paper's (28)-(29), which is small; the paper's values imply a force of the size of the "
        "whole joint force. Details and numbers below.",
        "",
    ]


def _misprint_section(run: PaperRun) -> list[str]:
    out = ["## Misprints in the paper's tables", "",
           f"Found by rule (`gsfric.paper.find_misprints`): a magnitude below "
           f"{SMALL_FRACTION:g} times its table's 10th percentile (a lost digit), above every "
           f"other value of its table by more than {LARGE_FACTOR - 1:.0%}, or more printed "
           "decimals than the rest of its column. Values of the first two kinds are left out of "
           "every comparison; the third kind is a printing slip, and its value is kept. The "
           "references are table-wide: a joint's values cluster around two levels (about 0.04 "
           "and 0.12 N m in Tables 1-2), so a column's median is no reference for its lower "
           "values. Besides these, the paper's Table 1 header reads MfrC where it means MfrE.",
           ""]
    rows = []
    for number in TABLES:
        for m in run.misprints[number]:
            rows.append([f"Table {number}", str(m.pos), m.column, m.printed,
                         ", ".join(m.kinds), m.likely or "?",
                         "left out" if m.excluded else "kept", m.reason])
    out += [_markdown_table(["table", "step", "column", "printed", "kind", "probably",
                             "here", "why"], rows), ""]
    return out


def _implied_section(run: PaperRun) -> list[str]:
    fr = PAPER_FRICTION
    w = models.PAPER_JOINT_SPEED
    weight = (run.platform.platform.mass + run.platform.platform.payload_mass) \
        * run.platform.gravity
    implied = {k: run.implied_reaction(k) for k in TABLES}
    r3, r_e = run.reaction("R_3"), run.reaction("R_E")
    with_r_e = run.prismatic_friction_with("R_E")
    joints = np.concatenate([implied[1], implied[2]])
    factor = np.nanmedian(implied[1]) / np.median(r_e)
    high = np.mean(implied[1][np.isfinite(implied[1])] > 45.0)
    high_ours = np.mean(r_e > 45.0)
    legs = run.platform.legs
    bound = max(legs.lower_mass, legs.upper_mass) * run.platform.gravity
    leg_weight = (legs.lower_mass + legs.upper_mass) * run.platform.gravity
    inertial = (legs.lower_mass + legs.upper_mass) \
        * np.linalg.norm(models.PAPER_LEG_ACCELERATION)
    tolerance = fr.joint_coulomb * fr.joint_radius * inertial
    gap = np.abs(np.abs(run.paper_values(2)) - np.abs(run.paper_values(1)))
    disagree = np.mean(gap[np.isfinite(gap)] > tolerance)
    ours_gap = np.abs(run.our_values(2)) - np.abs(run.our_values(1))
    out = ["## What the paper's values imply", "",
           "Inverting (33)-(34) with the paper's constants gives the reaction magnitude that "
           f"each friction moment implies: |R| = (|M| - c_s omega) / (mu r) = (|M| - "
           f"{_n(fr.joint_viscous * w)} N m) / {_n(fr.joint_coulomb * fr.joint_radius)} m "
           f"(c_s = {fr.joint_viscous} N m s/rad, omega = {w} rad/s, mu = {fr.joint_coulomb}, "
           f"r = {fr.joint_radius} m). Inverting (35): |R_3| = (|F_fr| - c v) / mu with "
           f"c = {fr.prismatic_viscous} N s/m, mu = {fr.prismatic_coulomb} and our sliding "
           "speeds v (the paper gives none; c v is below "
           f"{_n(fr.prismatic_viscous * np.abs(run.result.D_dot).max())} N).", ""]
    kinds = {1: "spherical joint", 2: "universal joint", 3: "prismatic joint, transverse"}
    rows = [[f"Table {k}", f"|{spec.reaction}| ({kinds[k]})", _stats(implied[k]),
             _stats(run.reaction(spec.reaction))] for k, spec in TABLES.items()]
    rows += [["", "our |R_E|, for scale", "", _stats(r_e)],
             ["", "our |F| (actuator force), for scale", "", _stats(np.abs(run.result.F))]]
    out += [_markdown_table(["from", "reaction (N)", "implied by the paper: min / median / max",
                             "ours: min / median / max"], rows), ""]
    out += [
        f"- Tables 1-2 imply joint forces of {_n(np.nanmin(joints), 2)}-"
        f"{_n(np.nanmax(joints), 2)} N, the size of ours ({_n(r_e.min(), 2)}-"
        f"{_n(run.reaction('R_C').max(), 2)} N); the platform and payload weigh {_n(weight)} N, "
        f"{_n(weight / 6)} N a leg. The paper's median is {_n(factor, 2)} times ours for |R_E|: "
        f"{high:.0%} of Table 1 implies more than 45 N, against {high_ours:.0%} of ours.",
        f"- Tables 1 and 2 contradict each other. The paper's (11)-(13) leave out the legs' "
        f"weight, so there R_C and R_E differ only by the leg parts' inertial forces, "
        f"{_n(inertial, 2)} N with its leg accelerations, and (33)-(34) with one joint speed "
        f"make |MfrC| and |MfrE| agree to {_n(tolerance, 2)} N m. They differ by more at "
        f"{disagree:.0%} of the cells (median difference {_n(np.nanmedian(gap), 2)} N m). In "
        f"our model the legs' weight ({_n(leg_weight, 2)} N) sets the two apart: |MfrC| - |MfrE| "
        f"is {_stats(ours_gap)} N m (min / median / max).",
        f"- Table 3 implies transverse forces of {_n(np.nanmin(implied[3]), 2)}-"
        f"{_n(np.nanmax(implied[3]), 2)} N (median {_n(np.nanmedian(implied[3]), 2)} N) in the "
        f"prismatic joints. Ours are at most {_n(r3.max(), 2)} N. R_3 is the force the joint "
        "exerts across the leg, and it is small: in a static balance of the leg, |R_3| = "
        "|g_perp| |m_4 s_4 - m_2 s_2| / D (g_perp: the part of gravity across the leg; s_4, "
        "s_2: distances of the lower part's centre from C_i and of the upper part's centre "
        "from E_i). The spherical joint carries the upper part's weight across the leg; with "
        "the paper's placement (s_4 = s_2 = 0.25 D) and equal masses the rest is zero, and "
        "what remains comes from the leg parts' inertia. With the paper's leg parts "
        f"({_n(legs.lower_mass)} and {_n(legs.upper_mass)} kg) no placement gives more than "
        f"{_n(bound, 2)} N (a part's whole weight, for a horizontal leg), and their inertial "
        f"forces are {_n(legs.upper_mass * np.linalg.norm(models.PAPER_LEG_ACCELERATION), 2)} "
        "N with the paper's leg accelerations: the paper's 10-40 N cannot be a transverse force "
        "of these legs.",
        f"- The paper's Table 3 is of the size of the whole joint force instead: with our "
        f"|R_E| in place of |R_3|, (35) gives {_stats(with_r_e)} N (min / median / max) against "
        f"the paper's {_stats(np.abs(run.paper_values(3)))} N; the implied |R_3| (median "
        f"{_n(np.nanmedian(implied[3]), 2)} N) is close to our median |R_E| "
        f"({_n(np.median(r_e), 2)} N) and |F| ({_n(np.median(np.abs(run.result.F)), 2)} N). "
        "The paper's (28)-(29) define R_3 as a transverse force, so its Table 3 does not follow "
        "from its own equations; it does if the whole force of the spherical joint (or the "
        "actuator force) enters (35).",
        "",
    ]
    return out


def _why_section(run: PaperRun, sensitivity: pd.DataFrame) -> list[str]:
    out = ["## Why our values differ", ""]
    base = sensitivity.iloc[0]
    rows = [[name] + [f"{_n(v)} ({_n(v / base[c], 2)}x)" for c, v in row.items()]
            for name, row in sensitivity.iterrows()]
    paper_row = ["the paper"] + [_n(run.summary(k).loc["all", "paper_median"]) for k in TABLES] \
        + [f"{_n(np.nanmedian(run.implied_reaction(3)))} (implied)"]
    spread = _geometry_spread(sensitivity)
    ratio = {k: run.summary(k).loc["all", "ratio"] for k in TABLES}
    out += [
        "1. **The geometry is unknown.** The paper's dimensions (figures 6-7) are not in its "
        "text; the project's reference geometry is a plausible hexapod, not the paper's. How "
        "much our medians move when it changes (ratios to our run):",
        "",
        _markdown_table(["variant"] + [f"median {c}" for c in sensitivity.columns],
                        rows + [paper_row]),
        "",
        f"   A 20 % change of the dimensions moves the friction moments by at most "
        f"{spread:.0%}: the geometry alone does not explain medians of {_n(ratio[1], 2)} and "
        f"{_n(ratio[2], 2)} times the paper's. The leg masses' distribution, not the geometry, "
        "sets our |R_3| (last variant).",
        "",
    ]
    jump_rows = []
    for number in TABLES:
        p_count, p_pairs, p_max = _jumps(run.paper_values(number))
        o_count, o_pairs, o_max = _jumps(run.our_values(number))
        jump_rows.append([f"Table {number}", f"{p_count} of {p_pairs}", _n(p_max, 2),
                          f"{o_count} of {o_pairs}", _n(o_max, 2)])
    first = run.paper[1]["MfrE1"].to_numpy()
    out += [
        "2. **The paper's steps are not a smooth motion.** Under constant accelerations from "
        "rest every force changes smoothly from step to step, and so do ours. The paper's "
        f"values jump: MfrE1 reads {', '.join(f'{v:.3f}' for v in first[:4])} over steps 1-4, "
        f"an implied |R_E| jumping between {_n(implied_joint_reaction(first[0]), 2)} N and "
        f"{_n(implied_joint_reaction(first[1]), 2)} N within 0.05 s. Changes between "
        "neighbouring steps of more than half the column's median:",
        "",
        _markdown_table(["table", "paper: such changes", "paper: largest change / median",
                         "ours: such changes", "ours: largest change / median"], jump_rows),
        "",
        "   The paper's 40 movement steps must be poses of a path its text does not give, so "
        "no motion reproduces its tables row by row; the comparison is of sizes (medians, "
        "ranges), not of rows.",
        "",
        "3. **Table 3 rests on a different force** (previous section): ours follow (35) with the "
        f"transverse force R_3 of (28)-(29) and come out {_n(1 / ratio[3], 2)} times smaller.",
        "",
        "4. **Misprints** (above) put single values an order of magnitude off; they are left "
        "out of every median and range here.",
        "",
    ]
    return out


# -- the command ----------------------------------------------------------------------------------


def _write_table(frame: pd.DataFrame, path: Path) -> None:
    columns = list(frame.columns)
    lines = [",".join(columns)]
    for row in frame.itertuples(index=False):
        lines.append(",".join([str(int(row[0]))] + [format_significant(v) for v in row[1:]]))
    with atomic_write(path, "w", newline="") as handle:
        handle.write("\n".join(lines) + "\n")


def run_paper(out_dir: str | os.PathLike[str], mode: str = "paper",
              platform_file: str | os.PathLike[str] | None = None,
              plots: bool = True) -> list[Path]:
    """Evaluate the paper's motion and write the tables, platform, plots and report.

    Parameters
    ----------
    out_dir : path-like
        Directory to write into (created if missing).
    mode : {"paper", "kinematic"}
    platform_file : path-like, optional
        Platform TOML (default ``gsfric.models.paper_platform()``).
    plots : bool
        Write ``table1.png``..``table3.png``.

    Returns
    -------
    list of Path
        The files written: table1-3.csv, platform.toml, the plots, report.md.
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise InputError(f"{out}: exists and is not a directory") from None
    except OSError as error:
        raise InputError(f"{out}: cannot create the directory ({error.strerror})") from None
    platform = models.paper_platform() if platform_file is None \
        else Platform.from_toml(platform_file)
    run = evaluate_paper(platform, mode=mode)
    written = []
    for number in TABLES:
        path = out / f"table{number}.csv"
        _write_table(run.ours[number], path)
        written.append(path)
    path = out / "platform.toml"
    platform.to_toml(path)
    written.append(path)
    if plots:
        for number in TABLES:
            path = out / f"table{number}.png"
            png = figure_png(plot_table(run, number))
            with atomic_write(path, "wb") as handle:
                handle.write(png)
            written.append(path)
    from gsfric import paper_friction

    if plots:
        path = out / "breakdown.png"
        png = figure_png(paper_friction.breakdown_figure(platform, run.motion))
        with atomic_write(path, "wb") as handle:
            handle.write(png)
        written.append(path)
    path = out / "report.md"
    text = report_text(run, files=[p.name for p in written] + [path.name],
                       source=None if platform_file is None else f"`{platform_file}`")
    text += "\n".join(paper_friction.report_section(run)) + "\n"
    if plots:
        text += ("\nWhat each part contributes to the actuator force (kinematic mode, legs 1 "
                 "and 4): ![breakdown](breakdown.png)\n")
    with atomic_write(path, "w") as handle:
        handle.write(text)
    written.append(path)
    return written
