"""summary.json: the discovery's result as data (``summary``, also
``Discovery.summary()``)."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from gsfric.discovery.answer import verdict_line
from gsfric.discovery.candidates import separating_motion
from gsfric.discovery.regimes import hotspots
from gsfric.discovery.results import DiscoveryRecord
from gsfric.platform import catalog

if TYPE_CHECKING:
    from gsfric.discovery.final_tests import LackOfFit


def _clean(value):
    """JSON-safe copy: NumPy scalars to Python, non-finite floats to None, tuples to lists."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def _asdict(value) -> dict:
    """A dataclass's fields as a dict ({} for None)."""
    return dataclasses.asdict(value) if value is not None else {}


def per_leg_rms(r: np.ndarray) -> list[float]:
    """RMS of each leg's residual (6,), N, of r (M, 6)."""
    return [float(v) for v in np.sqrt(np.mean(r ** 2, axis=0))]


def summary(d: DiscoveryRecord) -> dict:
    """The content of summary.json (SPEC), plus the refit, rounds and per-leg gaps, the
    measured-data file (``data.file``) and the answer in one line (``answer``,
    ``answer.verdict_line``)."""
    n = d.used.stop - d.used.start
    duration = float(d.t[-1] - d.t[0]) if len(d.t) > 1 else 0.0
    s = d.settings
    lof = d.lack_of_fit
    out = {
        "verdict": d.verdict,
        "verdict_reason": d.verdict_reason,
        "verdict_decided_by": d.verdict_decided_by,
        "unexplained": _unexplained(d, lof),
        "lack_of_fit": lof.to_json(),
        "noise": _asdict(d.noise),
        "rms_after_all_samples": d.rms_after_all,
        "effects": _effects(d),
        "rms_before": d.rms_before,
        "rms_after": d.rms_after,
        "noise_rms_estimate": d.noise_rms_estimate,
        "rms_after_refit": d.rms_refit,
        "per_leg": {"rms_before": per_leg_rms(d.residual_before),
                    "rms_after": per_leg_rms(d.residual_after)},
        "refit": d.refit.to_json(),
        "ambiguous": _ambiguous(d),
        "rounds": _rounds(d),
        "regimes": [vars(b) for b in d.regimes],
        "hotspots": [f"{b.regime}: {b.name}" for b in hotspots(d.regimes)],
        "noise_model": dataclasses.asdict(d.noise_model),
        "data": {"samples_used": n, "first_used": d.used.start,
                 "duration": duration, "rate": (n - 1) / duration if duration > 0 else None,
                 "file": d.source or None},
        "settings": {"alpha": s.alpha, "min_fold_share": s.min_fold_share,
                     "min_gap": s.min_gap, "n_blocks": s.n_blocks, "n_folds": s.n_folds,
                     "n_bootstrap": s.n_bootstrap, "candidates": list(s.candidates),
                     "refit": list(s.refit), "floor_ratio": s.floor_ratio,
                     "dictionary_min_gap": s.dictionary_min_gap},
        "notes": d.notes,
        "evaluations": d.evaluations,
        "answer": verdict_line(d),
    }
    return _clean(out)


def _effects(d: DiscoveryRecord) -> list[dict]:
    """summary.json's ``effects``: each named effect's parameters and evidence."""
    effects = []
    for f in d.effects:
        evidence = dataclasses.asdict(f.evidence)
        evidence["interval_95"] = {k: list(v) for k, v in f.interval.items()}
        # with structure left that the catalog does not explain, a named effect is the best
        # candidate for a part of the gap, not a confident explanation of it
        effects.append({"name": f.name, "parameters": dict(f.parameters),
                        "units": {k: catalog.unit(f"{f.name}.{k}") for k in f.parameters},
                        "partial": d.verdict == "unexplained_discrepancy",
                        "evidence": evidence})
    return effects


