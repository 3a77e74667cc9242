"""The workflow's last stage: the final fit's findings, its residual's tests and the verdict.

The named effects get block-bootstrap intervals, their stability across the record's halves,
their size and contribution; the final residual is tested for structure the model misses
(``final_tests.lack_of_fit``, ``dictionary.find``), compared with the noise floor
(``floor``), and the verdict (``verdict.decide``) and the regimes close the ``Discovery``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gsfric.discovery import dictionary, outside
from gsfric.discovery import statistics as st
from gsfric.discovery.candidates import CANDIDATES
from gsfric.discovery.final_tests import LackOfFit, lack_of_fit
from gsfric.discovery.floor import (
    NoiseFloor,
    estimated_force_noise,
    noise_floor,
    pose_noise_forces,
)
from gsfric.discovery.outcome import Discovery
from gsfric.discovery.refine import Refined, half_stability
from gsfric.discovery.refit import Refit
from gsfric.discovery.regimes import bands as regime_bands
from gsfric.discovery.residuals import Problem
from gsfric.discovery.results import (
    NOISE_METHOD,
    Finding,
    NoiseEstimate,
    RefitReport,
    Round,
)
from gsfric.discovery.rounds import Rounds
from gsfric.discovery.selection import noise_model
from gsfric.discovery.verdict import Verdict, decide
from gsfric.platform.catalog import EFFECTS
from gsfric.platform.description import Platform
from gsfric.signal.noise import ForceNoise
from gsfric.trajectory import Motion


@dataclass(frozen=True)
class Given:
    """What the user gave besides the data and the model.

    Attributes
    ----------
    force_noise : ForceNoise or None
        The load cells' noise (None: estimated from the final residual).
    seed : int
        Seed of the pose noise's draws of the floor.
    platform_source : str
        The platform file of the model as given ("": a Platform or the reference platform).
    """

    force_noise: ForceNoise | None = None
    seed: int = 0
    platform_source: str = ""


@dataclass(frozen=True)
class _Final:
    """The final fit (``_findings``): the named effects, the refit report with its final
    values, intervals and alternatives, the final model, and the noise level of the final
    residual corrected for the parameters fitted (N)."""

    findings: list[Finding]
    refit: RefitReport
    platform: Platform
    noise: float


def conclude(problem: Problem, motion: Motion, platform: Platform, refit: Refit,
             found: Rounds, rng: np.random.Generator, given: Given) -> Discovery:
    """The ``Discovery`` of the fit ``found`` after ``refit``: the final fit's intervals
    (drawn with ``rng``) and findings, the lack-of-fit tests of its residual, the verdict and
    the regimes; ``platform`` is the model as given. Its notes: the candidates not tested,
    then the refit's, the rounds' and the final fit's."""
    settings, model, used, sliding = problem.settings, problem.model, problem.used, problem.sliding
    fit = found.fit
    residual_after = fit.r
    whitener = st.Whitener.fit(residual_after, settings.max_order, valid=sliding)
    final = _findings(problem, fit, found, refit.report, whitener, rng)
    notes = ([f"candidate {n} not tested: {why}" for n, why in problem.skipped.items()]
             + list(refit.notes) + list(found.notes)
             + _final_notes(problem, found, len(refit.residual_before)))
    full_after = problem.y - model.forces(fit.theta)[used]
    lof = lack_of_fit(problem, fit.theta, residual_after,
                      in_model=[c.name for c in problem.own_effects] + list(found.active))
    rms_after = st.rms(residual_after[sliding])
    independent = float(np.sqrt(np.mean(problem.force_noise ** 2)))
    floor = _floor(problem, motion, final.platform, full_after, rms_after,
                   force_noise=given.force_noise, seed=given.seed)
    features = dictionary.Features.of(problem, motion, fit.theta, floor.force)
    structures = dictionary.find(residual_after, features, settings)
    notes += _imitator_notes(found.rounds)
    lof = _sourced(lof, found.rounds)
    decision = _verdict(problem, refit, found, lof, rms_after, floor, structures, whitener)
    table = regime_bands(np.asarray(motion.t[used]), problem.result.D_dot[used],
                         problem.result.D[used], problem.result.F[used],
                         motion.rotation[used], refit.residual_before, residual_after,
                         settings)
    return Discovery(
        effects=final.findings, refit=final.refit, rounds=list(found.rounds),
        rms_before=st.rms(refit.residual_before[sliding]), rms_refit=refit.rms_refit,
        rms_after=rms_after, noise_rms_estimate=independent,
        t=np.asarray(motion.t[used]), residual_before=refit.residual_before,
        residual_after=residual_after, used=used, model=platform, platform=final.platform,
        result_before=problem.result, noise_model=noise_model(whitener), regimes=table,
        settings=settings, evaluations=model.evaluations, notes=notes,
        verdict=decision.verdict, lack_of_fit=lof,
        noise=_noise_info(problem, independent, final.noise, whitener, floor),
        rms_after_all=st.rms(full_after), sliding=sliding, structures=structures,
        verdict_reason=decision.reason, verdict_decided_by=decision.decided_by,
        platform_source=given.platform_source, forces=problem.y,
        forces_after=problem.y - full_after, motion=motion)


