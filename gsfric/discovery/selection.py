"""Testing the candidates of a round and choosing among them.

``screen_candidates`` fits every candidate with the refitted parameters on the prewhitened
linearised model and decides (F-test at alpha / K, block cross-validation, smallest gap);
``winner_of`` picks the accepted candidate with the largest held-out gain;
``indistinguishable`` and ``refit_alternatives`` find the explanations the data cannot tell
apart; ``bootstrap_share`` measures how stable the choice is; ``refine`` fits the chosen model
by Gauss-Newton on the compiled model.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gsfric.discovery import lackfit
from gsfric.discovery import statistics as st
from gsfric.discovery.candidates import Candidate
from gsfric.discovery.evidence import Evidence, Rule, accept, failures
from gsfric.discovery.residuals import Design, Problem


@dataclass
class CandidateTest:
    """One candidate's test in one round.

    Attributes
    ----------
    name : str
    parameters : dict[str, float]
        The candidate's parameters fitted together with the refitted model (linearised).
    F, p_value : float
        Nested F-test on the prewhitened data against the refitted model.
    dof : int
        Number of parameters tested.
    cv_gain : float
        Relative reduction of the held-out prewhitened squared error (block cross-validation).
    fold_share : float
        Share of the folds in which the held-out error went down.
    sse_gain : float
        Relative reduction of the prewhitened squared error on all data.
    gap : float
        RMS change of the fitted residual when the candidate is added (the gap it closes
        beyond the refitted model, or with the refitted changes it replaces held at the
        model's values: ``gap_replacing_refit``), divided by the RMS of the residual left.
    p_bands : float
        p-value of the same F-test on the record's slowest components alone or on the rest
        alone, whichever is smaller, times two (``statistics.band_p_value``).
    significant : bool
    slow_only : bool
        Accepted by every rule but the test on the record's slowest components alone or on
        the rest alone: the data hold what the candidate fits, but as slow as noise the AR
        model does not describe (``workflow``: such a candidate is held against the generic
        out-of-catalog structure).
    reason : str
        Why the candidate was or was not accepted.
    """

    name: str
    parameters: dict[str, float]
    F: float
    p_value: float
    dof: int
    cv_gain: float
    fold_share: float
    sse_gain: float
    gap: float = 0.0
    p_bands: float = 1.0
    significant: bool = False
    slow_only: bool = False
    reason: str = ""

    @property
    def evidence(self) -> Evidence:
        """The numbers the acceptance rule reads (``evidence.Evidence``)."""
        return Evidence(self.p_value, self.p_bands, self.cv_gain, self.fold_share, self.gap)


@dataclass
class NoiseModel:
    """The AR noise model of each leg's residual, for the report.

    Attributes
    ----------
    ar_order : list of int
        AR order per leg.
    lag1_autocorrelation : list of float
        Lag-one autocorrelation per leg (rounded to 4 decimals).
    innovation_std, residual_std : list of float
        Standard deviation of the innovations and of the residual itself per leg, N.
    """

    ar_order: list[int]
    lag1_autocorrelation: list[float]
    innovation_std: list[float]
    residual_std: list[float]


def noise_model(w: st.Whitener) -> NoiseModel:
    """The AR model of each leg's residual of a whitener, for the report."""
    return NoiseModel([len(c) for c in w.coefficients],
                      [round(float(v), 4) for v in w.phi1()],
                      [float(v) for v in w.innovation_std],
                      [float(v) for v in w.marginal_std])


@dataclass
class Screen:
    """The tests of one round: per candidate its test, its best fit and the variant chosen;
    the refitted model's fit (``null``), the block cross-products and the null's held-out
    errors per fold."""

    tests: dict[str, CandidateTest]
    fits: dict[str, st.Fit]
    variant: dict[str, int]
    null: st.Fit
    blocks: st.Blocks
    cv_null: np.ndarray


def screen_candidates(problem: Problem, design: Design, whitener: st.Whitener,
                      candidates: Sequence[Candidate]) -> Screen:
    """Fit and test every candidate against the refitted model (prewhitened by ``whitener``).

    A candidate is accepted when (a) its F-test gives p < alpha / K, and so does the same
    test on the record's slowest components alone or on the rest alone, each band's noise
    measured in that band (``statistics.band_p_value``: the smaller p-value, times two; slow
    noise that the AR model does not describe is not taken for an offset), (b) it lowers the
    held-out error of the block cross-validation in total and in at least ``min_fold_share``
    of the folds that hold used pairs (``statistics.fold_share``), (c) the gap it closes
    reaches ``min_gap`` (counting the refitted changes it replaces, ``gap_replacing_refit``),
    (d) it lowers the plain residual
    as well as the prewhitened one (the prewhitened fit weighs frequencies by the noise
    model; an explanation of the gap must also shrink the gap as measured).
    """
    s = problem.settings
    blocks = st.Blocks.whitened(whitener, design.X, design.r, s.n_blocks, ridge=s.ridge,
                                low=low_band_of(problem, whitener))
    null_cols = design.refit
    null = st.fit(blocks, null_cols, design.lower, design.upper)
    cv_null = st.cross_validate(blocks, null_cols, design.lower, design.upper, s.n_folds)
    level = s.alpha / max(len(candidates), 1)
    rule = Rule(level, min_gap=s.min_gap, min_cv_gain=0.0, min_fold_share=s.min_fold_share)
    tests, fits, chosen = {}, {}, {}
    for c in candidates:
        options = [st.fit(blocks, null_cols + v, design.lower, design.upper)
                   for v in design.variants[c.name]]
        j = int(np.argmin([o.sse for o in options]))
        best = options[j]
        F, p, k = st.f_test(null, best, k=len(c.fitted))
        cv = st.cross_validate(blocks, null_cols, design.lower, design.upper, s.n_folds,
                               variants=design.variants[c.name])
        cv_gain = float((cv_null.sum() - cv.sum()) / cv_null.sum())
        share = st.fold_share(blocks, cv, cv_null, s.n_folds)
        params = candidate_values(problem, design, c, best, j)
        gap = gap_closed(design, null, best)
        before_bands = Evidence(p, cv_gain=cv_gain, fold_share=share, gap=gap)
        if failures(before_bands, rule) == ["gap"]:
            gap = max(gap, gap_replacing_refit(problem, design, blocks, best, k))
        p_bands = st.band_p_value(blocks, null, best, k) if p < level else 1.0
        test = CandidateTest(c.name, params, float(F), p, k, cv_gain, share,
                             float((null.sse - best.sse) / null.sse), gap, p_bands)
        plain = plain_sse(design, best) < plain_sse(design, null)
        failed = failures(test.evidence, rule)
        test.slow_only = bool(failed == ["p_bands"] and plain)
        test.significant = not failed and plain
        test.reason = _reason(test, failed, plain, rule)
        tests[c.name], fits[c.name], chosen[c.name] = test, best, j
    return Screen(tests, fits, chosen, null, blocks, cv_null)


def _reason(test: CandidateTest, failed: list[str], plain: bool, rule: Rule) -> str:
    """Why a candidate was or was not accepted: the first criterion of the rule it fails
    (``failures``), else whether it lowers the plain residual as well."""
    first = failed[0] if failed else None
    if first == "p_value":
        return f"not significant (p = {test.p_value:.2g} >= {rule.level:.2g})"
    if first == "p_bands":
        return (f"not significant on the record's slowest components alone nor on "
                f"the rest alone (p = {test.p_bands:.2g} >= {rule.level:.2g}): slow noise "
                "explains it as well")
    if first == "cv_gain":
        return "does not lower the held-out error (block cross-validation)"
    if first == "fold_share":
        return (f"lowers the held-out error in only {test.fold_share:.0%} of the folds "
                f"(needs {rule.min_fold_share:.0%})")
    if first == "gap":
        return (f"closes a gap of only {test.gap:.2f} x the noise level "
                f"(needs {rule.min_gap:g})")
    if not plain:
        return ("lowers the prewhitened error but not the residual itself: it "
                "fits what the noise model weighs most, not the gap")
    return "significant"


def low_band_of(problem: Problem, whitener: st.Whitener) -> np.ndarray:
    """The record's slowest components (``statistics.low_band``) on the samples that
    ``whitener`` filters and keeps, (M - order, 6, ``problem.settings.low_band``)."""
    return whitener.low_band(problem.model.t[problem.used], problem.sliding,
                             q=problem.settings.low_band)


def plain_sse(design: Design, f: st.Fit) -> float:
    """Sum of squares of the plain (not prewhitened) residual left by a fit's coefficients."""
    a = np.zeros(design.XtX.shape[0])
    a[f.columns] = f.coef
    return float(design.rtr - 2 * a @ design.Xtr + a @ design.XtX @ a)


def gap_closed(design: Design, null: st.Fit, alternative: st.Fit) -> float:
    """RMS change of the fitted residual from null to alternative over the RMS residual left
    (unwhitened, from the design's cross-products)."""
    return _gap(design.XtX, design.Xtr, design.rtr, null, alternative)


def _gap(XtX: np.ndarray, Xtr: np.ndarray, rtr: float, null: st.Fit, alternative: st.Fit
         ) -> float:
    """``gap_closed`` from the cross-products of any columns (X'X, X'r) and r'r."""
    a = np.zeros(len(Xtr))
    a[alternative.columns] = alternative.coef
    change = a.copy()
    change[null.columns] -= null.coef
    left = rtr - 2 * a @ Xtr + a @ XtX @ a
    return float(np.sqrt(max(change @ XtX @ change, 0.0) / max(left, 1e-300)))


def gap_replacing_refit(problem: Problem, design: Design, blocks: st.Blocks,
                        best: st.Fit, fitted: int) -> float:
    """The gap a significant candidate closes when it replaces the refit's changes.

    The refit comes first (a wrong number, not a missing effect), and a candidate's gap is
    measured beyond it. Where the refitted parameters' columns nearly span the candidate's
    (a seal force and the bushings' Coulomb coefficient on moves whose bending loads change
    little), the refit takes most of a missing effect and the gap left beyond it is small,
    while the candidate is significant beyond the refit: the refitted model without it is
    rejected. When, with the candidate present, the data no longer need the refit's change
    of a parameter (held at the model's value it is not significantly worse: F-test at
    ``alpha``, each parameter alone and those held together), the refit's change was the
    candidate's doing: its gap is measured with those parameters held at the model's values,
    in the null model and with the candidate. Only when the candidate, with ``fitted``
    parameters, replaces at least as many refitted changes: an effect with more parameters
    than the changes it replaces is not the simpler explanation (six per-leg offsets for a
    payload mass moved by the bias of the differentiated accelerations), and the refit stays
    first. 0 when no refitted change is replaced.
    """
    s = problem.settings
    index = problem.model.index
    theta0 = problem.model.theta0
    columns = best.columns

    def pinned_bounds(cols):
        lo, hi = design.lower.copy(), design.upper.copy()
        for col in cols:
            name = design.names[col]
            lo[col] = hi[col] = theta0[index[name]] - design.theta[index[name]]
        return lo, hi

    def reduced(f: st.Fit, k: int) -> st.Fit:
        return st.Fit(f.columns[:len(f.columns) - k], f.coef, f.sse, f.rows)

    held = []
    for col in design.refit:
        if design.names[col] not in problem.plausible:
            continue
        f = st.fit(blocks, columns, *pinned_bounds([col]))
        if st.f_test(reduced(f, 1), best)[1] >= s.alpha:
            held.append(col)
    if not held or len(held) < fitted:
        return 0.0
    lo, hi = pinned_bounds(held)
    alternative = st.fit(blocks, columns, lo, hi)
    if st.f_test(reduced(alternative, len(held)), best)[1] < s.alpha:
        return 0.0
    null = st.fit(blocks, design.refit, lo, hi)
    return _gap(design.XtX, design.Xtr, design.rtr, null, alternative)


def candidate_values(problem: Problem, design: Design, c: Candidate, fit: st.Fit,
                     variant: int) -> dict[str, float]:
    """The candidate's parameter values of a fit (fixed and grid values included)."""
    index = problem.model.index
    values = {}
    for col, step in zip(fit.columns, fit.coef):
        name = design.names[col]
        if name.startswith(c.name + "."):
            values[name.split(".", 1)[1]] = float(design.theta[index[name]]
                                                   + design.signs[col] * step)
    for p, v in c.fixed(problem.platform, problem.context).items():
        values[p] = float(v)
    values.update({p: float(v) for p, v in design.grid[c.name][variant].items()})
    return {p: values[p] for p in list(c.fitted) + [p for p in values if p not in c.fitted]}


def winner_of(screen: Screen) -> str | None:
    """The accepted candidate with the largest held-out gain, or None."""
    significant = [t for t in screen.tests.values() if t.significant]
    if not significant:
        return None
    return max(significant, key=lambda t: t.cv_gain).name


def indistinguishable(problem: Problem, design: Design, screen: Screen, winner: str
                       ) -> tuple[list[str], dict[str, float]]:
    """Significant candidates such that the winner adds nothing significant to them."""
    s = problem.settings
    blocks = screen.blocks
    out, p_values = [], {}
    wv = design.variants[winner][screen.variant[winner]]
    for name, test in screen.tests.items():
        if name == winner or not test.significant:
            continue
        cv = design.variants[name][screen.variant[name]]
        alone = st.fit(blocks, design.refit + cv, design.lower, design.upper)
        both = st.fit(blocks, design.refit + cv + wv, design.lower, design.upper)
        _, p, _ = st.f_test(alone, both)
        p_values[name] = p
        if p >= s.alpha:
            out.append(name)
    return out, p_values


def refit_alternatives(problem: Problem, design: Design, screen: Screen,
                       theta0: np.ndarray) -> dict[str, list[str]]:
    """Refitted changes that a candidate could explain just as well.

    For a refitted parameter q whose change from the model's value is significant, a
    candidate c that is not accepted is an alternative when, with q held at the model's value,
    c explains the gap (significant) and q's change is no longer significant with c present:
    the data cannot tell the two explanations apart.
    """
    s = problem.settings
    out: dict[str, list[str]] = {}
    index = problem.model.index
    for col in design.refit:
        name = design.names[col]
        if name not in problem.plausible:
            continue
        pinned_lo, pinned_hi = design.lower.copy(), design.upper.copy()
        pinned_lo[col] = pinned_hi[col] = theta0[index[name]] - design.theta[index[name]]
        fixed = st.fit(screen.blocks, design.refit, pinned_lo, pinned_hi)
        _, p, _ = st.f_test(as_reduced(fixed), screen.null)
        if p >= s.alpha:
            continue
        for c, test in screen.tests.items():
            if test.significant:
                continue
            cols = design.refit + design.variants[c][screen.variant[c]]
            with_c = st.fit(screen.blocks, cols, design.lower, design.upper)
            pinned_c = st.fit(screen.blocks, cols, pinned_lo, pinned_hi)
            _, p_c, _ = st.f_test(as_reduced(fixed), as_reduced(pinned_c))
            _, p_q, _ = st.f_test(as_reduced(pinned_c), with_c)
            if p_c < s.alpha and p_q >= s.alpha:
                out.setdefault(name, []).append(c)
    return out


def as_reduced(f: st.Fit) -> st.Fit:
    """A fit with one parameter pinned, counted as a model with one parameter fewer."""
    return st.Fit(f.columns[:-1], f.coef, f.sse, f.rows)


def bootstrap_share(problem: Problem, design: Design, screen: Screen,
                    rng: np.random.Generator) -> dict[str, float]:
    """Share of block-bootstrap draws (``n_bootstrap // 2``) in which each accepted candidate
    reduces the error most."""
    s = problem.settings
    names = [n for n, t in screen.tests.items() if t.significant]
    if not names:
        return {}
    weights = st.bootstrap_weights(rng, len(screen.blocks.ztz), max(s.n_bootstrap // 2, 1))
    wins = np.zeros(len(names))
    for w in weights:
        null = st.fit(screen.blocks, design.refit, design.lower, design.upper, w)
        gains = []
        for n in names:
            cols = design.refit + design.variants[n][screen.variant[n]]
            f = st.fit(screen.blocks, cols, design.lower, design.upper, w)
            gains.append(null.sse - f.sse)
        wins[int(np.argmax(gains))] += 1
    return {n: float(v / len(weights)) for n, v in zip(names, wins)}


@dataclass
class GenericCompetitor:
    """A round's winner against the generic out-of-catalog basis (``generic_competitor``).

    Attributes
    ----------
    p_winner_beyond_generic : float
        p-value of the winner added to the refitted model and the basis.
    gap_winner_beyond_generic : float
        The gap it closes there, over the RMS left.
    p_generic_beyond_catalog : float
        p-value of the basis added to the refitted model, the winner and every other accepted
        candidate.
    p_generic_bands : float
        The same test on the record's slowest components alone or on the rest alone
        (``statistics.band_p_value``).
    gap_generic_beyond_catalog : float
        The gap the basis closes beyond the catalog, over the RMS left.
    blocked, imitates : bool
        ``competitor_rule``'s decisions.
    main_signal : str or None
        The generic signal that carries most of the basis's part (``lackfit.SIGNALS``).
    """

    p_winner_beyond_generic: float
    gap_winner_beyond_generic: float
    p_generic_beyond_catalog: float
    p_generic_bands: float
    gap_generic_beyond_catalog: float
    blocked: bool
    imitates: bool
    main_signal: str | None


def generic_competitor(problem: Problem, design: Design, whitener: st.Whitener,
                       screen: Screen, winner: str) -> GenericCompetitor:
    """The winner against the generic out-of-model structure of ``lackfit`` (a delay, a
    nonlinear or mis-scaled load cell, another friction law, a drift, a scale error of the
    recorded position), without the signals that a tested candidate reproduces
    (``lackfit.CATALOG_EQUIVALENT``).

    The winner is *blocked* (not named) when it adds nothing worth naming to the generic basis
    (p >= alpha, or a gap below ``min_gap`` times the noise, with the refitted model in both),
    while the generic basis adds something significant (p < alpha / K and a gap of at least
    ``min_gap``) to the winner and every other accepted candidate of the round: the structure
    is then a generic, out-of-catalog one that the winner only imitates in part. The winner
    *imitates* when it adds nothing significant to the generic basis (p >= alpha), whatever
    the basis adds to it, or when it adds nothing worth naming and the basis adds a
    significant part smaller than ``min_gap``: the data cannot tell it from an error outside
    the catalog, as they cannot tell two indistinguishable candidates apart; it is named (the
    simpler explanation), but the verdict is not ``explained``. Returns the p-values and gaps
    both ways (and ``p_generic_bands``, the basis beyond the catalog on the record's slowest
    components alone or on the rest alone: ``statistics.band_tests``),
    ``blocked``, ``imitates`` and the generic signal that carries most.
    """
    s = problem.settings
    side = _BesideBasis.of(problem, design, whitener, screen, winner)
    blocks, lower, upper = side.blocks, side.lower, side.upper
    R, W, O, G = side.groups
    k_w = len(next(c for c in problem.candidates if c.name == winner).fitted)
    generic = st.fit(blocks, R + G, lower, upper)
    both = st.fit(blocks, R + G + W, lower, upper)
    _, p_winner, _ = st.f_test(generic, both, k=k_w)
    catalog = st.fit(blocks, R + W + O, lower, upper)
    everything = st.fit(blocks, R + W + O + G, lower, upper)
    _, p_generic, _ = st.f_test(catalog, everything)
    p_generic_bands = st.band_p_value(blocks, catalog, everything, len(G))
    level = s.alpha / max(len(screen.tests), 1)
    parts = {}
    coef = everything.coef[len(R + W + O):]
    for j, name in enumerate(side.names):
        parts[name] = parts.get(name, 0.0) + float(coef[j] ** 2 * side.basis_sq[j])
    main = max(parts, key=parts.get) if parts else None
    gap_winner = _gap(side.XtX, side.Xtr, design.rtr, generic, both)
    gap_generic = _gap(side.XtX, side.Xtr, design.rtr, catalog, everything)
    blocked, imitates = competitor_rule(p_winner, gap_winner, p_generic, gap_generic,
                                        alpha=s.alpha, level=level, min_gap=s.min_gap)
    return GenericCompetitor(float(p_winner), gap_winner, float(p_generic), p_generic_bands,
                             gap_generic, blocked, imitates, main)


@dataclass
class _BesideBasis:
    """The model's columns of a round (the refit's, the winner's, the other accepted
    candidates') beside the generic basis: prewhitened blocks, the unwhitened cross-products
    X'X and X'r, each basis column's sum of squares and signal, the bounds, and the column
    groups (refit, winner, others, basis)."""

    blocks: st.Blocks
    XtX: np.ndarray
    Xtr: np.ndarray
    basis_sq: np.ndarray
    names: list[str]
    lower: np.ndarray
    upper: np.ndarray
    groups: tuple[list[int], list[int], list[int], list[int]]

    @classmethod
    def of(cls, problem: Problem, design: Design, whitener: st.Whitener, screen: Screen,
           winner: str) -> _BesideBasis:
        used = problem.used
        F = problem.model.forces(design.theta)[used]
        # only what lies outside the catalog as tested: a signal that a candidate (or an
        # effect of the model) reproduces is that effect, not a generic structure
        available = set(screen.tests) | {n.split(".")[0] for n in design.names}
        B, names = lackfit.basis_outside(np.asarray(problem.model.t[used], float), F,
                                         problem.result.D_dot[used], problem.sliding,
                                         problem.weight, available,
                                         pose=problem.model.pose_scale(design.theta, used))
        others = [n for n, t in screen.tests.items() if t.significant and n != winner]
        wcols = design.variants[winner][screen.variant[winner]]
        ocols = [c for n in others for c in design.variants[n][screen.variant[n]]]
        cols = design.refit + wcols + ocols
        # the model's columns and the basis side by side, never joined into one array (that
        # copy was the largest temporary of a round)
        nb = B.shape[2]
        Xc = design.X[:, :, cols]
        s = problem.settings
        blocks = st.Blocks.whitened(whitener, [Xc, B], design.r, s.n_blocks, ridge=s.ridge,
                                    by="time", low=low_band_of(problem, whitener))
        fc, fb, z = Xc.reshape(-1, len(cols)), B.reshape(-1, nb), design.r.reshape(-1)
        cross = fc.T @ fb
        XtX = np.block([[fc.T @ fc, cross], [cross.T, fb.T @ fb]])
        Xtr = np.concatenate([fc.T @ z, fb.T @ z])
        basis_sq = np.diag(XtX)[len(cols):]
        del Xc, B, fc, fb
        nr, nw, no = len(design.refit), len(wcols), len(ocols)
        groups = (list(range(nr)), list(range(nr, nr + nw)),
                  list(range(nr + nw, nr + nw + no)),
                  list(range(nr + nw + no, nr + nw + no + nb)))
        return cls(blocks, XtX, Xtr, basis_sq, names,
                   np.r_[design.lower[cols], np.full(nb, -np.inf)],
                   np.r_[design.upper[cols], np.full(nb, np.inf)], groups)


def competitor_rule(p_winner: float, gap_winner: float, p_generic: float, gap_generic: float,
                    *, alpha: float, level: float, min_gap: float) -> tuple[bool, bool]:
    """Whether a round's winner is blocked (not named) or imitates the generic basis (named,
    never confidently), from the F-tests and gaps of the winner beyond the basis and of the
    basis beyond the catalog (``generic_competitor``).

    Blocked: the winner adds nothing significant to the basis (p >= ``alpha``) while the basis
    adds a significant part of at least ``min_gap`` (p < ``level``) to the catalog. Imitates,
    when not blocked: the winner adds nothing significant, or adds a significant part smaller
    than ``min_gap`` while the basis adds a significant part of any size. The data cannot
    tell such a winner from an error outside the catalog, as they cannot tell two
    indistinguishable candidates apart; a significant winner is a real part of the gap,
    however small beside what the basis takes (a motion differentiated from noisy poses can
    leave several times the noise), so it is named, as the simpler explanation."""
    winner_adds = accept(Evidence(p_winner), Rule(alpha))
    adds = accept(Evidence(p_winner, gap=gap_winner), Rule(alpha, min_gap=min_gap))
    generic_adds = accept(Evidence(p_generic), Rule(level))
    structure = accept(Evidence(p_generic, gap=gap_generic), Rule(level, min_gap=min_gap))
    blocked = structure and not winner_adds
    imitates = not blocked and ((not adds and generic_adds) or not winner_adds)
    return bool(blocked), bool(imitates)
