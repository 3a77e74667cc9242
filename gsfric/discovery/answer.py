"""Discovery's answer for a reader: the one-line verdict, the units of every parameter, the
glossary of the report's statistics, and the commented platform file written back.

>>> from gsfric.discovery.answer import GLOSSARY
>>> GLOSSARY["held-out gain"][:40]
'relative drop of the prewhitened squared'
"""

from __future__ import annotations

from gsfric.discovery.results import DiscoveryRecord, Finding
from gsfric.platform import catalog
from gsfric.platform.text import commented_toml


GLOSSARY: dict[str, str] = {
    "verdict": "`explained`: the effects named (or the refit) close the gap and no structure "
               "is left; `unexplained_discrepancy`: a significant structure is left that no "
               "catalog effect explains; `no_discrepancy`: model and data agree within the "
               "noise.",
    "gap": "RMS of the residual F_measured - F_model over all legs, N, on the samples where "
           "the legs slide.",
    "gap closed (console)": "(RMS before - RMS after) / (RMS before - noise floor): the share "
                            "of the gap above the noise that the final model removes; the "
                            "noise floor is the smaller of the noise level and the final RMS.",
    "noise floor": "what model and data can agree to, N RMS over the legs: the load cells' "
                   "noise (as given with --force-noise or --noise-record, or estimated from "
                   "the force channels in a way the discrepancy cannot inflate) plus what the "
                   "pose noise puts into the model's forces through differentiation.",
    "model / refit / final / unbounded": "a parameter's value in the platform as given "
                                         "(model), after refitting the model's own parameters "
                                         "alone, within the plausible range (refit), in the "
                                         "final model, refitted again together with the "
                                         "effects found (final), and the value a refit "
                                         "without limits would need (unbounded).",
    "effect size": "RMS of an effect's contribution to the forces over the noise level of "
                   "the final residual.",
    "F, p": "the nested F-test of a candidate against the refitted model on the prewhitened "
            "residual, and its p-value; a candidate needs p below the test level.",
    "test level": "alpha / K, the significance level per candidate (Bonferroni over the K "
                  "candidates of the round).",
    "p slowest / rest": "the same F-test on the record's slowest components alone or on the "
                        "rest alone (the smaller p, times two): an effect must stand out of "
                        "slow noise too; '-' where the first test already failed.",
    "held-out gain": "relative drop of the prewhitened squared error on held-out stretches "
                     "of the record (block cross-validation): 0.9 means the candidate "
                     "predicts data it was not fitted on with 90 % less error.",
    "folds improved": "share of the held-out stretches (folds) whose error went down.",
    "gap closed (rounds)": "RMS change of the fitted residual when the candidate is added, "
                           "over the RMS of the residual left (in units of the noise left); "
                           "a candidate must close at least the setting min_gap.",
    "AR orders": "order of the autoregressive model of each leg's residual used to "
                 "prewhiten it (0: white noise), one per leg 1..6.",
    "lag-1 autocorrelation": "correlation of each leg's residual with itself one sample "
                             "later (near 1: slow, structured residual).",
    "block bootstrap share": "share of resampled records (blocks of the record drawn with "
                             "replacement) in which the candidate reduced the error most.",
    "95% interval": "the parameter's 2.5 % and 97.5 % quantiles over the block bootstrap.",
    "concentration": "RMS of the residual in a band over its overall RMS (above 1: the gap "
                     "concentrates there).",
    "friction-like part": "the residual's mean signed by the direction of motion, N "
                          "(positive: more friction than the model).",
}
"""Each statistic the report prints, explained (the report's glossary)."""


def parameter_unit(effect: str, parameter: str) -> str:
    """Unit of an effect's parameter (``catalog.unit``)."""
    return catalog.unit(f"{effect}.{parameter}")


def units_of(effect: str, parameters) -> dict[str, str]:
    """Parameter -> unit of an effect's parameters."""
    return {p: parameter_unit(effect, p) for p in parameters}


def _effect(f: Finding) -> str:
    """``seal_friction (force = 12.3 N)``; many parameters as their range."""
    items = list(f.parameters.items())
    units = units_of(f.name, f.parameters)
    if len(items) <= 3:
        return f"{f.name} (" + ", ".join(
            f"{k} = {catalog.with_unit(v, units[k], 3)}" for k, v in items) + ")"
    values = [v for _, v in items]
    unit = units[items[0][0]]
    low, high = catalog.with_unit(min(values), "", 3), catalog.with_unit(max(values), unit, 3)
    return f"{f.name} ({items[0][0]}..{items[-1][0]} from {low} to {high})"


