"""report.md: the discovery's result for a reader, with the decisions explained
(``report``, also ``Discovery.report()``)."""

from __future__ import annotations

import math
import numpy as np

from gsfric.discovery.answer import GLOSSARY, units_of, verdict_line
from gsfric.discovery.regimes import hotspots
from gsfric.discovery.results import DiscoveryRecord
from gsfric.discovery.summary import per_leg_rms
from gsfric.platform import catalog



def _g(x, digits: int = 4) -> str:
    if x is None:
        return "-"
    if isinstance(x, (float, np.floating)):
        if not math.isfinite(x):
            return "-" if math.isnan(x) else ("inf" if x > 0 else "-inf")
        return f"{x:.{digits}g}"
    return str(x)


def _table(header: list[str], rows: list[list]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_g(c) for c in row) + " |" for row in rows]
    return lines + [""]


def report(d: DiscoveryRecord, figures: bool = True) -> str:
    """The readable report (Markdown): report.md's text; ``figures``: with the list of the
    plots written beside it (none with ``--no-plots``)."""
    L = _header(d)
    for section in (_unexplained, _effects_named, _disagreement, _own_parameters, _rounds,
                    _effects_found, _gaps, *((_plots,) if figures else ()), _method,
                    _glossary):
        L += section(d)
    return "\n".join(L)


def _header(d: DiscoveryRecord) -> list[str]:
    """Title, data and model."""
    L = ["# Discrepancy discovery", ""]
    n = d.used.stop - d.used.start
    model = d.platform_source or "reference platform"
    L += [f"Measured data: `{d.source or '(arrays)'}`; model: `{model}`.",
          f"Samples used: {n} ({d.used.start} left out at each end, where the pose's "
          f"differentiation is least accurate), {d.t[-1] - d.t[0]:.4g} s.", ""]
    L += ["## Result", "", f"Verdict: **{d.verdict}**.", "", f"> {verdict_line(d)}", ""]
    if d.verdict_reason:
        L += [f"Why: {d.verdict_reason}.", ""]
    return L


def _unexplained(d: DiscoveryRecord) -> list[str]:
    """An ``unexplained_discrepancy``: where the structure was found and what it looks like."""
    L: list[str] = []
    if d.structures:
        L += ["Structure in the final residual that no catalog effect explains (each found by "
              "a regression on a generic dictionary, accepted by the held-out rule the "
              "candidate effects face):", ""]
        L += [f"- **{s.kind}** on {', '.join(map(str, s.legs))}: {s.description} "
              f"({_g(s.size_rms, 3)} N RMS, {_g(s.gap, 3)} x the residual it leaves; "
              f"p = {_g(s.p_value, 2)} at level {_g(s.level, 2)}, held-out gain "
              f"{_g(s.cv_gain, 2)})" for s in d.structures]
        L.append("")
    if d.verdict == "unexplained_discrepancy" and d.lack_of_fit.source is not None:
        lof = d.lack_of_fit
        source = lof.source or "final residual"
        if source == "final residual":
            L += [f"The catalog does not explain the data: a structured residual of "
                  f"{_g(lof.structure_rms)} N RMS ({_g(lof.gap, 3)} x the noise "
                  f"left) remains, {lof.looks_like}. Per leg (N): "
                  f"{', '.join(_g(v, 3) for v in lof.per_leg_rms)}; dominant "
                  f"frequency of the residual {_g(lof.frequency, 3)} Hz.", ""]
        else:
            L += [f"The catalog does not explain the data: in {source}, a generic structure "
                  f"outside the catalog (mainly {lof.main_signal}) explains the gap as "
                  "well as the catalog's best candidate or better (see the round's table "
                  f"below), {lof.looks_like}. The final residual's own tests find "
                  "no structure by themselves: what the round found went into the effects "
                  "named, or is too slow to stand out of the noise alone. Dominant frequency "
                  f"of the residual {_g(lof.frequency, 3)} Hz.", ""]
        drift = lof.tests["drift"]
        if drift.significant:
            L += ["The friction-like part of the residual (signed by the direction of motion; "
                  "negative: less friction than the model) changes over the record "
                  f"(p = {_g(drift.p_value, 2)}); its mean per third of the record "
                  "(s: N): "
                  + ", ".join(f"{a:.3g}-{b:.3g}: {_g(v, 2)}"
                              for a, b, v in drift.details["levels"])
                  + ". A friction that drifts with time (a seal warming up) leaves this; every "
                  "catalog effect is one constant of the record.", ""]
        rev = lof.tests["reversal"]
        if rev.significant:
            L += ["After each reversal the residual, signed by the direction of travel (negative: "
                  "less friction than the model), depends on the travel since the reversal "
                  f"(p = {_g(rev.p_value, 2)}, {rev.details['reversals']} reversals); mean "
                  "per bin of travel (upper edge, mm: N): "
                  + ", ".join(f"{1e3 * e:.3g}: {_g(v, 2)}" for e, v in rev.details["profile"])
                  + ". Play in a joint or a pre-sliding friction leaves this; a friction given "
                  "by the speed does not.", ""]
    return L


