"""The discrepancy workflow: refit the model, test the candidate effects, add the winner, repeat.

Steps (docs/explanation/discovery.md explains each decision):

1. Simulate the measured motion with the current model; residuals ``r = F_measured - F_model``
   per leg. The first and last ``trim`` samples, where the differentiation of the recorded pose
   is least accurate, are left out of every fit and statistic.
2. Refit the model's own parameters (``REFIT``: prismatic friction coefficients, payload mass,
   plus the parameters of any effect the model already has) within their plausible ranges. A
   refit that would need an implausible value is reported as such; it is held at the range's
   edge and the rest of the gap is left to the candidates.
3. Round after round: linearise the model at the current parameters (compiled Jacobian),
   prewhiten with an AR model of the residual, and test every candidate effect against the
   refitted model with (a) a nested F-test on the prewhitened data at level ``alpha / K`` (K
   candidates: Bonferroni), (b) block cross-validation: the held-out prewhitened error must
   shrink, in total and in most folds, and (c) the gap it closes must reach ``min_gap`` times
   the noise level. The accepted candidate with the largest held-out gain wins; accepted
   candidates to which the winner adds nothing significant are reported as "cannot be told
   apart". The AR model is re-estimated from the winner's residual and the round repeated
   until the winner is stable (Cochrane-Orcutt).
4. Refine the winner and the refitted parameters by Gauss-Newton on the compiled model, add
   the winner, and start the next round; stop when no candidate is significant.
5. Block bootstrap of the final fit: how often each effect wins, and parameter intervals.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from tqdm import tqdm

from gsfric._checks import short
from gsfric._threads import one_blas_thread
from gsfric.discovery import dictionary, lackfit
from gsfric.discovery import statistics as st
from gsfric.discovery.candidates import CANDIDATES
from gsfric.discovery.evidence import Evidence, Rule, accept
from gsfric.discovery.final_tests import LackOfFit, lack_of_fit
from gsfric.discovery.floor import (
    ForceNoise,
    NoiseFloor,
    estimated_force_noise,
    noise_floor,
    pose_noise_forces,
)
from gsfric.discovery.outcome import Discovery
from gsfric.discovery.refine import half_stability, refine
from gsfric.discovery.regimes import bands as regime_bands
from gsfric.discovery.residuals import Problem, checked_forces
from gsfric.discovery.results import (
    NOISE_METHOD,
    Finding,
    FindingEvidence,
    NoiseEstimate,
    RefitParameter,
    RefitReport,
    RefitTest,
    Round,
)
from gsfric.discovery.selection import (
    bootstrap_share,
    generic_competitor,
    indistinguishable,
    low_band_of,
    noise_model,
    refit_alternatives,
    screen_candidates,
    winner_of,
)
from gsfric.discovery.settings import Settings
from gsfric.discovery.verdict import Verdict, decide
from gsfric.errors import InputTypeError
from gsfric.evaluation.flags import check_flagged, flag_counts
from gsfric.models import platform_from
from gsfric.platform.catalog import EFFECTS
from gsfric.platform.description import Platform
from gsfric.platform.usable import check_forces, check_poses
from gsfric.trajectory import Motion

# -- the workflow -------------------------------------------------------------------------------


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r ** 2)))


@dataclass
class _State:
    """The workflow between its stages: the parameters fitted so far and what was found.

    ``theta`` (n_theta,) holds the parameters, ``names`` those fitted, ``r`` (M, 6) the
    residual there (N) and ``J`` (M, 6, len(names)) its derivatives; ``refit`` the report of
    the model's own parameters (``Discovery.refit``); ``active`` the effects named, ``dropped``
    the winners that, refined, did not lower the residual; ``evidence`` each named effect's
    evidence (``Finding.evidence``); ``force_noise`` the load cells' noise the user gave,
    ``seed`` the seed of the pose noise's draws."""

    problem: Problem
    rng: np.random.Generator
    theta0: np.ndarray
    notes: list[str]
    theta: np.ndarray | None = None
    r: np.ndarray | None = None
    J: np.ndarray | None = None
    names: list[str] = field(default_factory=list)
    residual_before: np.ndarray | None = None
    rms_refit: float = 0.0
    refit: RefitReport = field(default_factory=RefitReport)
    active: list[str] = field(default_factory=list)
    dropped: list[str] = field(default_factory=list)
    rounds: list[Round] = field(default_factory=list)
    evidence: dict[str, FindingEvidence] = field(default_factory=dict)
    force_noise: ForceNoise | None = None
    seed: int = 0


