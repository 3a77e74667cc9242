"""Writing the paper's 40-step evaluation: plots, ``report.md`` and the ``gsfric paper`` command.

``run_paper`` evaluates (``gsfric.paper.evaluate_paper``) and writes, into one directory, the
tables ``table1.csv``..``table3.csv``, ``platform.toml``, the plots ``table1.png``..``table3.png``
and ``report.md`` (see ``gsfric.paper``'s module docstring for what each holds).
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pandas as pd

from gsfric import models
from gsfric._optional import optional
from gsfric.evaluation.paper_constants import (
    PAPER_ACCELERATION,
    PAPER_ANGULAR_ACCELERATION,
    PAPER_JOINT_SPEED,
    PAPER_LEG_ACCELERATION,
)
from gsfric.io.files import atomic_write, output_folder
from gsfric.paper import friction as paper_friction
from gsfric.paper.tables import (
    LARGE_FACTOR,
    PAPER_FRICTION,
    SMALL_FRACTION,
    TABLES,
    PaperRun,
    evaluate_paper,
    format_significant,
    geometry_sensitivity,
    implied_joint_reaction,
)
from gsfric.platform.description import Platform

# -- plots ----------------------------------------------------------------------------------------


def plot_table(run: PaperRun, number: int):
    """Ours against the paper's for one table: |value| against the step, one panel per joint.

    Log scale, so that values an order of magnitude apart and the misprints show (red crosses:
    the values left out of the comparison; printing slips that are kept are not marked).
    For Table 3 a dashed line shows (35) with our |R_E| in place of |R_3|.

    Returns
    -------
    matplotlib.figure.Figure (Agg canvas; no pyplot state)
    """
    FigureCanvasAgg = optional("matplotlib.backends.backend_agg").FigureCanvasAgg
    Figure = optional("matplotlib.figure").Figure
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
        bad = [m for m in run.misprints[number] if m.column == column and m.excluded]
        if bad:
            ax.semilogy([m.pos for m in bad], [abs(m.value) for m in bad], "x", color="red",
                        ms=9, mew=2, label="misprint (left out of the comparison)")
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
    fig.suptitle(f"Table {number}: {spec.title}, |{spec.prefix}| in {spec.unit}")
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
    out = _header_section(run, source)
    out += _summary_section(run, sensitivity)
    out += _tables_section(run, files)
    out += _misprint_section(run)
    out += _implied_section(run)
    out += _why_section(run, sensitivity)
    out += _actuator_section(run)
    if files:
        out += ["## Files", ""] + [f"- `{f}`" for f in files] + [""]
    return "\n".join(out)


def _header_section(run: PaperRun, source: str | None) -> list[str]:
    """The title and what was run: platform, motion, mode, flagged steps."""
    n = len(run.result)
    mode_text = {
        "paper": ("paper mode: the paper's constant accelerations of platform and leg parts, no "
                  "gyroscopic terms, joint speed 0.02 rad/s in (33)-(34); positions and sliding "
                  "speeds from the motion"),
        "kinematic": "kinematic mode: every velocity and acceleration from the motion itself",
    }[run.mode]
    return [
        "# The paper's Tables 1-3, reproduced",
        "",
        f"- Platform: {source or 'the built-in paper platform (`gsfric.models.paper_platform()`)'}"
        ", written to `platform.toml`. The paper's dimensions (its figures 6-7) are missing, so "
        "the geometry is the project's reference geometry (docs/explanation/reference-platform.md).",
        f"- Motion: {n} steps from rest at the home pose with constant accelerations "
        f"a = {PAPER_ACCELERATION} m/s^2, alpha = {PAPER_ANGULAR_ACCELERATION} "
        f"rad/s^2, t_j = {models.PAPER_DT} j s.",
        f"- Mode: {mode_text}.",
        f"- Flagged steps: {len(run.result.flagged())} of {n}.",
        "- Every value of every table is negative (friction opposes the motion); the "
        "comparisons below are of magnitudes, with the paper's misprints left out.",
        "",
    ]


def _summary_section(run: PaperRun, sensitivity: pd.DataFrame) -> list[str]:
    """The summary: each table's medians, ours against the paper's, and what they say."""
    out = ["## Summary", ""]
    rows = []
    for number, spec in TABLES.items():
        s = run.summary(number).loc["all"]
        rows.append([f"Table {number}", f"|{spec.prefix}| ({spec.unit})", _n(s.ours_median),
                     _n(s.paper_median), _n(s.ratio)])
    out += [_markdown_table(["table", "quantity", "ours, median", "paper, median",
                             "ratio ours/paper"], rows), ""]
    return out + _summary_text(run, sensitivity)


def _tables_section(run: PaperRun, files: list[str]) -> list[str]:
    """One section per table: per column, our and the paper's min / median / max, and the plot
    if it is among ``files``."""
    out = []
    for number, spec in TABLES.items():
        out += [f"## Table {number}: {spec.title} ({spec.unit})", ""]
        rows = [[c, _n(r.ours_min), _n(r.ours_median), _n(r.ours_max), _n(r.paper_min),
                 _n(r.paper_median), _n(r.paper_max), _n(r.ratio)]
                for c, r in run.summary(number).iterrows()]
        out += [_markdown_table(["column", "ours min", "ours median", "ours max", "paper min",
                                 "paper median", "paper max", "ratio of medians"], rows), ""]
        if f"table{number}.png" in files:
            out += [f"![Table {number}: ours against the paper's](table{number}.png)", ""]
    return out


def _actuator_section(run: PaperRun) -> list[str]:
    """The actuator forces F and F0 per leg (which the paper does not give)."""
    res = run.result
    out = ["## Actuator forces (not in the paper)", "",
           "F: the axial force of each actuator, friction included, positive pushing the "
           "platform away from the base; F0: the same with frictionless joints.", ""]
    rows = [[f"leg {i + 1}", _n(res.F[:, i].min()), _n(res.F[:, i].max()),
             _n(res.F0[:, i].min()), _n(res.F0[:, i].max())] for i in range(6)]
    return out + [_markdown_table(["leg", "F min (N)", "F max (N)", "F0 min (N)", "F0 max (N)"],
                                  rows), ""]


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
    """The reactions the paper's values imply, by inverting (33)-(35), beside ours."""
    fr = PAPER_FRICTION
    w = PAPER_JOINT_SPEED
    implied = {k: run.implied_reaction(k) for k in TABLES}
    r_e = run.reaction("R_E")
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
    return out + _joint_findings(run, implied) + _table3_findings(run, implied) + [""]