def _effects_named(d: DiscoveryRecord) -> list[str]:
    """The effects named (or that none is missing), the gap and the notes."""
    L: list[str] = []
    if d.effects and d.verdict == "unexplained_discrepancy":
        L += ["The effects below are the best candidates for a part of the gap, not a "
              "confident explanation of it (`partial` in summary.json): structure is left that "
              "no catalog effect explains, or the named effect explains no more than a generic "
              "error outside the catalog would.", ""]
    if d.effects:
        for f in d.effects:
            units = units_of(f.name, f.parameters)
            params = ", ".join(f"{k} = {catalog.with_unit(v, units[k])}"
                               for k, v in f.parameters.items())
            twins = f.evidence.indistinguishable_from
            L.append(f"- **{f.name}** ({params}): effect size {_g(f.evidence.effect_size, 3)}"
                     f" x noise, found in round {f.evidence.round}"
                     + (f"; cannot be told apart from {', '.join(twins)}" if twins else ""))
    else:
        L.append("- No missing effect: after refitting the model's own parameters, no candidate "
                 "explains a significant part of the gap.")
    L += ["", f"Gap (RMS of the residual, all legs): **{_g(d.rms_before)} N** with the model as "
          f"given, {_g(d.rms_refit)} N after refitting its own parameters, **{_g(d.rms_after)} N**"
          f" with the effects found (RMS over the samples where the legs slide). "
          + _floor_text(d) + " Samples not sliding (speed within "
          f"the uncertainty of the differentiated poses): "
          f"{_g(d.noise.not_sliding_share, 3)} of the pairs.", ""]
    for note in d.notes:
        L.append(f"- Note: {note}")
    if d.notes:
        L.append("")
    return L


def _floor_text(d: DiscoveryRecord) -> str:
    """The noise floor in words: its two parts and their sources, the residual against it,
    and why the other two noise figures are not the floor."""
    floor = d.noise.floor
    force = float(np.sqrt(np.mean(np.square(floor.force))))
    pose = float(np.sqrt(np.mean(np.square(floor.pose))))
    return (f"Noise floor: **{_g(floor.rms)} N**, the load cells' noise {_g(force)} N "
            f"({floor.force_source}: {floor.force_detail}) with the pose noise in the model's "
            f"forces {_g(pose)} N ({floor.pose_source}); the final residual is "
            f"{_g(floor.residual_over_floor, 3)} x the floor. The force channels' "
            f"high-frequency part read alone ({_g(d.noise_rms_estimate)} N) counts the forces' "
            "own fast changes (friction steps at the reversals, a fast motion) as noise, and "
            f"the final residual corrected for the parameters fitted "
            f"({_g(d.noise.residual_corrected)} N) holds whatever the model misses: neither is "
            "the floor.")


def _disagreement(d: DiscoveryRecord) -> list[str]:
    """The bands where the model as given was furthest off."""
    L: list[str] = []
    L += ["## Where model and measurement disagreed", ""]
    spots = hotspots(d.regimes)
    if spots:
        L.append("Bands where the residual of the model as given was largest "
                 "(concentration = band RMS / overall RMS):")
        L.append("")
        L += _table(["regime", "band", "share", "RMS before (N)", "concentration",
                     "friction-like part (N)"],
                    [[b.regime, b.name, b.share, b.rms_before, b.concentration_before,
                      b.friction_before] for b in spots])
    else:
        L += ["The residual is spread evenly over every regime.", ""]
    return L


