"""The content of summary.json (SPEC), from a ``Discovery``; imports no other workflow module."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from gsfric.discovery.candidates import separating_motion
from gsfric.discovery.regimes import hotspots

if TYPE_CHECKING:
    from gsfric.discovery.workflow import Discovery


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


def _per_leg(r: np.ndarray) -> list[float]:
    return [float(v) for v in np.sqrt(np.mean(r ** 2, axis=0))]


def summary(d: Discovery) -> dict:
    """The content of summary.json (see the module docstring)."""
    effects = []
    for f in d.effects:
        evidence = dict(f.evidence)
        evidence["interval_95"] = {k: list(v) for k, v in f.interval.items()}
        # with structure left that the catalog does not explain, a named effect is the best
        # candidate for a part of the gap, not a confident explanation of it
        effects.append({"name": f.name, "parameters": dict(f.parameters),
                        "partial": d.verdict == "unexplained_discrepancy",
                        "evidence": evidence})
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
    for name, entry in d.refit.get("parameters", {}).items():
        for alt in entry.get("alternatives", []):
            ambiguous.append({"round": 0, "effects": [f"refit:{name}", alt],
                              "message": f"the change of {name} could equally be {alt}"})
    rounds = []
    for rnd in d.rounds:
        rounds.append({
            "round": rnd.index, "winner": rnd.winner, "level": rnd.level,
            "indistinguishable": rnd.indistinguishable,
            "bootstrap_share": rnd.bootstrap_share, "noise_model": rnd.noise_model,
            "rms_before": rnd.rms_before, "rms_after": rnd.rms_after,
            "generic": rnd.generic, "blocked": rnd.blocked, "slow": rnd.slow,
            "tests": [{"name": t.name, "F": t.F, "p_value": t.p_value, "dof": t.dof,
                       "cv_gain": t.cv_gain, "fold_share": t.fold_share,
                       "sse_gain": t.sse_gain, "gap": t.gap, "p_bands": t.p_bands,
                       "significant": t.significant, "slow_only": t.slow_only,
                       "reason": t.reason, "parameters": t.parameters} for t in rnd.tests]})
    n = d.used.stop - d.used.start
    duration = float(d.t[-1] - d.t[0]) if len(d.t) > 1 else 0.0
    s = d.settings
    lof = dict(d.lack_of_fit)
    unexplained = None
    if d.verdict == "unexplained_discrepancy":
        unexplained = {
            "size_rms": lof.get("structure_rms"), "size_over_noise": lof.get("gap"),
            "per_leg_rms": lof.get("per_leg_rms"), "time_rms": lof.get("time_rms"),
            "dominant_frequency": lof.get("frequency"), "main_signal": lof.get("main_signal"),
            "looks_like": lof.get("looks_like"),
            "partial_effects": [f.name for f in d.effects],
            "speed_bands": {b.name: b.rms_after for b in d.regimes if b.regime == "speed"},
            "source": lof.get("source"),
            "message": _unexplained_message(lof)}
    out = {
        "verdict": d.verdict,
        "unexplained": unexplained,
        "lack_of_fit": lof,
        "noise": d.noise,
        "rms_after_all_samples": d.rms_after_all,
        "effects": effects,
        "rms_before": d.rms_before,
        "rms_after": d.rms_after,
        "noise_rms_estimate": d.noise_rms_estimate,
        "rms_after_refit": d.rms_refit,
        "per_leg": {"rms_before": _per_leg(d.residual_before),
                    "rms_after": _per_leg(d.residual_after)},
        "refit": d.refit,
        "ambiguous": ambiguous,
        "rounds": rounds,
        "regimes": [vars(b) for b in d.regimes],
        "hotspots": [f"{b.regime}: {b.name}" for b in hotspots(d.regimes)],
        "noise_model": d.noise_model,
        "data": {"samples_used": n, "first_used": d.used.start,
                 "duration": duration, "rate": (n - 1) / duration if duration > 0 else None},
        "settings": {"alpha": s.alpha, "min_fold_share": s.min_fold_share,
                     "min_gap": s.min_gap, "n_blocks": s.n_blocks, "n_folds": s.n_folds,
                     "n_bootstrap": s.n_bootstrap, "candidates": list(s.candidates),
                     "refit": list(s.refit)},
        "notes": d.notes,
        "evaluations": d.evaluations,
    }
    return _clean(out)


def _unexplained_message(lof: dict) -> str:
    """One sentence on an ``unexplained_discrepancy``: the structure left in the final
    residual, or the round whose generic competitor found it (``lof["source"]``)."""
    source = lof.get("source") or "final residual"
    if source == "final residual":
        return ("the catalog does not explain the data: a structured residual of "
                f"{lof.get('structure_rms', 0.0):.4g} N RMS remains, {lof.get('looks_like', '')}")
    return (f"the catalog does not explain the data: in {source}, a generic structure outside "
            f"the catalog ({lof.get('main_signal')}) explains the gap as well as the catalog's "
            f"best candidate or better, {lof.get('looks_like', '')}")
