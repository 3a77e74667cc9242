"""The plots of a sweep: ``envelope.png`` (each quantity per leg over all cases, with the
limits) and ``locations.png`` (where each joint's largest load occurs). Matplotlib figures
without pyplot, so the caller's backend is left alone."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from gsfric._optional import optional
from gsfric.sweep.envelope import LIMIT_QUANTITY, QUANTITIES

_SHOWN = ("R_E", "R_C", "M_C", "R_3", "M_3", "F_max", "Ffr", "P_C", "W_C")
"""Quantities of ``envelope.png``, one panel each (``F_max`` with ``F_min``)."""

_LOCATED = ("R_E", "R_C", "M_C", "R_3", "M_3", "F_max")
"""Quantities of ``locations.png``."""

MAX_LABELLED = 12
"""Cases drawn each in a colour of its own and named in the legend; more are drawn grey."""


def case_labels(envelopes: pd.DataFrame, variants: pd.DataFrame | None) -> dict:
    """(motion, variant) -> a label naming the case by its varied values, e.g.
    ``"run1, payload_mass=4"``; only the motion when one variant, only the values when one
    motion."""
    cases = envelopes[["motion", "variant"]].drop_duplicates().itertuples(index=False)
    cases = list(cases)
    motions = {c.motion for c in cases}
    table = (variants.set_index("variant") if variants is not None and len(variants)
             else pd.DataFrame())
    labels = {}
    for motion, variant in cases:
        parts = [str(motion)] if len(motions) > 1 else []
        if len(table.columns) and variant in table.index:
            row = table.loc[variant]
            values = ", ".join(f"{k.rpartition('.')[2]}={row[k]:.4g}" for k in table.columns)
            parts.append(values + (" (nominal)" if variant == 0 else ""))
        elif not parts:
            parts.append(f"variant {variant}")
        labels[(motion, variant)] = ", ".join(parts)
    return labels


def _envelope_panel(ax, q: str, envelopes: pd.DataFrame, summary: pd.DataFrame,
                    limits: Mapping, labels: dict) -> None:
    """One quantity per leg: every case (a line each, labelled when ``labels`` holds it),
    the extreme over the cases (bars), limits."""
    legs = np.arange(1, 7)
    limit_of = {quantity: key for key, quantity in LIMIT_QUANTITY.items()}
    sub = envelopes[envelopes.quantity == q]
    _, unit, meaning = QUANTITIES[q]
    if sub.value.notna().any():
        table = sub.pivot_table(index="leg", columns=["motion", "variant"], values="value")
        for n, case in enumerate(table.columns):
            if case in labels:
                ax.plot(legs, table[case].to_numpy(), color=f"C{n % 10}", lw=1.0,
                        marker=".", ms=4, label=labels[case])
            else:
                ax.plot(legs, table[case].to_numpy(), color="0.7", lw=0.8, marker=".", ms=3)
        best = summary[summary.quantity == q].sort_values("leg")
        ax.bar(legs, best.value, alpha=0.35, color="C0")
    if q == "F_max":
        fmin = envelopes[envelopes.quantity == "F_min"].groupby("leg").value.min()
        ax.bar(legs, fmin.reindex(legs), alpha=0.35, color="C1")
        ax.set_title(f"actuator force range, F_min..F_max ({unit})", fontsize=9)
        if "actuator_force" in limits:
            for v in limits["actuator_force"]:
                ax.axhline(v, color="C3", ls="--")
    else:
        ax.set_title(f"{meaning.replace(' (motions only)', '')} ({unit})", fontsize=9)
    if q in limit_of and limit_of[q] in limits:
        ax.axhline(limits[limit_of[q]], color="C3", ls="--", label="limit")
    ax.set_xlabel("leg")
    ax.set_ylabel(f"{q} ({unit})")


def _locations_panel(ax, i: str, j: str, summary: pd.DataFrame, workspace: dict | None) -> None:
    """Where each located quantity's extreme occurs, coordinates ``i`` and ``j``."""
    if workspace is not None:
        Rectangle = optional("matplotlib.patches").Rectangle
        (x0, x1), (y0, y1) = workspace["pose"][i], workspace["pose"][j]
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ls=":",
                               color="0.4", label="workspace"))
    for k, q in enumerate(_LOCATED):
        best = summary[summary.quantity == q]
        ax.scatter(best[i], best[j], s=40, marker="os^v<>"[k], label=q, alpha=0.8)
        for _, r in best.iterrows():
            ax.annotate(str(int(r.leg)), (r[i], r[j]), fontsize=7)
    ax.set_xlabel(f"{i} [m]")
    ax.set_ylabel(f"{j} [m]")
    ax.autoscale()


def plot(envelopes: pd.DataFrame, summary: pd.DataFrame, folder: Path, limits: Mapping,
         workspace: dict | None, variants: pd.DataFrame | None = None) -> None:
    """``envelope.png`` (each quantity per leg, all cases, limits) and ``locations.png``
    in ``folder``; ``workspace`` is ``Workspace.to_dict()`` (its box is drawn) or None;
    ``variants`` the variants' table (``variants.csv``) that names each case's line."""
    Figure = optional("matplotlib.figure").Figure
    labels = case_labels(envelopes, variants)
    if len(labels) > MAX_LABELLED:
        labels = {}
    fig = Figure(figsize=(12, 9.5 + 0.25 * len(labels) / 2), layout="constrained")
    axes = fig.subplots(3, 3)
    for ax, q in zip(axes.flat, _SHOWN):
        _envelope_panel(ax, q, envelopes, summary, limits, labels)
    if labels:
        handles, names = axes.flat[0].get_legend_handles_labels()
        fig.legend(handles[:len(labels)], names[:len(labels)], loc="outside lower center",
                   ncol=min(3, len(labels)), fontsize=8, title="cases (lines)")
        fig.suptitle("Load envelope per joint: bars = extreme over all cases, lines = each "
                     "case")
    else:
        fig.suptitle("Load envelope per joint: bars = extreme over all cases, grey = each "
                     "case (too many to name: variants.csv lists them)")
    fig.savefig(folder / "envelope.png", dpi=90)

    fig = Figure(figsize=(11, 4.5), layout="constrained")
    axes = fig.subplots(1, 2)
    for ax, (i, j) in zip(axes, (("x", "y"), ("x", "z"))):
        _locations_panel(ax, i, j, summary, workspace)
    axes[0].legend(fontsize=7)
    fig.suptitle("Where each joint's largest load occurs: platform position x, y, z (m); "
                 "numbers: legs")
    fig.savefig(folder / "locations.png", dpi=90)
