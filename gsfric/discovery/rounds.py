"""The workflow's second stage: round after round, test the candidates and add the winner.

Each round linearises the model at the current parameters (compiled Jacobian), prewhitens
with an AR model of the residual, and tests every candidate effect against the refitted
model (``selection.screen_candidates``). The accepted candidate with the largest held-out gain
wins; the AR model is re-estimated from the winner's residual and the screen repeated until
the winner is stable (Cochrane-Orcutt). Of the explanations the data cannot tell apart, the
simpler is preferred; a winner that only a generic out-of-catalog structure explains better
is not named. The winner is refined with the refitted parameters by Gauss-Newton on the
compiled model and added, and the next round starts; the rounds stop when no candidate is
significant.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from gsfric.discovery import lackfit, outside
from gsfric.discovery import statistics as st
from gsfric.discovery.candidates import Candidate
from gsfric.discovery.evidence import Evidence, Rule, accept
from gsfric.discovery.refine import Refined, refine
from gsfric.discovery.residuals import Design, Problem
from gsfric.discovery.results import FindingEvidence, Round
from gsfric.discovery.selection import (
    CandidateTest,
    GenericCompetitor,
    Screen,
    bootstrap_share,
    generic_competitor,
    indistinguishable,
    noise_model,
    refit_alternatives,
    screen_candidates,
    winner_of,
)


@dataclass(frozen=True)
class Rounds:
    """What the rounds found.

    Attributes
    ----------
    fit : Refined
        The parameters after the last named effect's refinement (the refit's when none was
        named).
    rounds : tuple of Round
        Every round, in order.
    active : tuple of str
        The effects named, in the order found.
    dropped : tuple of str
        The winners that, refined on the compiled model, did not lower the residual.
    evidence : dict of str -> FindingEvidence
        Each named effect's evidence from the round it won (its final size not yet filled).
    alternatives : dict of str -> list of str
        The refitted parameters whose change a candidate explains as well (first round).
    notes : tuple of str
        Remarks for the report, in the order the rounds made them.
    """

    fit: Refined
    rounds: tuple[Round, ...]
    active: tuple[str, ...]
    dropped: tuple[str, ...]
    evidence: dict[str, FindingEvidence]
    alternatives: dict[str, list[str]]
    notes: tuple[str, ...]


@dataclass(frozen=True)
class RoundOutcome:
    """One round's result.

    Attributes
    ----------
    round : Round
        The report's entry of the round.
    fit : Refined
        The parameters after the round: the winner's refinement when it was named, else those
        the round started from.
    named, dropped : str or None
        The effect named; the winner dropped because, refined, it did not lower the residual.
    evidence : FindingEvidence or None
        The named effect's evidence.
    alternatives : dict of str -> list of str
        First round only: refitted parameters whose change a candidate explains as well.
    notes : tuple of str
    goes_on : bool
        Whether another round follows.
    """

    round: Round
    fit: Refined
    named: str | None = None
    dropped: str | None = None
    evidence: FindingEvidence | None = None
    alternatives: dict[str, list[str]] | None = None
    notes: tuple[str, ...] = ()
    goes_on: bool = False


def run_rounds(problem: Problem, start: Refined, theta0: np.ndarray, rng: np.random.Generator,
               step: Callable[[str], None]) -> Rounds:
    """Round after round from the refitted parameters ``start`` until no candidate is
    significant, none is left, or ``max_effects`` are named; ``theta0`` (n_theta,) holds the
    model's values, ``rng`` draws the rounds' bootstrap, ``step`` is told each round's start."""
    fit, rounds, active, dropped = start, [], [], []
    evidence, alternatives, notes = {}, {}, []
    while len(active) < problem.settings.max_effects:
        candidates = [c for c in problem.candidates if c.name not in active + dropped]
        if not candidates:
            break
        step(f"round {len(rounds) + 1}: testing {len(candidates)} candidate effects")
        out = play_round(problem, fit, active, candidates, index=len(rounds) + 1, rng=rng,
                         theta0=theta0)
        rounds.append(out.round)
        alternatives.update(out.alternatives or {})
        notes += out.notes
        fit = out.fit
        if out.named is not None:
            active.append(out.named)
            evidence[out.named] = out.evidence
        if out.dropped is not None:
            dropped.append(out.dropped)
        if not out.goes_on:
            break
    return Rounds(fit, tuple(rounds), tuple(active), tuple(dropped), evidence, alternatives,
                  tuple(notes))


@dataclass(frozen=True)
class _Screened:
    """A round's design, noise model, tests and winner (``_screen_round``), and in the first
    round the refitted changes a candidate explains as well."""

    design: Design
    whitener: st.Whitener
    screen: Screen
    winner: str | None
    alternatives: dict[str, list[str]]


@dataclass(frozen=True)
class _Choice:
    """The winner preferred by parsimony (``_prefer_simplest``): the candidates it cannot be
    told apart from, the one it was preferred over, and its p-values beyond each of them."""

    winner: str
    indistinguishable: list[str]
    preferred_over: str | None
    p_alone: dict[str, float]