@one_blas_thread
def discover_motion(motion: Motion, forces: np.ndarray, platform: Platform | None = None, *,
             settings: Settings | None = None, seed: int = 0, progress: bool = False,
             poses: tuple[np.ndarray, np.ndarray] | None = None,
             force_noise: ForceNoise | None = None, **options) -> Discovery:
    """Find which effects the model misses, fit them, and measure how much of the gap closes.

    Parameters
    ----------
    motion : Motion
        The measured motion (N steps), e.g. from ``gsfric.io.read_measured``.
    forces : ndarray, shape (N, 6)
        Measured actuator forces F1..F6, N (friction included).
    platform : Platform, optional
        The current model (default: ``gsfric.models.platform_from(None)``).
    settings : Settings, optional
    seed : int
        Seed of the block bootstrap.
    progress : bool
        Show progress on stderr.
    poses : (ndarray (N, 3), ndarray (N, 3, 3)), optional
        The recorded (unsmoothed) positions (m) and rotations, from which the pose noise and
        the uncertainty of the leg speeds are estimated (``rest.speed_uncertainty``; see
        ``rest.poses_from_columns``). Default: the samples the motion was made from
        (``Motion.recorded_poses``), else its smoothed poses, which underestimate it.
    force_noise : ForceNoise, optional
        The load cells' noise as the user gives it (a specification, a recording at rest):
        the force part of the noise floor the verdict compares the residual with
        (``floor``); default: estimated from the force channels.
    **options
        Fields of ``Settings`` overriding ``settings``.

    Returns
    -------
    Discovery

    Raises
    ------
    InputTypeError
        ``motion`` not a Motion, ``platform`` not a Platform, path or None, an unknown option.
    InputError
        ``forces`` of the wrong shape or type, mostly unusable data (NaN, dead or saturated
        channels), a bad setting; each in one line.
    """
    if not isinstance(motion, Motion):
        raise InputTypeError(f"discover: motion must be a gsfric.Motion, got {short(motion)} "
                             "(gsfric.io.read_measured)")
    unknown = sorted(set(options) - {f.name for f in dataclasses.fields(Settings)})
    if unknown:
        raise InputTypeError(f"discover: unknown option {unknown[0]!r} (a Settings field "
                             "name)")
    settings = dataclasses.replace(settings or Settings(), **options)
    platform_source = str(platform) if isinstance(platform, (str, os.PathLike)) else ""
    platform = platform_from(platform)
    forces = checked_forces(motion, forces, settings)
    recorded = poses if poses is not None else motion.recorded_poses()
    check_poses(platform, *(recorded if recorded is not None else (motion.position,
                                                                   motion.rotation)), motion.t)
    check_forces(platform, forces)
    if force_noise is not None:
        force_noise.check_at_rest(settings.record_travel, settings.record_turn)
        force_noise.check_plausible(forces, settings.noise_spread)
    bar = _Progress(progress, settings.max_effects + 3)
    bar.step("simulating the model along the measured motion")
    problem = Problem(motion, forces, platform, settings, poses=poses)
    used_flags = problem.result.flag[problem.used]
    check_flagged(platform, flag_counts(used_flags), int(np.count_nonzero(used_flags)),
                  len(used_flags))
    state = _State(problem, np.random.default_rng(seed), problem.model.theta0.copy(),
                   notes=[f"candidate {n} not tested: {why}"
                          for n, why in problem.skipped.items()], force_noise=force_noise,
                   seed=seed)
    bar.step("refitting the model's own parameters")
    _refit_own_parameters(state)
    while len(state.active) < settings.max_effects:
        candidates = [c for c in problem.candidates
                      if c.name not in state.active + state.dropped]
        if not candidates:
            break
        bar.step(f"round {len(state.rounds) + 1}: testing {len(candidates)} candidate effects")
        if not _round(state, candidates):
            break
    bar.step("bootstrap of the final fit")
    result = _final(state, motion, platform)
    result.platform_source = platform_source
    bar.close()
    return result