def _ambiguous(d: DiscoveryRecord) -> list[dict]:
    """summary.json's ``ambiguous``: the winners the data cannot tell from other candidates,
    and the refitted changes that a candidate explains as well."""
    ambiguous = []
    for rnd in d.rounds:
        if rnd.winner and rnd.indistinguishable:
            why = ("the simpler explanation" if rnd.preferred_over
                   else "the largest held-out gain")
            ambiguous.append({
                "round": rnd.index, "effects": [rnd.winner] + list(rnd.indistinguishable),
                "indistinguishable": True, "chosen": rnd.winner,
                "separating_motion": [separating_motion(rnd.winner, o)
                                      for o in rnd.indistinguishable],
                "message": f"the data cannot tell {rnd.winner} apart from "
                           f"{', '.join(rnd.indistinguishable)}: either explains the same "
                           f"part of the gap; {rnd.winner} was added ({why})"})
    for name, entry in d.refit.parameters.items():
        for alt in entry.alternatives or []:
            ambiguous.append({"round": 0, "effects": [f"refit:{name}", alt],
                              "message": f"the change of {name} could equally be {alt}"})
    return ambiguous


def _rounds(d: DiscoveryRecord) -> list[dict]:
    """summary.json's ``rounds``: each round's tests and decision."""
    rounds = []
    for rnd in d.rounds:
        rounds.append({
            "round": rnd.index, "winner": rnd.winner, "level": rnd.level,
            "indistinguishable": rnd.indistinguishable,
            "bootstrap_share": rnd.bootstrap_share, "noise_model": _asdict(rnd.noise_model),
            "rms_before": rnd.rms_before, "rms_after": rnd.rms_after,
            "generic": _asdict(rnd.generic),
            "blocked": rnd.blocked, "slow": rnd.slow,
            "tests": [{"name": t.name, "F": t.F, "p_value": t.p_value, "dof": t.dof,
                       "cv_gain": t.cv_gain, "fold_share": t.fold_share,
                       "sse_gain": t.sse_gain, "gap": t.gap, "p_bands": t.p_bands,
                       "significant": t.significant, "slow_only": t.slow_only,
                       "reason": t.reason, "parameters": t.parameters,
                       "units": {k: catalog.unit(f"{t.name}.{k}") for k in t.parameters}}
                      for t in rnd.tests]})
    return rounds


def _unexplained(d: DiscoveryRecord, lof: LackOfFit) -> dict | None:
    """summary.json's ``unexplained``: the structure left, for an ``unexplained_discrepancy``."""
    unexplained = None
    if d.verdict == "unexplained_discrepancy":
        unexplained = {
            "size_rms": lof.structure_rms, "size_over_noise": lof.gap,
            "per_leg_rms": lof.per_leg_rms, "time_rms": lof.time_rms,
            "dominant_frequency": lof.frequency, "main_signal": lof.main_signal,
            "looks_like": lof.looks_like,
            "partial_effects": [f.name for f in d.effects],
            "speed_bands": {b.name: b.rms_after for b in d.regimes if b.regime == "speed"},
            "source": lof.source,
            "message": _unexplained_message(lof),
            "structures": [dataclasses.asdict(s) for s in d.structures],
            "decided_by": d.verdict_decided_by}
        if d.verdict_decided_by in ("dictionary", "floor"):
            unexplained["message"] = (
                "the catalog does not explain the data: "
                + ("; ".join(s.description for s in d.structures) if d.structures
                   else d.verdict_reason))
    return unexplained


def _unexplained_message(lof: LackOfFit) -> str:
    """One sentence on an ``unexplained_discrepancy``: the structure left in the final
    residual, or the round whose generic competitor found it (``lof.source``)."""
    source = lof.source or "final residual"
    if source == "final residual":
        return ("the catalog does not explain the data: a structured residual of "
                f"{lof.structure_rms:.4g} N RMS remains, {lof.looks_like}")
    return (f"the catalog does not explain the data: in {source}, a generic structure outside "
            f"the catalog ({lof.main_signal}) explains the gap as well as the catalog's "
            f"best candidate or better, {lof.looks_like}")