def play_round(problem: Problem, fit: Refined, active: Sequence[str],
               candidates: list[Candidate], *, index: int, rng: np.random.Generator,
               theta0: np.ndarray) -> RoundOutcome:
    """Round ``index``: test the candidates against ``fit`` (with the effects ``active``),
    choose the winner, refine it and add it (``rng`` draws the bootstrap share; ``theta0``
    (n_theta,) the model's values, against which the first round's alternatives are read)."""
    sc = _screen_round(problem, fit.theta, active, candidates, theta0 if index == 1 else None)
    notes = tuple(f"the refitted change of {name} could equally be explained by "
                  f"{', '.join(alts)}: the data cannot tell them apart"
                  for name, alts in sc.alternatives.items())
    head = {"index": index, "tests": list(sc.screen.tests.values()),
            "level": problem.settings.alpha / len(candidates),
            "noise_model": noise_model(sc.whitener),
            "rms_before": st.rms(sc.design.r[problem.sliding])}
    if sc.winner is None:
        slow = _slow_structure(problem, sc, index, head["level"])
        rnd = Round(winner=None, rms_after=head["rms_before"],
                    generic=slow.generic if slow else None,
                    slow=slow.candidate if slow else None, **head)
        return RoundOutcome(rnd, fit, alternatives=sc.alternatives,
                            notes=notes + ((slow.note,) if slow else ()))
    winner = _winner(problem, sc, candidates, rng)
    if winner.generic.blocked:
        rnd = Round(winner=None, blocked=winner.name, rms_after=head["rms_before"],
                    **winner.round_fields(), **head)
        note = (f"round {index}: {winner.name} was significant but adds nothing to a generic "
                f"out-of-catalog structure (mainly {winner.generic.main_signal}), which "
                "explains more: not named")
        return RoundOutcome(rnd, fit, alternatives=sc.alternatives, notes=notes + (note,))
    whitener, alternatives = sc.whitener, sc.alternatives
    del sc     # free the round's design before the refinement
    names = problem.refit_names(list(active) + [winner.name])
    theta, r, J = refine(problem, winner.start, names, whitener)
    refined = Refined(theta, tuple(names), r, J)
    rms_after = st.rms(r[problem.sliding])
    if rms_after >= head["rms_before"]:
        # refined on the compiled model, the effect no longer shrinks the gap (a change of
        # the refitted parameters that the linearised screening did not foresee); it says
        # nothing of the other candidates: the round is repeated without it
        rnd = Round(winner=None, blocked=winner.name, rms_after=head["rms_before"],
                    **winner.round_fields(), **head)
        note = (f"round {index}: {winner.name} refined on the compiled model does not lower "
                f"the residual ({rnd.rms_before:.4g} N -> {rms_after:.4g} N): not named, "
                "the round repeated without it")
        return RoundOutcome(rnd, fit, dropped=winner.name, alternatives=alternatives,
                            notes=notes + (note,), goes_on=True)
    rnd = Round(winner=winner.name, rms_after=rms_after, **winner.round_fields(), **head)
    return RoundOutcome(rnd, refined, named=winner.name, evidence=winner.evidence(rnd),
                        alternatives=alternatives, notes=notes, goes_on=True)


@dataclass(frozen=True)
class _Winner:
    """A round's winner (``_winner``), before its refinement.

    ``choice``: the winner preferred by parsimony; ``generic``: it against the generic
    out-of-catalog basis; ``share``: the bootstrap share of each accepted candidate (empty
    when the basis blocks the winner); ``start`` (n_theta,): the parameters it is refined
    from; ``test``: its test in the round; ``candidate``: its catalog entry."""

    choice: _Choice
    generic: GenericCompetitor
    share: dict[str, float]
    start: np.ndarray
    test: CandidateTest
    candidate: Candidate

    @property
    def name(self) -> str:
        return self.choice.winner

    def round_fields(self) -> dict:
        """The winner's fields of its ``Round``, as keyword arguments."""
        return {"indistinguishable": list(self.choice.indistinguishable),
                "preferred_over": self.choice.preferred_over, "generic": self.generic,
                "bootstrap_share": dict(self.share)}

    def evidence(self, rnd: Round) -> FindingEvidence:
        """Its evidence, named in round ``rnd``."""
        test = self.test
        return FindingEvidence(
            round=rnd.index, F=test.F, p_value=test.p_value, dof=test.dof, level=rnd.level,
            cv_gain=test.cv_gain, fold_share=test.fold_share,
            bootstrap_share=self.share.get(self.name, 0.0),
            indistinguishable_from=list(self.choice.indistinguishable),
            preferred_over=self.choice.preferred_over, p_value_beyond=dict(self.choice.p_alone),
            rms_before=rnd.rms_before, rms_after=rnd.rms_after,
            signature=self.candidate.signature)