def _refit_own_parameters(state: _State) -> None:
    """Stage 1: the refit of the model's own parameters (``REFIT`` and the parameters of the
    effects it has), with the unbounded values it would need and its test; sets the state's
    parameters, residual and Jacobian."""
    problem, theta0 = state.problem, state.theta0
    model = problem.model
    names = problem.refit_names([])
    F0, J0 = model.jacobian(theta0, names, rows=problem.used)
    residual_before = problem.mask(problem.y - F0[problem.used])
    J0 *= problem.weight[:, :, None]
    whitener = _largest_model_whitener(problem, residual_before, J0)
    # the refit's columns prewhitened once, for its unbounded values and for its test
    s = problem.settings
    refit_blocks = st.Blocks.whitened(whitener, J0, residual_before, s.n_blocks, ridge=s.ridge,
                                      low=low_band_of(problem, whitener))
    refit, notes = _refit_report(problem, theta0, refit_blocks)
    refit.test = _refit_test(problem, refit_blocks)
    del refit_blocks
    theta, r, J = refine(problem, theta0, names, whitener, start=(residual_before, J0))
    del J0
    for name in names:
        value = float(theta[model.index[name]])
        if name in refit.parameters:
            refit.parameters[name].refit = value
        else:
            refit.parameters[name] = RefitParameter(
                float(theta0[model.index[name]]), value, None, list(problem.bounds(name)),
                True, own_effect=True)
    state.notes += notes
    state.theta, state.r, state.J, state.names = theta, r, J, names
    state.residual_before, state.refit = residual_before, refit
    state.rms_refit = _rms(r[problem.sliding])


def _round(state: _State, candidates: list) -> bool:
    """Stage 2, once per round: test the candidates, choose the winner, refine and add it.
    Returns whether another round follows."""
    problem = state.problem
    design, whitener, screen, winner = _screen_round(state, candidates)
    level = problem.settings.alpha / len(candidates)
    rnd = Round(len(state.rounds) + 1, list(screen.tests.values()), winner, level=level,
                noise_model=noise_model(whitener), rms_before=_rms(design.r[problem.sliding]))
    state.rounds.append(rnd)
    if winner is None:
        rnd.rms_after = rnd.rms_before
        _slow_structure(problem, design, whitener, screen, rnd, state.notes)
        return False
    winner, p_alone = _prefer_simplest(problem, design, screen, rnd, candidates)
    rnd.generic = generic_competitor(problem, design, whitener, screen, winner)
    if rnd.generic.blocked:
        rnd.blocked, rnd.winner = winner, None
        rnd.rms_after = rnd.rms_before
        state.notes.append(
            f"round {rnd.index}: {winner} was significant but adds nothing to a generic "
            f"out-of-catalog structure (mainly {rnd.generic.main_signal}), which "
            "explains more: not named")
        return False
    rnd.bootstrap_share = bootstrap_share(problem, design, screen, state.rng)
    start = _winner_start(problem, design, screen, winner)
    test = screen.tests[winner]
    del design, screen     # free the round's design before the refinement
    _refine_winner(state, rnd, start, whitener, test, p_alone,
                   next(c for c in candidates if c.name == winner))
    return True


def _screen_round(state: _State, candidates: list):
    """A round's design, noise model, tests and winner: the candidates screened against the
    refitted model, the noise model re-estimated from the winner's residual and the screen
    repeated until the winner is stable (Cochrane-Orcutt, at most three times); in the first
    round, the refitted changes that a candidate explains as well are noted."""
    problem = state.problem
    design = problem.linearise(state.theta, state.active, candidates)
    whitener = _noise_whitener(design, problem)
    screen = screen_candidates(problem, design, whitener, candidates)
    if not state.rounds:
        for name, alts in refit_alternatives(problem, design, screen, state.theta0).items():
            state.refit.parameters[name].alternatives = alts
            state.notes.append(f"the refitted change of {name} could equally be explained by "
                               f"{', '.join(alts)}: the data cannot tell them apart")
    winner = winner_of(screen)
    seen = [winner]
    for _ in range(3):
        if winner is None:
            break
        fit = screen.fits[winner]
        r_alt = design.r - design.X[:, :, fit.columns] @ fit.coef
        whitener = st.Whitener.fit(r_alt, problem.settings.max_order, valid=problem.sliding)
        screen = screen_candidates(problem, design, whitener, candidates)
        new = winner_of(screen)
        if new == winner:
            break
        winner = new
        if winner in seen:
            break
        seen.append(winner)
    return design, whitener, screen, winner