def _joint_findings(run: PaperRun, implied: dict[int, np.ndarray]) -> list[str]:
    """Tables 1-2: the joint forces they imply, and how they contradict each other."""
    fr = PAPER_FRICTION
    weight = (run.platform.platform.mass + run.platform.platform.payload_mass) \
        * run.platform.gravity
    r_e = run.reaction("R_E")
    joints = np.concatenate([implied[1], implied[2]])
    factor = np.nanmedian(implied[1]) / np.median(r_e)
    high = np.mean(implied[1][np.isfinite(implied[1])] > 45.0)
    high_ours = np.mean(r_e > 45.0)
    legs = run.platform.legs
    leg_weight = (legs.lower_mass + legs.upper_mass) * run.platform.gravity
    inertial = (legs.lower_mass + legs.upper_mass) \
        * np.linalg.norm(PAPER_LEG_ACCELERATION)
    tolerance = fr.joint_coulomb * fr.joint_radius * inertial
    gap = np.abs(np.abs(run.paper_values(2)) - np.abs(run.paper_values(1)))
    disagree = np.mean(gap[np.isfinite(gap)] > tolerance)
    ours_gap = np.abs(run.our_values(2)) - np.abs(run.our_values(1))
    return [
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
    ]


def _table3_findings(run: PaperRun, implied: dict[int, np.ndarray]) -> list[str]:
    """Table 3: the transverse forces it implies cannot be these legs'; the whole joint force
    gives its size."""
    r3, r_e = run.reaction("R_3"), run.reaction("R_E")
    with_r_e = run.prismatic_friction_with("R_E")
    legs = run.platform.legs
    bound = max(legs.lower_mass, legs.upper_mass) * run.platform.gravity
    return [
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
        f"forces are {_n(legs.upper_mass * np.linalg.norm(PAPER_LEG_ACCELERATION), 2)} "
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
    ]


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
    platform = models.paper_platform() if platform_file is None \
        else Platform.from_toml(platform_file)
    run = evaluate_paper(platform, mode=mode)
    written = []
    with output_folder(out, inputs={"platform": platform_file}) as folder:
        for number in TABLES:
            path = folder / f"table{number}.csv"
            _write_table(run.ours[number], path)
            written.append(path)
        path = folder / "platform.toml"
        platform.to_toml(path)
        written.append(path)
        if plots:
            for number in TABLES:
                path = folder / f"table{number}.png"
                png = figure_png(plot_table(run, number))
                with atomic_write(path, "wb") as handle:
                    handle.write(png)
                written.append(path)
            path = folder / "breakdown.png"
            png = figure_png(paper_friction.breakdown_figure(platform, run.motion))
            with atomic_write(path, "wb") as handle:
                handle.write(png)
            written.append(path)
        path = folder / "report.md"
        text = report_text(run, files=[p.name for p in written] + [path.name],
                           source=None if platform_file is None else f"`{platform_file}`")
        text += "\n".join(paper_friction.report_section(run)) + "\n"
        if plots:
            text += ("\nWhat each part contributes to the actuator force (kinematic mode, legs 1 "
                     "and 4): ![breakdown](breakdown.png)\n")
        with atomic_write(path, "w") as handle:
            handle.write(text)
        written.append(path)
    written = [out / p.name for p in written]
    return written
