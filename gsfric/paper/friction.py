"""The paper report's friction sections: Table 3 three ways, and what each part contributes.

Table 3 (the prismatic joints' friction) computed three ways from the same reactions of the
paper's run, each beside the paper's values (magnitudes, N):

* ``(35) with R_3``: the paper's (35) as printed, with the transverse force R_3 of (28)-(29)
  (our Table 3);
* ``(35) with R_E``: the same formula with the whole joint force |R_E|, which is what the size of
  the paper's values implies;
* ``bushings``: the coupled model's prismatic friction (docs/explanation/friction.md) from the same R_3 and
  M_3: two bushings ``bushing_spacing`` apart, ``bushing_offset`` from C_i, the same mu, plus
  viscous and seal terms.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from gsfric._optional import optional
from gsfric.compiled import native
from gsfric.evaluation.breakdown import plot, shown_parts
from gsfric.evaluation.evaluator import breakdown
from gsfric.evaluation.parameters import effect_vector, parameter_vector

WAYS = ("(35) with R_3", "(35) with R_E", "bushings")


def bushing_friction(run) -> np.ndarray:
    """|F_fr| of the bushing model from the run's reactions (nothing fed back), (N, 6), N."""
    r = run.result
    platform = run.platform.with_friction(model="coupled")
    n = len(r)
    ins = [r.R_E, r.R_C, r.R_3, r.M_3, r.omega_rel, r.omega_leg, r.D_dot, r.D, r.u]
    ins = [np.ascontiguousarray(np.asarray(a, float).reshape(n, -1)) for a in ins]
    out = native.get("friction")(ins + [parameter_vector(platform), effect_vector(platform)])
    return np.abs(out["Ffr"].reshape(n, 6))


def table3_three_ways(run) -> pd.DataFrame:
    """Median, min and max of |F_fr| over steps and legs for each way and for the paper, N."""
    values = {WAYS[0]: np.abs(run.our_values(3)),
              WAYS[1]: run.prismatic_friction_with("R_E"),
              WAYS[2]: bushing_friction(run),
              "paper": np.abs(run.paper_values(3))}
    rows = {name: dict(min=np.nanmin(v), median=np.nanmedian(v), max=np.nanmax(v),
                       ratio_to_paper=np.nanmedian(v) / np.nanmedian(values["paper"]))
            for name, v in values.items()}
    return pd.DataFrame.from_dict(rows, orient="index")


def report_section(run) -> list[str]:
    """Markdown lines: Table 3 three ways beside the paper's values."""
    table = table3_three_ways(run)
    fr = run.platform.friction
    lines = ["", "## Table 3 three ways", "",
             "The prismatic joints' friction |F_fr| (N) of the same run, over every step and leg, "
             "computed three ways from the same reactions, beside the paper's values:", "",
             "| way | min | median | max | median / paper's |", "|---|---|---|---|---|"]
    for name, row in table.iterrows():
        lines.append(f"| {name} | {row['min']:.3g} | {row['median']:.3g} | {row['max']:.3g} | "
                     f"{row['ratio_to_paper']:.3g} |")
    lines += ["",
              "(35) with R_3 is the paper's formula as printed (our table3.csv); with the whole "
              "joint force |R_E| it has the size of the paper's values; the bushing model "
              f"(docs/explanation/friction.md: bushings {fr.bushing_spacing:g} m apart, the first "
              f"{fr.bushing_offset:g} m from C_i, mu = {fr.prismatic_coulomb:g}, seal "
              f"{fr.prismatic_seal:g} N) adds the normal forces that the joint's moment M_3 "
              "puts on the bushings."]
    return lines


def breakdown_figure(platform, motion):
    """A figure of what each part contributes to F of legs 1 and 4 (kinematic mode)."""
    optional("matplotlib").use("Agg")
    plt = optional("matplotlib.pyplot")
    parts = breakdown(platform, motion)
    shown = shown_parts(parts, (0, 3))
    rows = 1 + len(shown)
    fig, axes = plt.subplots(rows, 2, figsize=(12, 1.4 * rows + 0.8), sharex=True,
                             squeeze=False)
    for column, leg in enumerate((0, 3)):
        plot(parts, leg, axes[:, column], shown)
    fig.suptitle("Breakdown of the actuator forces F into their parts, legs 1 and 4 (N)")
    fig.tight_layout()
    return fig