def _prefer_simplest(problem: Problem, design, screen, rnd: Round, candidates: list
                     ) -> tuple[str, dict[str, float]]:
    """Parsimony: of the explanations the data cannot tell apart from the round's winner, the
    simpler one (``Candidate.simpler``, then fewer parameters). Sets the round's
    ``indistinguishable`` (and ``winner``, ``preferred_over`` when another is preferred);
    returns the winner and the p-values of it beyond each of the others."""
    winner = rnd.winner
    rnd.indistinguishable, p_alone = indistinguishable(problem, design, screen, winner)
    if not rnd.indistinguishable:
        return winner, p_alone
    group = [winner] + list(rnd.indistinguishable)
    rank = {c.name: (c.simpler, len(c.fitted)) for c in candidates}
    simplest = min(group, key=lambda n: rank[n])
    if rank[simplest] < rank[winner]:
        rnd.preferred_over = winner
        winner = rnd.winner = simplest
        rnd.indistinguishable, p_alone = indistinguishable(problem, design, screen, winner)
        if rnd.preferred_over not in rnd.indistinguishable:
            rnd.indistinguishable.append(rnd.preferred_over)
    return winner, p_alone


def _winner_start(problem: Problem, design, screen, winner: str) -> np.ndarray:
    """The parameters from which the winner is refined: the design's, with the winner's
    linearised values and the refitted parameters stepped by their fit beside it."""
    index = problem.model.index
    start = design.theta.copy()
    for p, v in screen.tests[winner].parameters.items():
        start[index[f"{winner}.{p}"]] = v
    step_fit = screen.fits[winner]
    for col, step in zip(step_fit.columns, step_fit.coef):
        if col in design.refit:
            start[index[design.names[col]]] += design.signs[col] * step
    return start


def _refine_winner(state: _State, rnd: Round, start: np.ndarray, whitener: st.Whitener,
                   test, p_alone: dict[str, float], c) -> None:
    """Refine the winner ``c`` with the refitted parameters by Gauss-Newton on the compiled
    model and add it, with its evidence; a winner that, refined, does not lower the residual
    is dropped (the round repeated without it)."""
    problem, winner = state.problem, c.name
    new_names = problem.refit_names(state.active + [winner])
    theta_new, r_new, J_new = refine(problem, start, new_names, whitener)
    rnd.rms_after = _rms(r_new[problem.sliding])
    if rnd.rms_after >= rnd.rms_before:
        # refined on the compiled model, the effect no longer shrinks the gap (a change of
        # the refitted parameters that the linearised screening did not foresee); it says
        # nothing of the other candidates: the round is repeated without it
        state.notes.append(f"round {rnd.index}: {winner} refined on the compiled model does "
                           f"not lower the residual ({rnd.rms_before:.4g} N -> "
                           f"{rnd.rms_after:.4g} N): not named, the round repeated without it")
        rnd.blocked, rnd.winner, rnd.rms_after = winner, None, rnd.rms_before
        state.dropped.append(winner)
        return
    state.theta, state.r, state.J, state.names = theta_new, r_new, J_new, new_names
    state.active.append(winner)
    state.evidence[winner] = FindingEvidence(
        round=rnd.index, F=test.F, p_value=test.p_value, dof=test.dof, level=rnd.level,
        cv_gain=test.cv_gain, fold_share=test.fold_share,
        bootstrap_share=rnd.bootstrap_share.get(winner, 0.0),
        indistinguishable_from=list(rnd.indistinguishable), preferred_over=rnd.preferred_over,
        p_value_beyond=dict(p_alone), rms_before=rnd.rms_before, rms_after=rnd.rms_after,
        signature=c.signature)