def _own_parameters(d: DiscoveryRecord) -> list[str]:
    """The refit of the model's own parameters."""
    L: list[str] = []
    L += ["## The model's own parameters", ""]
    rows = []
    for name, e in d.refit.parameters.items():
        lo, hi = e.plausible
        rows.append([name, catalog.unit(name) or "1", e.model, e.refit, e.final, e.unbounded,
                     f"[{_g(lo)}, {_g(hi)}]", "yes" if e.plausible_refit else "**no**"])
    if rows:
        L.append("Refitted first, within plausible ranges (a wrong coefficient is not a missing "
                 "effect), with the parameters of the effects the model already has (within "
                 "their physical bounds). *Unbounded* is the value a refit without limits would "
                 "need; where it is implausible, the gap it would close is left to the "
                 "candidate effects.")
        L.append("")
        L.append("Columns: *model* is the value in the platform as given; *refit* the value "
                 "after refitting the model's own parameters alone (within the plausible "
                 "range); *final* the value in the final model, refitted again together with "
                 "the effects found (so a refit that an effect explains better returns towards "
                 "the model's value); *unbounded* the value a refit without limits would need.")
        L.append("")
        L += _table(["parameter", "unit", "model", "refit", "final", "unbounded",
                     "plausible range", "plausible"], rows)
    return L


def _rounds(d: DiscoveryRecord) -> list[str]:
    """Each round's tests and decision."""
    L: list[str] = []
    L += ["## Rounds", "",
          "Each round fits every candidate effect left and adds the best accepted one. In the "
          "tables: *F*, *p* the nested F-test against the refitted model; *p slowest / rest* "
          "the same test on the record's slowest components alone or on the rest alone; "
          "*held-out gain* the relative drop of the error on stretches of the record left "
          "out of the fit; *folds improved* the share of those stretches that improved; "
          "*gap closed* the RMS the candidate removes over the RMS left. The *AR orders* "
          "are those of each leg's residual model used to prewhiten it. The glossary at the "
          "end explains each.", ""]
    for rnd in d.rounds:
        L.append(f"### Round {rnd.index}: "
                 + (f"**{rnd.winner}** added" if rnd.winner else "nothing significant; stop"))
        L.append("")
        L.append(f"Test level per candidate {_g(rnd.level, 3)} (alpha / number of candidates); "
                 f"residual AR orders {rnd.noise_model.ar_order}, lag-1 "
                 f"autocorrelations {rnd.noise_model.lag1_autocorrelation}.")
        L.append("")
        L += _table(["candidate", "F", "p", "p slowest / rest", "held-out gain",
                     "folds improved", "gap closed", "decision"],
                    [[t.name, t.F, t.p_value, t.p_bands if t.p_value < rnd.level else "-",
                      t.cv_gain, t.fold_share, t.gap, t.reason]
                     for t in sorted(rnd.tests, key=lambda t: -t.cv_gain)])
        if rnd.winner:
            if rnd.indistinguishable:
                L += [f"The data cannot tell {rnd.winner} apart from "
                      f"{', '.join(rnd.indistinguishable)}.", ""]
            if rnd.bootstrap_share:
                shares = ", ".join(f"{k} {v:.0%}" for k, v in rnd.bootstrap_share.items())
                L += [f"Block bootstrap, share of draws won: {shares}.", ""]
            L += [f"RMS residual {_g(rnd.rms_before)} N -> {_g(rnd.rms_after)} N.", ""]
    return L