def _findings(problem: Problem, fit: Refined, found: Rounds, report: RefitReport,
              whitener: st.Whitener, rng: np.random.Generator) -> _Final:
    """The named effects with their bootstrap intervals (drawn with ``rng``), stability, size
    and contribution; the refit report with the final values, intervals and the first round's
    alternatives; the final platform and the noise level of the final residual."""
    theta, names, r = fit.theta, list(fit.names), fit.r
    model = problem.model
    intervals = _intervals(problem, fit.J, names, whitener, r, rng, theta)
    stability = {name: half_stability(problem, fit.J, r, names, name, whitener)
                 for name in found.active}
    rows = int(np.count_nonzero(problem.sliding))
    noise = float(np.sqrt(np.sum(r ** 2) / max(rows - len(names), 1)))
    final = model.platform_at(theta, list(dict.fromkeys(
        [c.name for c in problem.own_effects] + list(found.active))))
    contributions = _contributions(problem, theta, found.active)
    findings = []
    for name in found.active:
        c = next(c for c in CANDIDATES if c.name == name)
        size = st.rms(contributions[name])
        evidence = dataclasses.replace(
            found.evidence[name], stability=stability[name],
            effect_size=size / noise if noise > 0 else float("inf"), contribution_rms=size)
        findings.append(Finding(name, {p: float(v) for p, v in final.effects[name].items()},
                                {p: intervals[f"{name}.{p}"] for p in c.fitted + c.refined},
                                evidence, contribution=contributions[name]))
    parameters = {
        name: dataclasses.replace(entry,
                                  alternatives=found.alternatives.get(name, entry.alternatives),
                                  final=float(theta[model.index[name]]),
                                  interval=intervals.get(name))
        for name, entry in report.parameters.items()}
    return _Final(findings, dataclasses.replace(report, parameters=parameters), final, noise)


def _final_notes(problem: Problem, found: Rounds, samples: int) -> list[str]:
    """Notes on a workflow stopped by ``max_effects`` and on the used ``samples`` that the
    model flags."""
    settings, rounds, notes = problem.settings, found.rounds, []
    if (len(found.active) == settings.max_effects and rounds
            and rounds[-1].winner is not None):
        notes.append(f"stopped after {settings.max_effects} effects (max_effects)")
    flagged = int(np.count_nonzero(problem.result.flag[problem.used]))
    if flagged:
        notes.append(
            f"{flagged} of {samples} samples are flagged by the model "
            "(see gsfric.evaluation: stroke, near-singular poses); they are kept")
    return notes


def _noise_info(problem: Problem, independent: float, noise: float,
                whitener: st.Whitener, floor: NoiseFloor) -> NoiseEstimate:
    """summary.json's ``noise``: the force noise from the force channels alone
    (``independent``, N), from the final residual (``noise``, N), the final noise model's
    innovations, the speed uncertainty, the share of pairs that do not slide and the noise
    floor of the verdict."""
    return NoiseEstimate(
        high_frequency=independent,
        high_frequency_per_leg=[float(v) for v in problem.force_noise],
        residual_corrected=noise,
        innovation_std=[float(v) for v in whitener.innovation_std],
        method=NOISE_METHOD,
        speed_uncertainty=[float(v) for v in problem.sigma_v],
        not_sliding_share=float(1.0 - problem.sliding.mean()), floor=floor)


def _floor(problem: Problem, motion: Motion, final: Platform, full_after: np.ndarray,
           rms_after: float, *, force_noise: ForceNoise | None = None, seed: int = 0
           ) -> NoiseFloor:
    """The noise floor of the verdict (``floor``): the user's ``force_noise`` or its estimate
    from the final model's residual over every used pair (``full_after`` (M, 6), N), and the
    pose noise through the final model (drawn with ``seed``)."""
    s = problem.settings
    t = np.asarray(motion.t, float)
    step = (t[-1] - t[0]) / max(len(t) - 1, 1)
    estimate = estimated_force_noise(full_after, step, s.floor_segment)
    pose, how = pose_noise_forces(final, motion, problem.poses, problem.used,
                                  problem.sliding, s.floor_draws, seed=seed,
                                  n_threads=problem.model.n_threads)
    return noise_floor(force_noise, estimate, pose, how, rms_after)


