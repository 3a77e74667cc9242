"""The discrepancy workflow: refit the model, test the candidate effects, add the winner, repeat.

Steps (docs/discovery.md explains each decision):

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

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gsfric.discovery import lackfit
from gsfric.discovery import statistics as st
from gsfric.discovery.candidates import CANDIDATES
from gsfric.discovery.regimes import bands as regime_bands
from gsfric.discovery.residuals import Problem
from gsfric.discovery.selection import (
    CandidateTest,
    bootstrap_share,
    generic_competitor,
    half_stability,
    indistinguishable,
    low_band_of,
    noise_model,
    refine,
    refit_alternatives,
    screen_candidates,
    winner_of,
)
from gsfric.discovery.settings import Settings
from gsfric.platform.description import Platform
from gsfric.trajectory import Motion


@dataclass
class Round:
    """One round: the tests, the winner and its competitors.

    Attributes
    ----------
    index : int
    tests : list[CandidateTest]
    winner : str or None
    indistinguishable : list[str]
        Significant candidates that the data cannot tell apart from the winner.
    bootstrap_share : dict[str, float]
        Share of block-bootstrap draws in which each significant candidate reduced the error
        most.
    level : float
        The per-candidate test level ``alpha / K``.
    noise_model : dict
        AR orders and lag-one autocorrelations of the residual of each leg.
    rms_before, rms_after : float
        RMS of the residual (N) before and after the round.
    """

    index: int
    tests: list[CandidateTest]
    winner: str | None
    indistinguishable: list[str] = field(default_factory=list)
    bootstrap_share: dict[str, float] = field(default_factory=dict)
    level: float = 0.0
    noise_model: dict = field(default_factory=dict)
    rms_before: float = 0.0
    rms_after: float = 0.0
    preferred_over: str | None = None
    generic: dict = field(default_factory=dict)
    """The winner against the generic out-of-model structure (``generic_competitor``)."""
    blocked: str | None = None
    """A winner not named: a generic out-of-catalog structure explains the data better and the
    winner adds nothing to it (``generic["blocked"]``), or refined on the compiled model it
    does not lower the residual."""
    slow: str | None = None
    """Without a winner: the candidate accepted by every rule but the test on the slowest
    components (``CandidateTest.slow_only``) that a generic out-of-catalog structure explains
    as well or better (``generic`` holds that comparison): not slow noise but a structure."""


@dataclass
class Finding:
    """An effect named by the workflow.

    Attributes
    ----------
    name : str
        Catalog effect name.
    parameters : dict[str, float]
        Fitted values (fixed parameters included).
    interval : dict[str, tuple[float, float]]
        95% block-bootstrap intervals of the fitted parameters.
    evidence : dict
        Test statistics, cross-validation, bootstrap share, effect size, the round it was found
        in, the candidates it cannot be told apart from, where it shows.
    """

    name: str
    parameters: dict[str, float]
    interval: dict[str, tuple[float, float]]
    evidence: dict


@dataclass
class Discovery:
    """Everything the workflow found.

    Attributes
    ----------
    effects : list[Finding]
        Effects named, in the order found (empty: nothing significant is missing).
    refit : dict
        The model's own parameters: model value, refitted value, plausible range, the value an
        unbounded refit would need, and alternative explanations.
    rounds : list[Round]
    rms_before, rms_refit, rms_after : float
        RMS residual (N, all legs, trimmed samples) of the model as given, after the refit
        alone, and of the final model.
    noise_rms_estimate : float
        RMS of the final residual corrected for the parameters fitted: the noise level, if the
        final model is right.
    t : ndarray, shape (M,)
        Times of the samples used, s.
    residual_before, residual_after : ndarray, shape (M, 6)
        Residuals of the model as given and of the final model, N.
    used : slice
        The samples used, of the data's N.
    model : Platform
        The model as given.
    platform : Platform
        The final model: refitted parameters, named effects switched on.
    result_before : gsfric.Result
        Full evaluation of the given model over the used samples (speeds, lengths, loads).
    noise_model : dict
        AR model of the final residual.
    regimes : list[gsfric.discovery.regimes.Band]
        The residual before and after per band of speed, load, stroke, pose and time.
    settings : Settings
    evaluations : int
        Calls of the compiled model.
    notes : list[str]
        Remarks for the report (implausible refits, flagged steps, ...).
    """

    effects: list[Finding]
    refit: dict
    rounds: list[Round]
    rms_before: float
    rms_refit: float
    rms_after: float
    noise_rms_estimate: float
    t: np.ndarray
    residual_before: np.ndarray
    residual_after: np.ndarray
    used: slice
    model: Platform
    platform: Platform
    result_before: object
    noise_model: dict
    regimes: list = field(default_factory=list)
    settings: Settings = field(default_factory=Settings)
    evaluations: int = 0
    notes: list[str] = field(default_factory=list)
    verdict: str = "no_discrepancy"
    lack_of_fit: dict = field(default_factory=dict)
    noise: dict = field(default_factory=dict)
    rms_after_all: float = 0.0
    sliding: np.ndarray | None = None

    @property
    def names(self) -> list[str]:
        """Names of the effects found."""
        return [f.name for f in self.effects]

    def summary(self) -> dict:
        """The summary.json content (SPEC), plus the refit, rounds and per-leg gaps."""
        from gsfric.discovery.summary import summary

        return summary(self)


# -- the workflow -------------------------------------------------------------------------------


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r ** 2)))


def discover(motion: Motion, forces: np.ndarray, platform: Platform | None = None, *,
             settings: Settings | None = None, seed: int = 0, progress: bool = False,
             poses: tuple[np.ndarray, np.ndarray] | None = None, **options) -> Discovery:
    """Find which effects the model misses, fit them, and measure how much of the gap closes.

    Parameters
    ----------
    motion : Motion
        The measured motion (N steps), e.g. from ``gsfric.io.read_measured``.
    forces : ndarray, shape (N, 6)
        Measured actuator forces F1..F6, N (friction included).
    platform : Platform, optional
        The current model (default: the reference platform).
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
    **options
        Fields of ``Settings`` overriding ``settings``.

    Returns
    -------
    Discovery
    """
    import dataclasses

    from gsfric.models import reference_platform

    settings = dataclasses.replace(settings or Settings(), **options)
    platform = reference_platform() if platform is None else platform
    bar = _Progress(progress, settings.max_effects + 3)
    bar.step("simulating the model along the measured motion")
    problem = Problem(motion, forces, platform, settings, poses=poses)
    model = problem.model
    rng = np.random.default_rng(seed)
    theta0 = model.theta0.copy()
    notes = [f"candidate {n} not tested: {why}" for n, why in problem.skipped.items()]

    # -- refit of the model's own parameters
    bar.step("refitting the model's own parameters")
    names = problem.refit_names([])
    F0, J0 = model.jacobian(theta0, names, rows=problem.used)
    residual_before = problem.mask(problem.y - F0[problem.used])
    J0 *= problem.weight[:, :, None]
    whitener = _largest_model_whitener(problem, residual_before, J0)
    # the refit's columns prewhitened once, for its unbounded values and for its test
    refit_blocks = st.Blocks.whitened(whitener, J0, residual_before, problem.settings.n_blocks,
                                      low=low_band_of(problem, whitener))
    refit = _refit_report(problem, theta0, refit_blocks)
    refit["test"] = _refit_test(problem, refit_blocks)
    del refit_blocks
    theta, r, J = refine(problem, theta0, names, whitener, start=(residual_before, J0))
    del J0
    sliding = problem.sliding
    rms_refit = _rms(r[sliding])
    for name in names:
        if name not in refit["parameters"]:
            refit["parameters"][name] = {
                "model": float(theta0[model.index[name]]), "unbounded": None,
                "plausible": list(problem.bounds(name)), "plausible_refit": True}
        refit["parameters"][name]["refit"] = float(theta[model.index[name]])
    notes += refit.pop("notes")

    active: list[str] = []
    dropped: list[str] = []     # winners that, refined, did not lower the residual
    rounds: list[Round] = []
    findings_evidence: dict[str, dict] = {}
    while len(active) < settings.max_effects:
        candidates = [c for c in problem.candidates if c.name not in active + dropped]
        if not candidates:
            break
        bar.step(f"round {len(rounds) + 1}: testing {len(candidates)} candidate effects")
        design = screen = None     # the previous round's, before the next is built
        design = problem.linearise(theta, active, candidates)
        whitener = _noise_whitener(design, problem)
        screen = screen_candidates(problem, design, whitener, candidates)
        if not rounds:
            for name, alts in refit_alternatives(problem, design, screen, theta0).items():
                refit["parameters"][name]["alternatives"] = alts
                notes.append(f"the refitted change of {name} could equally be explained by "
                             f"{', '.join(alts)}: the data cannot tell them apart")
        winner = winner_of(screen)
        seen = [winner]
        for _ in range(3):
            if winner is None:
                break
            fit = screen.fits[winner]
            r_alt = design.r - design.X[:, :, fit.columns] @ fit.coef
            whitener = st.Whitener.fit(r_alt, valid=problem.sliding)
            screen = screen_candidates(problem, design, whitener, candidates)
            new = winner_of(screen)
            if new == winner:
                break
            winner = new
            if winner in seen:
                break
            seen.append(winner)
        level = settings.alpha / len(candidates)
        rnd = Round(len(rounds) + 1, list(screen.tests.values()), winner, level=level,
                    noise_model=noise_model(whitener), rms_before=_rms(design.r[sliding]))
        rounds.append(rnd)
        if winner is None:
            rnd.rms_after = rnd.rms_before
            _slow_structure(problem, design, whitener, screen, rnd, notes)
            break
        rnd.indistinguishable, p_alone = indistinguishable(problem, design, screen, winner)
        if rnd.indistinguishable:
            # parsimony: of explanations the data cannot tell apart, the simpler one
            group = [winner] + list(rnd.indistinguishable)
            rank = {c.name: (c.simpler, len(c.fitted)) for c in candidates}
            simplest = min(group, key=lambda n: rank[n])
            if rank[simplest] < rank[winner]:
                rnd.preferred_over = winner
                winner = rnd.winner = simplest
                rnd.indistinguishable, p_alone = indistinguishable(problem, design, screen,
                                                                   winner)
                if rnd.preferred_over not in rnd.indistinguishable:
                    rnd.indistinguishable.append(rnd.preferred_over)
        rnd.generic = generic_competitor(problem, design, whitener, screen, winner)
        if rnd.generic["blocked"]:
            rnd.blocked, rnd.winner = winner, None
            rnd.rms_after = rnd.rms_before
            notes.append(
                f"round {rnd.index}: {winner} was significant but adds nothing to a generic "
                f"out-of-catalog structure (mainly {rnd.generic['main_signal']}), which "
                "explains more: not named")
            break
        rnd.bootstrap_share = bootstrap_share(problem, design, screen, rng)
        c = next(c for c in candidates if c.name == winner)
        start = design.theta.copy()
        values = screen.tests[winner].parameters
        for p, v in values.items():
            start[model.index[f"{winner}.{p}"]] = v
        step_fit = screen.fits[winner]
        for col, step in zip(step_fit.columns, step_fit.coef):
            if col in design.refit:
                start[model.index[design.names[col]]] += design.signs[col] * step
        new_names = problem.refit_names(active + [winner])
        test = screen.tests[winner]
        design = screen = None     # free the round's design before the refinement
        theta_new, r_new, J_new = refine(problem, start, new_names, whitener)
        rnd.rms_after = _rms(r_new[sliding])
        if rnd.rms_after >= rnd.rms_before:
            # refined on the compiled model, the effect no longer shrinks the gap
            # (a change of the refitted parameters that the linearised screening did not
            # foresee); it says nothing of the other candidates: the round is repeated
            # without it
            notes.append(f"round {rnd.index}: {winner} refined on the compiled model does "
                         f"not lower the residual ({rnd.rms_before:.4g} N -> "
                         f"{rnd.rms_after:.4g} N): not named, the round repeated without it")
            rnd.blocked, rnd.winner, rnd.rms_after = winner, None, rnd.rms_before
            dropped.append(winner)
            continue
        theta, r, J, names = theta_new, r_new, J_new, new_names
        active.append(winner)
        findings_evidence[winner] = {
            "round": rnd.index, "F": test.F, "p_value": test.p_value, "dof": test.dof,
            "level": level, "cv_gain": test.cv_gain, "fold_share": test.fold_share,
            "bootstrap_share": rnd.bootstrap_share.get(winner, 0.0),
            "indistinguishable_from": list(rnd.indistinguishable),
            "preferred_over": rnd.preferred_over,
            "p_value_beyond": {k: v for k, v in p_alone.items()},
            "rms_before": rnd.rms_before, "rms_after": rnd.rms_after,
            "signature": c.signature,
        }

    design = screen = None     # free the last round's design before the final steps
    bar.step("bootstrap of the final fit")
    residual_after = r
    whitener = st.Whitener.fit(residual_after, valid=problem.sliding)
    intervals = _intervals(problem, J, names, whitener, residual_after, rng, theta)
    for name in active:
        findings_evidence[name]["stability"] = half_stability(
            problem, J, residual_after, names, name, whitener)
    n_fitted = len(names)
    rows = int(np.count_nonzero(sliding))
    noise = float(np.sqrt(np.sum(residual_after ** 2) / max(rows - n_fitted, 1)))
    final = model.platform_at(theta, list(dict.fromkeys(
        [c.name for c in problem.own_effects] + active)))
    contributions = _contributions(problem, theta, active)
    findings = []
    for name in active:
        c = next(c for c in CANDIDATES if c.name == name)
        params = {p: float(v) for p, v in final.effects[name].items()}
        ev = findings_evidence[name]
        ev["effect_size"] = _rms(contributions[name]) / noise if noise > 0 else float("inf")
        ev["contribution_rms"] = _rms(contributions[name])
        findings.append(Finding(name, params,
                                {p: intervals[f"{name}.{p}"] for p in c.fitted + c.refined},
                                ev))
    for name in list(refit["parameters"]):
        refit["parameters"][name]["final"] = float(theta[model.index[name]])
        refit["parameters"][name]["interval"] = intervals.get(name)
    if len(active) == settings.max_effects and rounds and rounds[-1].winner is not None:
        notes.append(f"stopped after {settings.max_effects} effects (max_effects)")
    flagged = int(np.count_nonzero(problem.result.flag[problem.used]))
    if flagged:
        notes.append(f"{flagged} of {len(residual_before)} samples are flagged by the model "
                     "(see gsfric.evaluation: stroke, near-singular poses); they are kept")
    used = problem.used
    full_after = problem.y - model.forces(theta)[used]
    lof = _lack_of_fit(problem, theta, residual_after, whitener,
                       in_model=[c.name for c in problem.own_effects] + active)
    rms_after = _rms(residual_after[sliding])
    independent = float(np.sqrt(np.mean(problem.force_noise ** 2)))
    noise_info = {
        "high_frequency": independent,
        "high_frequency_per_leg": [float(v) for v in problem.force_noise],
        "residual_corrected": noise,
        "innovation_std": [float(v) for v in whitener.innovation_std],
        "method": "high_frequency: residual of a local cubic fit of each force channel "
                  "(robust scale), independent of the model; residual_corrected: final "
                  "residual corrected for the parameters fitted",
        "speed_uncertainty": [float(v) for v in problem.sigma_v],
        "not_sliding_share": float(1.0 - sliding.mean()),
    }
    imitators = [rnd.winner for rnd in rounds if rnd.winner and rnd.generic.get("imitates")]
    for name in imitators:
        rnd = next(x for x in rounds if x.winner == name)
        notes.append(
            f"round {rnd.index}: {name} explains nothing that a generic out-of-catalog structure "
            f"(mainly {rnd.generic['main_signal']}: {lackfit.MEANING.get(rnd.generic['main_signal'], '')}) "
            "does not explain as well or better: the data cannot tell "
            f"{name} from an error outside the catalog; it is named as the simpler explanation, "
            "the verdict is not 'explained'")
    lof["source"] = "final residual" if lof["significant"] else None
    by_round = next((rnd for rnd in rounds if rnd.slow or rnd.generic.get("blocked")
                     or (rnd.winner and rnd.generic.get("imitates"))), None)
    if lof["significant"] or by_round is not None:
        verdict = "unexplained_discrepancy"
        if not lof["significant"]:
            _round_structure(lof, by_round)
    elif active:
        verdict = "explained"
    else:
        closed = np.sqrt(max(_rms(residual_before[sliding]) ** 2 - rms_after ** 2, 0.0))
        verdict = "explained" if (closed >= settings.min_gap * rms_after
                                  and refit["test"]["significant"]) else "no_discrepancy"
    lof.pop("fitted")
    table = regime_bands(np.asarray(motion.t[used]), problem.result.D_dot[used],
                         problem.result.D[used], problem.result.F[used],
                         motion.rotation[used], residual_before, residual_after)
    bar.close()
    return Discovery(
        effects=findings, refit=refit, rounds=rounds, rms_before=_rms(residual_before[sliding]),
        rms_refit=rms_refit, rms_after=rms_after, noise_rms_estimate=independent,
        t=np.asarray(motion.t[problem.used]), residual_before=residual_before,
        residual_after=residual_after, used=problem.used, model=platform, platform=final,
        result_before=problem.result, noise_model=noise_model(whitener), regimes=table,
        settings=settings, evaluations=model.evaluations, notes=notes, verdict=verdict,
        lack_of_fit=lof, noise=noise_info, rms_after_all=_rms(full_after),
        sliding=sliding)


def _round_structure(lof: dict, rnd: Round) -> None:
    """What the lack-of-fit summary ``lof`` says about an ``unexplained_discrepancy`` that a
    round found (a generic structure that blocks its winner, that its winner only imitates, or
    that a slow part fits) while the final residual's tests found none: the round's generic
    signal, and the round as the source, instead of the final basis's weaker signals."""
    main = rnd.generic.get("main_signal")
    lof["source"] = f"round {rnd.index}"
    lof["main_signal"] = main
    lof["looks_like"] = lackfit.MEANING.get(main, "") if main else ""


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
    if not ((generic["blocked"] or generic["imitates"])
            and generic["p_generic_beyond_catalog"] < rnd.level
            and generic["p_generic_bands"] < rnd.level):
        return
    rnd.generic, rnd.slow = generic, name
    notes.append(
        f"round {rnd.index}: {name} fits a part of the gap that slow noise could also make "
        f"(not named), but a generic out-of-catalog structure (mainly {generic['main_signal']}: "
        f"{lackfit.MEANING.get(generic['main_signal'], '')}) explains it as well or better, "
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
    return _whitener_beyond(problem, residual, J, flat.T @ flat, flat.T @ residual.reshape(-1))


def _noise_whitener(design, problem: Problem) -> st.Whitener:
    """The AR noise model of a round, fitted to the residual of the largest model (the refit
    and every candidate at once, each with one variant: ``Design.largest_model``; least
    squares): what the candidates could explain does not inflate the noise model, so a
    step-like effect (Coulomb friction) is not whitened away before it is tested, and the
    noise is not under-modelled either."""
    cols = design.largest_model()
    return _whitener_beyond(problem, design.r, design.X[:, :, cols],
                            design.XtX[np.ix_(cols, cols)], design.Xtr[cols])


def _whitener_beyond(problem: Problem, r: np.ndarray, X: np.ndarray, XtX: np.ndarray,
                     Xtr: np.ndarray) -> st.Whitener:
    """The AR noise model of the residual r (M, 6) less its least-squares fit by the columns
    X (M, 6, k), given their cross-products XtX (k, k) and Xtr (k,)."""
    coef = st.solve(XtX, Xtr)
    r = r.copy()
    for j in range(X.shape[2]):
        r -= X[:, :, j] * coef[j]
    return st.Whitener.fit(r, valid=problem.sliding)


def _lack_of_fit(problem: Problem, theta: np.ndarray, residual: np.ndarray,
                 whitener: st.Whitener, in_model: Sequence[str] = ()) -> dict:
    """The lack-of-fit test of the final residual (``lackfit``), with where it lives."""

    s = problem.settings
    used = problem.used
    F = problem.model.forces(theta)[used]
    t = np.asarray(problem.model.t[used])
    # a signal that an effect of the final model reproduces (a delay's dF/dt once time_offset
    # is in it) is that effect's parameter, refitted already: not a structure outside the model
    speed = problem.result.D_dot[used]
    dF, acceleration = lackfit.rates(t, F, speed)     # once: the basis and the dynamic test
    X, names = lackfit.basis_outside(t, F, speed, problem.sliding, problem.weight, in_model,
                                     derivatives=(dF, acceleration))
    # the noise model from the residual of the basis fit (largest model), as in each round
    whitener = lackfit.whitener_beyond(residual, X, problem.sliding)
    out = lackfit.test(residual, X, whitener, alpha=s.alpha, min_gap=s.min_gap,
                       n_blocks=s.n_blocks, n_folds=s.n_folds,
                       min_fold_share=s.min_fold_share, names=names,
                       low=low_band_of(problem, whitener))
    X = None
    drift = lackfit.parameter_drift(
        residual, lackfit.drift_basis(t, speed, problem.sliding) * problem.weight[:, :, None],
        problem.sliding, t, alpha=s.alpha, min_gap=s.min_gap, n_blocks=s.n_blocks,
        n_folds=s.n_folds)
    D = problem.result.D[used]
    state = lackfit.state_structure(residual, lackfit.state_features(D, speed, F),
                                    problem.sliding, n_folds=s.n_folds, min_gap=s.min_gap)
    inputs = {"dF/dt": dF, "acceleration": acceleration}
    dynamic = lackfit.dynamic_structure(residual, inputs, problem.sliding, alpha=s.alpha,
                                        min_gap=max(s.min_gap, lackfit.DYNAMIC_MIN_GAP))
    direction, travel = lackfit.travel_since_reversal(D, speed, problem.sliding)
    reversal = lackfit.reversal_structure(residual, direction, travel, problem.sliding,
                                          n_folds=s.n_folds, alpha=s.alpha, min_gap=s.min_gap)
    out["state"], out["dynamic"], out["reversal"] = state, dynamic, reversal
    out["rest"] = _rest_test(problem, theta)
    drift_fitted = drift.pop("fitted")
    drift["levels"] = lackfit.friction_levels(t, residual, speed, problem.sliding)
    out["drift"] = drift
    # structure in a form of the basis says most about what it is; else a friction that
    # drifts over the record; else structure that repeats with the state; else structure
    # that follows the motion; else after each reversal; else what happens at the rests
    tests = {"basis": out, "drift": drift, "state": state, "dynamic": dynamic,
             "reversal": reversal, "rest": out["rest"]}
    by = next((k for k, v in tests.items() if v["significant"]), None)
    if by in ("drift", "state", "dynamic", "reversal", "rest"):
        out.update(significant=True, gap=tests[by]["gap"],
                   structure_rms=tests[by]["structure_rms"], per_leg_rms=tests[by]["per_leg_rms"])
    fitted = drift_fitted if by == "drift" else out["fitted"]
    thirds = np.array_split(np.arange(len(t)), 3)
    out["time_rms"] = {f"{t[g[0]]:.4g}-{t[g[-1]]:.4g} s": _rms(fitted[g]) for g in thirds}
    out["frequency"] = lackfit.dominant_frequency(t, residual)
    main = max(out["signals"], key=out["signals"].get) if out["signals"] else None
    out["looks_like"] = lackfit.MEANING.get(main, "") if main else ""
    if by == "drift":
        main = "drifts over the record"
        out["looks_like"] = lackfit.DRIFT_MEANING
    elif by == "state":
        main = f"repeats with {state['variable']}"
        out["looks_like"] = lackfit.state_meaning(state["variable"])
    elif by == "dynamic":
        main = "driven by the motion"
        out["looks_like"] = lackfit.DYNAMIC_MEANING
    elif by == "reversal":
        main = "follows the travel since each reversal"
        out["looks_like"] = lackfit.REVERSAL_MEANING
    elif by == "rest":
        main = "transient at the rests"
        out["looks_like"] = lackfit.REST_MEANING
    out["main_signal"] = main
    return out


def _rest_test(problem: Problem, theta: np.ndarray) -> dict:
    """``lackfit.rest_transients`` on the rest cores: the measured force less the final
    model's frictionless force, where friction is static. The load cells' gains and delay
    are not applied: at rest the force is constant, a gain changes it by a constant and a
    delay (shorter than the differentiator's reach cut from the cores) not at all, while a
    delay fitted to imitate something else would put its own transients into the rests."""
    s = problem.settings
    used = problem.used
    runs = lackfit.rest_runs(problem.sliding, problem.move_reach)
    if len(runs) < 4:
        return lackfit.rest_transients(np.zeros_like(problem.y), [], alpha=s.alpha,
                                       min_gap=s.min_gap)
    model = problem.model
    residual = problem.y - model.evaluate(theta, keep=("F0",)).F0[used]
    return lackfit.rest_transients(residual, runs, alpha=s.alpha, min_gap=s.min_gap)


def _contributions(problem: Problem, theta: np.ndarray, active: Sequence[str]
                   ) -> dict[str, np.ndarray]:
    """Each named effect's contribution to F at theta (F minus F with it switched off)."""
    if not active:
        return {}
    from gsfric.platform.catalog import EFFECTS

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
    blocks = st.Blocks.whitened(whitener, J, residual, s.n_blocks)
    cols = [model.index[n] for n in names]
    lo = np.array([problem.bounds(n)[0] for n in names]) - theta[cols]
    hi = np.array([problem.bounds(n)[1] for n in names]) - theta[cols]
    draws = []
    for w in st.bootstrap_weights(rng, s.n_blocks, s.n_bootstrap):
        draws.append(st.fit(blocks, list(range(len(names))), lo, hi, w).coef)
    draws = np.array(draws) + theta[cols]
    q = np.percentile(draws, [2.5, 97.5], axis=0)
    return {n: (float(q[0, k]), float(q[1, k])) for k, n in enumerate(names)}


def _refit_test(problem: Problem, blocks: st.Blocks) -> dict:
    """Is the refit of the model's own parameters significant? ``blocks``: its columns (at
    the model's values) and the residual, prewhitened, with the record's slowest components.
    The F-test of all of them against none, and the same test on the record's slowest
    components alone or on the rest alone (``statistics.band_p_value``, the smaller p-value
    times two), each at ``alpha``: a refit that takes up slow noise (a Coulomb coefficient and
    a payload mass that follow the wander of 1/f noise) is not a gap closed."""
    k = blocks.XtX.shape[1]
    if k == 0:
        return {"p_value": 1.0, "p_bands": 1.0, "significant": False}
    lo, hi = np.full(k, -np.inf), np.full(k, np.inf)
    none, every = st.fit(blocks, [], lo, hi), st.fit(blocks, list(range(k)), lo, hi)
    p = st.f_test(none, every)[1]
    p_bands = st.band_p_value(blocks, none, every, k)
    alpha = problem.settings.alpha
    return {"p_value": p, "p_bands": p_bands, "significant": bool(p < alpha and p_bands < alpha)}


def _refit_report(problem: Problem, theta0: np.ndarray, blocks: st.Blocks) -> dict:
    """The unbounded values a refit would need, and their plausibility.

    ``blocks`` holds the prewhitened derivatives of F at theta0 for the refitted parameters
    (the plausible ones first) and the residual there.
    """
    model = problem.model
    names = list(problem.plausible)
    out = {"parameters": {}, "implausible": [], "notes": []}
    if not names:
        return out
    A, b, _, _ = blocks.total()
    n = len(names)
    free = st.solve(A[:n, :n], b[:n])
    free += theta0[[model.index[n] for n in names]]
    for k, name in enumerate(names):
        lo, hi = problem.plausible[name]
        value0 = float(theta0[model.index[name]])
        entry = {"model": value0, "refit": value0, "unbounded": float(free[k]),
                 "plausible": [lo, hi]}
        if not lo <= free[k] <= hi:
            entry["plausible_refit"] = False
            out["implausible"].append(name)
            out["notes"].append(
                f"an unbounded refit of the model's parameters would need {name} = "
                f"{free[k]:.4g}, outside its plausible range [{lo:.4g}, {hi:.4g}]: not a wrong "
                "value but a missing effect is the likely cause; the refit is held within the "
                "range and the rest of the gap is left to the candidate effects")
        else:
            entry["plausible_refit"] = True
        out["parameters"][name] = entry
    return out


class _Progress:
    """A tqdm progress bar on stderr over the workflow's stages (or nothing)."""

    def __init__(self, enabled: bool, total: int) -> None:
        self.bar = None
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit="stage", desc="discover", leave=False)

    def step(self, text: str) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(text, refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