def noise_floor(d: DiscoveryRecord) -> float:
    """The noise floor the console line compares with, N RMS (``GLOSSARY``): the verdict's
    floor, or the force channels' high-frequency noise where no floor was made."""
    if d.noise is None:
        return float(d.noise_rms_estimate)
    if d.noise.floor is not None:
        return float(d.noise.floor.rms)
    return float(d.noise.high_frequency)


def gap_closed(d: DiscoveryRecord) -> float:
    """Share of the gap above the noise floor that the final model closes, 0..1."""
    floor = min(noise_floor(d), d.rms_after)
    closable = d.rms_before - floor
    return 0.0 if closable <= 0 else min(max((d.rms_before - d.rms_after) / closable, 0.0), 1.0)


def _refit_changes(d: DiscoveryRecord) -> list[str]:
    out = []
    for name, e in d.refit.parameters.items():
        final = e.final if e.final is not None else e.refit
        if final != e.model and not e.own_effect:
            unit = catalog.unit(name)
            out.append(f"{name} {catalog.with_unit(e.model, unit, 3)} -> "
                       f"{catalog.with_unit(final, unit, 3)}")
    return out


def verdict_line(d: DiscoveryRecord) -> str:
    """The answer in one line, e.g. ``explained: seal_friction (force = 12.3 N) and
    time_offset (delay = 4.1 ms) close 93 % of the gap; residual 0.11 N RMS vs noise floor
    0.10 N``."""
    tail = (f"residual {d.rms_after:.3g} N RMS (was {d.rms_before:.3g} N) vs noise floor "
            f"{noise_floor(d):.3g} N")
    effects = [_effect(f) for f in d.effects]
    named = " and ".join([", ".join(effects[:-1]), effects[-1]] if len(effects) > 1
                         else effects)
    closed = f"{100 * gap_closed(d):.0f} % of the gap"
    if d.verdict == "explained":
        if not effects:
            changes = "; ".join(_refit_changes(d)) or "the model's own parameters"
            return f"explained: refitting {changes} closes {closed}; {tail}"
        return f"explained: {named} close{'s' if len(effects) == 1 else ''} {closed}; {tail}"
    if d.verdict == "unexplained_discrepancy":
        lof = d.lack_of_fit
        left = (f"{lof.structure_rms:.3g} N RMS of structure left" if lof is not None
                and lof.structure_rms else "structure left")
        looks = f" ({lof.looks_like})" if lof is not None and lof.looks_like else ""
        part = f"; best partial candidates {named} close {closed}" if effects else ""
        return f"unexplained_discrepancy: {left} that no catalog effect explains{looks}{part}; " \
               f"{tail}"
    return f"no_discrepancy: model and data agree within the noise; {tail}"


def platform_text(d: DiscoveryRecord) -> str:
    """The final model as a commented platform TOML: where it came from (``d.source``,
    ``d.platform_source``), what changed from what, units in comments (reads back as
    ``d.platform``)."""
    before, after = _flat(d.model.to_dict()), _flat(d.platform.to_dict())
    notes, changed = {}, []
    for key, value in after.items():
        if key.startswith("effects."):
            continue
        if before.get(key) != value:
            notes[key] = f"refitted by discover, was {_short(before.get(key))}"
            changed.append(f"{key} {_short(before.get(key))} -> {_short(value)} "
                           f"{catalog.unit(key)}".rstrip())
    for f in d.effects:
        was = d.model.effects.get(f.name)
        notes[f"effects.{f.name}"] = (f"found by discover in round {f.evidence.round}"
                                      + (f", was {was}" if was else ""))
        changed.append(f"effect {f.name} switched on" if not was else f"effect {f.name} refitted")
    header = [f"Written by `gsfric discover` from the platform "
              f"{d.platform_source or '(the reference platform)'} and the record "
              f"{d.source or '(arrays)'}.",
              f"Verdict: {verdict_line(d)}"]
    header += ["Changed: " + (changed[0] if changed else "nothing")]
    header += [f"         {c}" for c in changed[1:]]
    header += ["Use it with `gsfric simulate --platform FILE`; report.md explains the fit."]
    return commented_toml(d.platform, header=header, notes=notes)


def _short(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else repr(value)


def _flat(data: dict, prefix: str = "") -> dict:
    """Dotted key -> leaf value of a platform's ``to_dict``."""
    out = {}
    for key, value in data.items():
        if isinstance(value, dict) and key in ("geometry", "platform", "legs", "friction",
                                              "effects", "limits") and not prefix:
            out.update(_flat(value, f"{key}."))
        else:
            out[prefix + key] = value
    return out