def _imitator_notes(rounds: Sequence[Round]) -> list[str]:
    """A note for each named effect that only imitates a generic out-of-catalog structure."""
    notes = []
    for name in [rnd.winner for rnd in rounds if rnd.winner and rnd.imitates]:
        rnd = next(x for x in rounds if x.winner == name)
        main = rnd.generic.main_signal
        notes.append(
            f"round {rnd.index}: {name} explains nothing that a generic out-of-catalog structure "
            f"(mainly {main}: {outside.looks_like('basis', main)}) "
            "does not explain as well or better: the data cannot tell "
            f"{name} from an error outside the catalog; it is named as the simpler explanation, "
            "the verdict is not 'explained'")
    return notes


def _structure_round(rounds: Sequence[Round]) -> Round | None:
    """The first round that found a generic structure: one that blocks its winner, that its
    winner only imitates, or that a slow part fits."""
    return next((rnd for rnd in rounds if rnd.slow or rnd.blocked_by_generic
                 or (rnd.winner and rnd.imitates)), None)


def _sourced(lof: LackOfFit, rounds: Sequence[Round]) -> LackOfFit:
    """The lack-of-fit summary ``lof`` with its ``source``: the final residual when its tests
    found structure; else the round that found a generic structure (``_structure_round``),
    whose generic signal then says what the ``unexplained_discrepancy`` is, instead of the
    final basis's weaker signals; else none."""
    if lof.significant:
        return dataclasses.replace(lof, source="final residual")
    rnd = _structure_round(rounds)
    if rnd is None:
        return dataclasses.replace(lof, source=None)
    main = rnd.generic.main_signal if rnd.generic is not None else None
    return dataclasses.replace(lof, source=f"round {rnd.index}", main_signal=main,
                               looks_like=outside.looks_like("basis", main))


def _verdict(problem: Problem, refit: Refit, found: Rounds, lof: LackOfFit, rms_after: float,
             floor: NoiseFloor, structures: list, whitener: st.Whitener) -> Verdict:
    """The verdict and its reason (``verdict.decide``): structure in the final residual
    (the dictionary's, the lack-of-fit tests', or a round's generic structure: ``lof``,
    ``_sourced``, then says which), a residual above the floor the user gave, effects named,
    or a significant refit that closes ``min_gap``."""
    found_structure = lof.significant or _structure_round(found.rounds) is not None
    sliding = problem.sliding
    closed = np.sqrt(max(st.rms(refit.residual_before[sliding]) ** 2 - rms_after ** 2, 0.0))
    refit_closes = bool(closed >= problem.settings.min_gap * rms_after
                        and refit.report.test.significant)
    return decide(structures=structures, structure_found=found_structure,
                  structure_text=lof.looks_like if found_structure else "", floor=floor,
                  ratio_limit=problem.settings.floor_ratio, named=list(found.active),
                  refit_closes=refit_closes, noise=noise_model(whitener))


def _contributions(problem: Problem, theta: np.ndarray, active: Sequence[str]
                   ) -> dict[str, np.ndarray]:
    """Each named effect's contribution to F (M, 6), N, at theta (F minus F with it
    switched off)."""
    if not active:
        return {}
    model = problem.model
    thetas = [theta]
    for name in active:
        off = theta.copy()
        for p, d in EFFECTS[name].items():
            off[model.index[f"{name}.{p}"]] = d
        thetas.append(off)
    F = model.forces_batch(np.stack(thetas))[:, problem.used]
    return {name: F[0] - F[k + 1] for k, name in enumerate(active)}


def _intervals(problem: Problem, J: np.ndarray, names: list[str], whitener: st.Whitener,
               residual: np.ndarray, rng: np.random.Generator, theta: np.ndarray
               ) -> dict[str, tuple[float, float]]:
    """95% block-bootstrap intervals of the fitted parameters, linearised at theta.

    J (M, 6, k) holds the derivatives of F with respect to ``names`` at theta, used samples.
    """
    if not names:
        return {}
    model = problem.model
    s = problem.settings
    blocks = st.Blocks.whitened(whitener, J, residual, s.n_blocks, ridge=s.ridge)
    cols = [model.index[n] for n in names]
    lo = np.array([problem.bounds(n)[0] for n in names]) - theta[cols]
    hi = np.array([problem.bounds(n)[1] for n in names]) - theta[cols]
    draws = []
    for w in st.bootstrap_weights(rng, s.n_blocks, s.n_bootstrap):
        draws.append(st.fit(blocks, list(range(len(names))), lo, hi, w).coef)
    draws = np.array(draws) + theta[cols]
    q = np.percentile(draws, [2.5, 97.5], axis=0)
    return {n: (float(q[0, k]), float(q[1, k])) for k, n in enumerate(names)}