def _final(state: _State, motion: Motion, platform: Platform) -> Discovery:
    """Stage 3: the final fit's intervals and findings, the lack-of-fit tests of its
    residual, the verdict and the regimes."""
    problem, settings = state.problem, state.problem.settings
    model, used, sliding = problem.model, problem.used, problem.sliding
    residual_after = state.r
    whitener = st.Whitener.fit(residual_after, settings.max_order, valid=sliding)
    findings, final, noise = _findings(state, whitener)
    _final_notes(state)
    full_after = problem.y - model.forces(state.theta)[used]
    lof = lack_of_fit(problem, state.theta, residual_after,
                      in_model=[c.name for c in problem.own_effects] + state.active)
    rms_after = _rms(residual_after[sliding])
    independent = float(np.sqrt(np.mean(problem.force_noise ** 2)))
    floor = _floor(state, motion, final, full_after, rms_after)
    noise_info = _noise_info(problem, independent, noise, whitener, floor)
    features = dictionary.Features.of(problem, motion, state.theta, floor.force)
    structures = dictionary.find(residual_after, features, settings)
    _imitator_notes(state)
    decision = _verdict(state, lof, rms_after, floor, structures, whitener)
    verdict = decision.verdict
    table = regime_bands(np.asarray(motion.t[used]), problem.result.D_dot[used],
                         problem.result.D[used], problem.result.F[used],
                         motion.rotation[used], state.residual_before, residual_after,
                         settings)
    return Discovery(
        effects=findings, refit=state.refit, rounds=state.rounds,
        rms_before=_rms(state.residual_before[sliding]), rms_refit=state.rms_refit,
        rms_after=rms_after, noise_rms_estimate=independent,
        t=np.asarray(motion.t[used]), residual_before=state.residual_before,
        residual_after=residual_after, used=used, model=platform, platform=final,
        result_before=problem.result, noise_model=noise_model(whitener), regimes=table,
        settings=settings, evaluations=model.evaluations, notes=state.notes, verdict=verdict,
        lack_of_fit=lof, noise=noise_info, rms_after_all=_rms(full_after), sliding=sliding,
        structures=structures, verdict_reason=decision.reason,
        verdict_decided_by=decision.decided_by, forces=problem.y,
        forces_after=problem.y - full_after, motion=motion)


def _findings(state: _State, whitener: st.Whitener) -> tuple[list[Finding], Platform, float]:
    """The named effects with their bootstrap intervals, stability, size and contribution;
    the refit's final values and intervals. Returns the findings, the final platform and the
    noise level of the final residual corrected for the parameters fitted (N)."""
    problem, theta, names, r = state.problem, state.theta, state.names, state.r
    model = problem.model
    intervals = _intervals(problem, state.J, names, whitener, r, state.rng, theta)
    for name in state.active:
        state.evidence[name].stability = half_stability(problem, state.J, r, names, name,
                                                           whitener)
    rows = int(np.count_nonzero(problem.sliding))
    noise = float(np.sqrt(np.sum(r ** 2) / max(rows - len(names), 1)))
    final = model.platform_at(theta, list(dict.fromkeys(
        [c.name for c in problem.own_effects] + state.active)))
    contributions = _contributions(problem, theta, state.active)
    findings = []
    for name in state.active:
        c = next(c for c in CANDIDATES if c.name == name)
        params = {p: float(v) for p, v in final.effects[name].items()}
        ev = state.evidence[name]
        ev.effect_size = _rms(contributions[name]) / noise if noise > 0 else float("inf")
        ev.contribution_rms = _rms(contributions[name])
        findings.append(Finding(name, params,
                                {p: intervals[f"{name}.{p}"] for p in c.fitted + c.refined},
                                ev, contribution=contributions[name]))
    for name, entry in state.refit.parameters.items():
        entry.final = float(theta[model.index[name]])
        entry.interval = intervals.get(name)
    return findings, final, noise


def _final_notes(state: _State) -> None:
    """Notes on a workflow stopped by ``max_effects`` and on samples the model flags."""
    problem, settings, rounds = state.problem, state.problem.settings, state.rounds
    if (len(state.active) == settings.max_effects and rounds
            and rounds[-1].winner is not None):
        state.notes.append(f"stopped after {settings.max_effects} effects (max_effects)")
    flagged = int(np.count_nonzero(problem.result.flag[problem.used]))
    if flagged:
        state.notes.append(
            f"{flagged} of {len(state.residual_before)} samples are flagged by the model "
            "(see gsfric.evaluation: stroke, near-singular poses); they are kept")


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


def _floor(state: _State, motion: Motion, final: Platform, full_after: np.ndarray,
           rms_after: float) -> NoiseFloor:
    """The noise floor of the verdict (``floor``): the user's force noise or its estimate from
    the final model's residual over every used pair (``full_after`` (M, 6), N), and the pose
    noise through the final model."""
    problem, s = state.problem, state.problem.settings
    t = np.asarray(motion.t, float)
    step = (t[-1] - t[0]) / max(len(t) - 1, 1)
    estimate = estimated_force_noise(full_after, step, s.floor_segment)
    pose, how = pose_noise_forces(final, motion, problem.poses, problem.used,
                                  problem.sliding, s.floor_draws, seed=state.seed,
                                  n_threads=problem.model.n_threads)
    return noise_floor(state.force_noise, estimate, pose, how, rms_after)