def _effects_found(d: DiscoveryRecord) -> list[str]:
    """Each named effect: parameters, intervals and evidence."""
    L: list[str] = []
    if d.effects:
        L += ["## Effects found", ""]
        for f in d.effects:
            L.append(f"### {f.name}")
            L.append("")
            L.append(f.evidence.signature)
            L.append("")
            units = units_of(f.name, f.parameters)
            L += _table(["parameter", "unit", "value", "95% interval (block bootstrap)"],
                        [[k, units[k] or "1", v,
                          ("[" + ", ".join(_g(x) for x in f.interval[k]) + "]")
                          if k in f.interval else "fixed"] for k, v in f.parameters.items()])
            ev = f.evidence
            L.append(f"F = {_g(ev.F)}, p = {_g(ev.p_value, 3)} (level {_g(ev.level, 3)}),"
                     f" held-out gain {_g(ev.cv_gain, 3)}, folds improved "
                     f"{ev.fold_share:.0%}, bootstrap share {ev.bootstrap_share:.0%}, "
                     f"contribution {_g(ev.contribution_rms)} N RMS.")
            L.append("")
    return L


def _gaps(d: DiscoveryRecord) -> list[str]:
    """The gap per leg and per regime."""
    L: list[str] = []
    L += ["## Gap per leg", ""]
    before, after = per_leg_rms(d.residual_before), per_leg_rms(d.residual_after)
    L += _table(["leg", "RMS before (N)", "RMS after (N)"],
                [[i + 1, b, a] for i, (b, a) in enumerate(zip(before, after))])
    L += ["## Gap per regime", ""]
    L += _table(["regime", "band", "share", "RMS before (N)", "RMS after (N)",
                 "friction-like before (N)", "friction-like after (N)"],
                [[b.regime, b.name, b.share, b.rms_before, b.rms_after, b.friction_before,
                  b.friction_after] for b in d.regimes])
    return L


def _plots(d: DiscoveryRecord) -> list[str]:
    """The plots written beside the report."""
    return ["## Plots", "",
            "- `residuals_time.png`: residual of each leg over time, before and after.",
            "- `residuals_speed.png`: residual against the leg's sliding speed on a "
            "symmetric-log axis, linear within the Stribeck velocity scale "
            f"(+-{stribeck_scale(d):.3g} m/s, shaded) so that the low-speed band is readable "
            "(friction shows as a step or peak at zero speed).",
            "- `regimes.png`: RMS residual per band of each regime, before and after.", ""]


def _method(d: DiscoveryRecord) -> list[str]:
    """How the decisions are made."""
    L: list[str] = []
    L += ["## How the decisions are made", "",
          "Each candidate is fitted together with the refitted model parameters on a "
          "linearisation of the compiled model. The residual is prewhitened with an AR model "
          "per leg; a candidate is accepted when (1) the nested F-test on the prewhitened data "
          "gives p below alpha / K (Bonferroni over the K candidates), and so does the same "
          f"test on the record's {_count(d.settings.low_band)} slowest components per leg alone "
          "(the noise measured on them: slow noise is not an offset) or on the rest alone, "
          "(2) block cross-validation over contiguous stretches, each holding an equal share "
          "of the used pairs, shows a lower held-out error in "
          f"total and in at least {d.settings.min_fold_share:.0%} of the folds, and (3) it "
          f"closes a gap of at least {d.settings.min_gap:g} x the noise level. The accepted "
          "candidate with the largest held-out gain is added, refined by Gauss-Newton on the "
          "compiled model, and the next round starts; the workflow stops when no candidate is "
          "accepted. See docs/explanation/discovery.md.", ""]
    return L


def _count(n: int) -> str:
    """A count in words up to ten, else in digits."""
    words = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten")
    return words[n] if 0 <= n < len(words) else str(n)


def _glossary(d: DiscoveryRecord) -> list[str]:
    """What each statistic of the report means."""
    return ["## Glossary", ""] + [f"- **{term}**: {text}" for term, text in GLOSSARY.items()] + [""]


def stribeck_scale(d: DiscoveryRecord) -> float:
    """The speed scale of the low-speed friction, m/s: the Stribeck velocity found, or the
    model's, or the catalog's default (the linear band of the speed plot's axis)."""
    for f in d.effects:
        if f.name == "stribeck":
            return float(f.parameters["velocity"])
    if "stribeck" in d.model.effects:
        return float(d.model.effects["stribeck"]["velocity"])
    return float(catalog.EFFECTS["stribeck"]["velocity"])
