"""A sweep's results: task envelopes merged into one envelope per case, the summary over all
cases, the cases beyond the platform's ``[limits]``, and ``SweepResult`` (``load`` reads a
finished output folder back)."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from gsfric.sweep.envelope import ENVELOPE_COLUMNS, LIMIT_QUANTITY, QUANTITIES
from gsfric.sweep.workspace import POSE

_KEY = ["motion", "variant", "quantity", "leg"]
LIMIT_COLUMNS = ["motion", "variant", "quantity", "leg", "value", "limit", "ratio", "step", "t",
                 *POSE]
"""Columns of ``limits.csv``."""


def _sums(sub: pd.DataFrame) -> pd.DataFrame:
    """The rows of a summed quantity folded: exact sums (NaN when a term is), lowest task."""
    sub = sub.sort_values(["task", "motion", "variant", "leg"], kind="stable")
    return sub.groupby(_KEY, sort=True, as_index=False).agg(
        task=("task", "min"),
        value=("value", lambda v: math.fsum(v) if v.notna().all() else math.nan),
        step=("step", "first"), t=("t", "first"), **{c: (c, "first") for c in POSE})


def fold(frames: Sequence[pd.DataFrame]) -> pd.DataFrame:
    """Fold task envelopes (and earlier folds) into one row per case, quantity and leg.

    The result does not depend on the order of ``frames`` or of their rows: an extreme is
    chosen by (value, then the lowest task index), the counts are integer sums, and an energy
    has at most one term per case (a motion's variant is one task: files are never split;
    the workspace has no energy). Rows keep the winning ``task``.
    """
    frame = pd.concat(frames, ignore_index=True)
    counts = (frame[(frame.quantity == "R_E") & (frame.leg == 1)]
              .groupby(["motion", "variant"], sort=True)[["steps", "flagged", "at_rest"]]
              .sum())
    kind = frame.quantity.map({q: k for q, (k, _, _) in QUANTITIES.items()})
    summed = (kind == "sum").to_numpy()
    extremes = frame[~summed]
    # every extreme at once: a minimum by its value, a maximum by its negative
    order = extremes.value.where(kind[~summed] == "min", -extremes.value)
    best = (extremes.assign(_order=order)
            .sort_values(["_order", "task"], kind="stable", na_position="last")
            .drop_duplicates(_KEY, keep="first").drop(columns="_order"))
    parts = [best, _sums(frame[summed])] if summed.any() else [best]
    out = pd.concat(parts, ignore_index=True).drop(columns=["steps", "flagged", "at_rest"],
                                                   errors="ignore")
    return out.join(counts, on=["motion", "variant"])


def merge(chunks) -> pd.DataFrame:
    """Per-case envelopes (``ENVELOPE_COLUMNS``) from task envelopes, in any order."""
    out = fold(list(chunks))
    out["quantity"] = pd.Categorical(out["quantity"], categories=list(QUANTITIES))
    out = out.sort_values(_KEY, ignore_index=True)
    out["quantity"] = out["quantity"].astype(str)
    out["step"] = out["step"].astype("int64")
    return out[list(ENVELOPE_COLUMNS)]


def summarize(envelopes: pd.DataFrame) -> pd.DataFrame:
    """The extreme of each quantity and leg over all cases, with its case and location."""
    kind = envelopes.quantity.map({q: k for q, (k, _, _) in QUANTITIES.items()})
    # every quantity at once: a minimum by its value, a maximum (or sum) by its negative;
    # ties keep the envelopes' order
    order = envelopes.value.where(kind == "min", -envelopes.value)
    best = (envelopes.assign(_order=order)
            .sort_values("_order", kind="stable", na_position="last")
            .drop_duplicates(["quantity", "leg"], keep="first"))
    best = best.assign(_q=best.quantity.map({q: i for i, q in enumerate(QUANTITIES)}),
                       unit=best.quantity.map({q: u for q, (_, u, _) in QUANTITIES.items()}))
    out = best.sort_values(["_q", "leg"]).reset_index(drop=True)
    return out[["quantity", "leg", "value", "unit", "motion", "variant", "step", "t", *POSE]]


def check_limits(envelopes: pd.DataFrame, limits: Mapping) -> pd.DataFrame:
    """Rows of ``envelopes`` beyond the platform's ``[limits]``, with the limit and the ratio
    (``LIMIT_COLUMNS``)."""
    parts = []
    for key, q in LIMIT_QUANTITY.items():
        if key in limits:
            sub = envelopes[(envelopes.quantity == q) & (envelopes.value > limits[key])].copy()
            sub["limit"] = float(limits[key])
            parts.append(sub)
    if "actuator_force" in limits:
        lo, hi = limits["actuator_force"]
        for q, bad, lim in (("F_max", envelopes.value > hi, hi), ("F_min", envelopes.value < lo,
                                                                  lo)):
            sub = envelopes[(envelopes.quantity == q) & bad].copy()
            sub["limit"] = float(lim)
            parts.append(sub)
    if not parts:
        return pd.DataFrame(columns=LIMIT_COLUMNS)
    out = pd.concat(parts, ignore_index=True)
    out["ratio"] = out["value"] / out["limit"]
    return out[LIMIT_COLUMNS].sort_values(_KEY, ignore_index=True)


@dataclass
class SweepResult:
    """What ``sweep`` wrote and read back: the envelopes and the paths.

    Attributes
    ----------
    out : Path
        The output folder.
    envelopes : DataFrame
        ``envelopes.parquet``: one row per case, quantity and leg (``ENVELOPE_COLUMNS``).
    summary : DataFrame
        ``summary.csv``: the extreme of each quantity and leg over all cases.
    variants : DataFrame
        ``variants.csv``: each variant's parameter values (variant 0 is the nominal platform).
    exceeded : DataFrame
        ``limits.csv``: the rows beyond the platform's ``[limits]`` (``LIMIT_COLUMNS``).
    info : dict
        ``sweep.json``: ``fingerprint``, ``tasks``, ``steps``, ``cases``, ``flagged`` (steps
        left out), ``computed_tasks`` (this run's), ``scheduler``, ``seconds``, ``limits``,
        ``exceeding_cases``, ``limits_check`` (what the check of the limits found, in a
        sentence), ``variants_drawn`` (how the variants were chosen), ``inputs``.
    """

    out: Path
    envelopes: pd.DataFrame
    summary: pd.DataFrame
    variants: pd.DataFrame
    exceeded: pd.DataFrame
    info: dict

    def __repr__(self) -> str:
        info = self.info
        return (f"<SweepResult {self.out}: {info.get('cases')} cases, {info.get('steps')} "
                f"steps, {info.get('flagged')} flagged; limits: "
                f"{info.get('limits_check', info.get('exceeding_cases'))}; the extremes in "
                ".summary, each case's in .envelopes>")

    def most_loaded(self, quantity: str = "R_C") -> pd.Series | None:
        """The summary row of ``quantity`` with the largest value over the legs; None when
        no step of any case was evaluated soundly (every step flagged)."""
        sub = self.summary[self.summary.quantity == quantity]
        if not sub.value.notna().any():
            return None
        return sub.loc[sub.value.idxmax()]


def load(out: str | os.PathLike) -> SweepResult:
    """Read a finished sweep's output folder back."""
    out = Path(out)
    info = json.loads((out / "sweep.json").read_text())
    envelopes = pd.read_parquet(out / "envelopes.parquet")
    exceeded = (pd.read_csv(out / "limits.csv") if (out / "limits.csv").exists()
                else check_limits(envelopes, {}))
    return SweepResult(out, envelopes, pd.read_csv(out / "summary.csv"),
                       pd.read_csv(out / "variants.csv"), exceeded, info)