def _imitator_notes(state: _State) -> None:
    """A note for each named effect that only imitates a generic out-of-catalog structure."""
    rounds = state.rounds
    imitators = [rnd.winner for rnd in rounds if rnd.winner and rnd.imitates]
    for name in imitators:
        rnd = next(x for x in rounds if x.winner == name)
        main = rnd.generic.main_signal
        state.notes.append(
            f"round {rnd.index}: {name} explains nothing that a generic out-of-catalog structure "
            f"(mainly {main}: {lackfit.MEANING.get(main, '')}) "
            "does not explain as well or better: the data cannot tell "
            f"{name} from an error outside the catalog; it is named as the simpler explanation, "
            "the verdict is not 'explained'")


def _verdict(state: _State, lof: LackOfFit, rms_after: float, floor: NoiseFloor,
             structures: list, whitener: st.Whitener) -> Verdict:
    """The verdict and its reason (``verdict.decide``): structure in the final residual
    (the dictionary's, the lack-of-fit tests', or a round's generic structure: ``lof`` then
    says which), a residual above the floor the user gave, effects named, or a significant
    refit that closes ``min_gap``."""
    lof.source = "final residual" if lof.significant else None
    by_round = next((rnd for rnd in state.rounds if rnd.slow or rnd.blocked_by_generic
                     or (rnd.winner and rnd.imitates)), None)
    if not lof.significant and by_round is not None:
        _round_structure(lof, by_round)
    sliding = state.problem.sliding
    closed = np.sqrt(max(_rms(state.residual_before[sliding]) ** 2 - rms_after ** 2, 0.0))
    refit_closes = bool(closed >= state.problem.settings.min_gap * rms_after
                        and state.refit.test.significant)
    found = lof.significant or by_round is not None
    return decide(structures=structures, structure_found=found,
                  structure_text=lof.looks_like if found else "", floor=floor,
                  ratio_limit=state.problem.settings.floor_ratio, named=list(state.active),
                  refit_closes=refit_closes, noise=noise_model(whitener))


def _round_structure(lof: LackOfFit, rnd: Round) -> None:
    """What the lack-of-fit summary ``lof`` says about an ``unexplained_discrepancy`` that a
    round found (a generic structure that blocks its winner, that its winner only imitates, or
    that a slow part fits) while the final residual's tests found none: the round's generic
    signal, and the round as the source, instead of the final basis's weaker signals."""
    main = rnd.generic.main_signal if rnd.generic is not None else None
    lof.source = f"round {rnd.index}"
    lof.main_signal = main
    lof.looks_like = lackfit.MEANING.get(main, "") if main else ""



def _slow_structure(problem: Problem, design, whitener: st.Whitener, screen, rnd: Round,
                    notes: list[str]) -> None:
    """A round without a winner, whose best candidate failed only the test on the record's
    slowest components: slow noise would explain it, and so would a structure outside the
    catalog (a scale error of the recorded pose, a delay on a slow motion). The candidate is
    held against the generic basis (``generic_competitor``) as a winner would be; when it only
    imitates the basis or is blocked by it, and the basis adds a significant part beyond the
    catalog also on the slowest components alone or on the rest alone (slow noise, which the
    basis's drift and force columns fit as well as an offset, does not pass that), the slow
    part is a structure, and the round says so (``Round.slow``)."""
    slow = [t for t in screen.tests.values() if t.slow_only]
    if not slow:
        return
    name = max(slow, key=lambda t: t.cv_gain).name
    generic = generic_competitor(problem, design, whitener, screen, name)
    beyond = Evidence(generic.p_generic_beyond_catalog, generic.p_generic_bands)
    if not ((generic.blocked or generic.imitates) and accept(beyond, Rule(rnd.level))):
        return
    rnd.generic, rnd.slow = generic, name
    notes.append(
        f"round {rnd.index}: {name} fits a part of the gap that slow noise could also make "
        f"(not named), but a generic out-of-catalog structure (mainly {generic.main_signal}: "
        f"{lackfit.MEANING.get(generic.main_signal, '')}) explains it as well or better, "
        "and a significant part beyond the catalog: the catalog does not explain the data")