def _winner(problem: Problem, sc: _Screened, candidates: list[Candidate],
            rng: np.random.Generator) -> _Winner:
    """The screened round's winner preferred by parsimony, held against the generic basis;
    unless the basis blocks it, its bootstrap share (drawn with ``rng``) and the parameters
    it is refined from."""
    choice = _prefer_simplest(problem, sc.design, sc.screen, sc.winner, candidates)
    generic = generic_competitor(problem, sc.design, sc.whitener, sc.screen, choice.winner)
    c = next(c for c in candidates if c.name == choice.winner)
    test = sc.screen.tests[choice.winner]
    if generic.blocked:
        return _Winner(choice, generic, {}, sc.design.theta, test, c)
    share = bootstrap_share(problem, sc.design, sc.screen, rng)
    start = _winner_start(problem, sc.design, sc.screen, choice.winner)
    return _Winner(choice, generic, share, start, test, c)


def _screen_round(problem: Problem, theta: np.ndarray, active: Sequence[str],
                  candidates: list[Candidate], theta0: np.ndarray | None) -> _Screened:
    """A round's design, noise model, tests and winner: the candidates screened against the
    model linearised at ``theta`` (n_theta,), the noise model re-estimated from the winner's
    residual and the screen repeated until the winner is stable (Cochrane-Orcutt, at most
    three times); given the model's values ``theta0`` (the first round), the refitted changes
    that a candidate explains as well."""
    design = problem.linearise(theta, active, candidates)
    whitener = _noise_whitener(design, problem)
    screen = screen_candidates(problem, design, whitener, candidates)
    alternatives = ({} if theta0 is None
                    else refit_alternatives(problem, design, screen, theta0))
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
    return _Screened(design, whitener, screen, winner, alternatives)


def _prefer_simplest(problem: Problem, design: Design, screen: Screen, winner: str,
                     candidates: list[Candidate]) -> _Choice:
    """Parsimony: of the explanations the data cannot tell apart from the round's ``winner``,
    the simpler one (``Candidate.simpler``, then fewer parameters)."""
    group, p_alone = indistinguishable(problem, design, screen, winner)
    if not group:
        return _Choice(winner, group, None, p_alone)
    rank = {c.name: (c.simpler, len(c.fitted)) for c in candidates}
    simplest = min([winner] + list(group), key=lambda n: rank[n])
    if rank[simplest] >= rank[winner]:
        return _Choice(winner, group, None, p_alone)
    group, p_alone = indistinguishable(problem, design, screen, simplest)
    if winner not in group:
        group.append(winner)
    return _Choice(simplest, group, winner, p_alone)


def _winner_start(problem: Problem, design: Design, screen: Screen, winner: str
                  ) -> np.ndarray:
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


@dataclass(frozen=True)
class _SlowPart:
    """A round without a winner whose slow part is a structure (``_slow_structure``): the
    candidate that fits it, its comparison with the generic basis, and the round's note."""

    generic: GenericCompetitor
    candidate: str
    note: str


def _slow_structure(problem: Problem, sc: _Screened, index: int, level: float
                    ) -> _SlowPart | None:
    """A round without a winner, whose best candidate failed only the test on the record's
    slowest components: slow noise would explain it, and so would a structure outside the
    catalog (a scale error of the recorded pose, a delay on a slow motion). The candidate is
    held against the generic basis (``generic_competitor``) as a winner would be; when it only
    imitates the basis or is blocked by it, and the basis adds a significant part beyond the
    catalog also on the slowest components alone or on the rest alone (slow noise, which the
    basis's drift and force columns fit as well as an offset, does not pass that), the slow
    part is a structure, and the round says so (``Round.slow``); None otherwise."""
    slow = [t for t in sc.screen.tests.values() if t.slow_only]
    if not slow:
        return None
    name = max(slow, key=lambda t: t.cv_gain).name
    generic = generic_competitor(problem, sc.design, sc.whitener, sc.screen, name)
    beyond = Evidence(generic.p_generic_beyond_catalog, generic.p_generic_bands)
    if not ((generic.blocked or generic.imitates) and accept(beyond, Rule(level))):
        return None
    return _SlowPart(generic, name, (
        f"round {index}: {name} fits a part of the gap that slow noise could also make "
        f"(not named), but a generic out-of-catalog structure (mainly {generic.main_signal}: "
        f"{outside.looks_like('basis', generic.main_signal)}) explains it as well or better, "
        "and a significant part beyond the catalog: the catalog does not explain the data"))


def _noise_whitener(design: Design, problem: Problem) -> st.Whitener:
    """The AR noise model of a round, fitted to the residual of the largest model (the refit
    and every candidate at once, each with one variant: ``Design.largest_model``; least
    squares): what the candidates could explain does not inflate the noise model, so a
    step-like effect (Coulomb friction) is not whitened away before it is tested, and the
    noise is not under-modelled either."""
    cols = design.largest_model(problem.settings.ridge)
    return lackfit.whitener_beyond(design.r, design.X, problem.sliding, problem.settings,
                                   cols, (design.XtX[np.ix_(cols, cols)], design.Xtr[cols]))