def _largest_model_whitener(problem: Problem, residual: np.ndarray, J: np.ndarray
                            ) -> st.Whitener:
    """The AR noise model of the refit: fitted to the residual (M, 6) less its least-squares
    fit by the refitted parameters' columns J (M, 6, k), as each round's noise model is
    fitted to the residual of its largest model (``_noise_whitener``). Fitted to the residual
    of the model as given, the noise model takes what the refit is about to explain for
    noise (a missing seal force, a step at every start of a move, made white noise look like
    AR(12) noise of lag-one correlation 0.92 on point-to-point moves), and the prewhitened
    refit then weighs the differences of the residual over its level: it stopped at 2.07
    times the noise where the refitted parameters reach 1.04 times."""
    flat = J.reshape(-1, J.shape[2])
    return lackfit.whitener_beyond(residual, J, problem.sliding, problem.settings,
                                   range(J.shape[2]),
                                   (flat.T @ flat, flat.T @ residual.reshape(-1)))


def _noise_whitener(design, problem: Problem) -> st.Whitener:
    """The AR noise model of a round, fitted to the residual of the largest model (the refit
    and every candidate at once, each with one variant: ``Design.largest_model``; least
    squares): what the candidates could explain does not inflate the noise model, so a
    step-like effect (Coulomb friction) is not whitened away before it is tested, and the
    noise is not under-modelled either."""
    cols = design.largest_model(problem.settings.ridge)
    return lackfit.whitener_beyond(design.r, design.X, problem.sliding, problem.settings,
                                   cols, (design.XtX[np.ix_(cols, cols)], design.Xtr[cols]))


def _contributions(problem: Problem, theta: np.ndarray, active: Sequence[str]
                   ) -> dict[str, np.ndarray]:
    """Each named effect's contribution to F at theta (F minus F with it switched off)."""
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


def _refit_test(problem: Problem, blocks: st.Blocks) -> RefitTest:
    """Is the refit of the model's own parameters significant? ``blocks``: its columns (at
    the model's values) and the residual, prewhitened, with the record's slowest components.
    The F-test of all of them against none, and the same test on the record's slowest
    components alone or on the rest alone (``statistics.band_p_value``, the smaller p-value
    times two), each at ``alpha``: a refit that takes up slow noise (a Coulomb coefficient and
    a payload mass that follow the wander of 1/f noise) is not a gap closed."""
    k = blocks.XtX.shape[1]
    if k == 0:
        return RefitTest(1.0, 1.0, False)
    lo, hi = np.full(k, -np.inf), np.full(k, np.inf)
    none, every = st.fit(blocks, [], lo, hi), st.fit(blocks, list(range(k)), lo, hi)
    p = st.f_test(none, every)[1]
    p_bands = st.band_p_value(blocks, none, every, k)
    significant = accept(Evidence(p, p_bands), Rule(problem.settings.alpha))
    return RefitTest(p, p_bands, significant)


def _refit_report(problem: Problem, theta0: np.ndarray, blocks: st.Blocks
                  ) -> tuple[RefitReport, list[str]]:
    """The unbounded values a refit would need, and their plausibility; and a note for each
    implausible one.

    ``blocks`` holds the prewhitened derivatives of F at theta0 for the refitted parameters
    (the plausible ones first) and the residual there.
    """
    model = problem.model
    names = list(problem.plausible)
    out, notes = RefitReport(), []
    if not names:
        return out, notes
    A, b, _, _ = blocks.total()
    n = len(names)
    free = st.solve(A[:n, :n], b[:n], ridge=blocks.ridge)
    free += theta0[[model.index[n] for n in names]]
    for k, name in enumerate(names):
        lo, hi = problem.plausible[name]
        value0 = float(theta0[model.index[name]])
        plausible = bool(lo <= free[k] <= hi)
        out.parameters[name] = RefitParameter(value0, value0, float(free[k]), [lo, hi],
                                              plausible)
        if not plausible:
            out.implausible.append(name)
            notes.append(
                f"an unbounded refit of the model's parameters would need {name} = "
                f"{free[k]:.4g}, outside its plausible range [{lo:.4g}, {hi:.4g}]: not a wrong "
                "value but a missing effect is the likely cause; the refit is held within the "
                "range and the rest of the gap is left to the candidate effects")
    return out, notes


class _Progress:
    """A tqdm progress bar on stderr over the workflow's stages (or nothing)."""

    def __init__(self, enabled: bool, total: int) -> None:
        self.bar = None
        if enabled:
            self.bar = tqdm(total=total, unit="stage", desc="discover", leave=False)

    def step(self, text: str) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(text, refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
