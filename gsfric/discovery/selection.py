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

from gsfric.discovery import statistics as st
from gsfric.discovery.candidates import Candidate
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


def noise_model(w: st.Whitener) -> dict:
    """The AR model of each leg's residual, for the report."""
    return {"ar_order": [len(c) for c in w.coefficients],
            "lag1_autocorrelation": [round(float(v), 4) for v in w.phi1()],
            "innovation_std": [float(v) for v in w.innovation_std],
            "residual_std": [float(v) for v in w.marginal_std]}


def profile_cv(blocks: st.Blocks, null: list[int], variants: list[list[int]],
               lower: np.ndarray, upper: np.ndarray, n_folds: int) -> np.ndarray:
    """Held-out SSE per fold, the variant chosen on each fold's training blocks."""
    groups = blocks.folds(n_folds)
    out = np.empty(len(groups))
    for f, g in enumerate(groups):
        Af, bf, cf = blocks.held(g)
        At, bt, ct = blocks.without(g)
        best = None
        for v in variants:
            cols = null + v
            idx = np.ix_(cols, cols)
            t = st.solve(At[idx], bt[cols], lower[cols], upper[cols])
            train = st.sse(At[idx], bt[cols], ct, t)
            if best is None or train < best[0]:
                best = (train, st.sse(Af[idx], bf[cols], cf, t))
        out[f] = best[1]
    return out


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
    blocks = st.Blocks.whitened(whitener, design.X, design.r, s.n_blocks,
                                low=low_band_of(problem, whitener))
    null_cols = design.refit
    null = st.fit(blocks, null_cols, design.lower, design.upper)
    cv_null = st.cross_validate(blocks, null_cols, design.lower, design.upper, s.n_folds)
    level = s.alpha / max(len(candidates), 1)
    tests, fits, chosen = {}, {}, {}
    for c in candidates:
        options = [st.fit(blocks, null_cols + v, design.lower, design.upper)
                   for v in design.variants[c.name]]
        j = int(np.argmin([o.sse for o in options]))
        best = options[j]
        F, p, k = st.f_test(null, best, k=len(c.fitted))
        cv = profile_cv(blocks, null_cols, design.variants[c.name], design.lower,
                         design.upper, s.n_folds)
        cv_gain = float((cv_null.sum() - cv.sum()) / cv_null.sum())
        share = st.fold_share(blocks, cv, cv_null, s.n_folds)
        params = candidate_values(problem, design, c, best, j)
        gap = gap_closed(design, null, best)
        if p < level and cv_gain > 0 and share >= s.min_fold_share and gap < s.min_gap:
            gap = max(gap, gap_replacing_refit(problem, design, blocks, best, k))
        p_bands = 1.0
        if p < level:
            p_bands = st.band_p_value(blocks, null, best, k)
        test = CandidateTest(c.name, params, float(F), p, k, cv_gain, share,
                             float((null.sse - best.sse) / null.sse), gap, p_bands)
        plain = plain_sse(design, best) < plain_sse(design, null)
        test.slow_only = bool(p < level <= p_bands and cv_gain > 0 and gap >= s.min_gap
                              and share >= s.min_fold_share and plain)
        if p >= level:
            test.reason = f"not significant (p = {p:.2g} >= {level:.2g})"
        elif p_bands >= level:
            test.reason = (f"not significant on the record's slowest components alone nor on "
                           f"the rest alone (p = {p_bands:.2g} >= {level:.2g}): slow noise "
                           "explains it as well")
        elif cv_gain <= 0:
            test.reason = "does not lower the held-out error (block cross-validation)"
        elif share < s.min_fold_share:
            test.reason = (f"lowers the held-out error in only {share:.0%} of the folds "
                           f"(needs {s.min_fold_share:.0%})")
        elif gap < s.min_gap:
            test.reason = (f"closes a gap of only {gap:.2f} x the noise level "
                           f"(needs {s.min_gap:g})")
        elif not plain:
            test.reason = ("lowers the prewhitened error but not the residual itself: it "
                           "fits what the noise model weighs most, not the gap")
        else:
            test.significant = True
            test.reason = "significant"
        tests[c.name], fits[c.name], chosen[c.name] = test, best, j
    return Screen(tests, fits, chosen, null, blocks, cv_null)


def low_band_of(problem: Problem, whitener: st.Whitener) -> np.ndarray:
    """The record's slowest components (``statistics.low_band``) on the samples that
    ``whitener`` filters and keeps, (M - order, 6, LOW_BAND)."""
    return whitener.low_band(problem.model.t[problem.used], problem.sliding)


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


def generic_competitor(problem: Problem, design: Design, whitener: st.Whitener,
                       screen: Screen, winner: str) -> dict:
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
    from gsfric.discovery import lackfit

    s = problem.settings
    used = problem.used
    F = problem.model.forces(design.theta)[used]
    # only what lies outside the catalog as tested: a signal that a candidate (or an effect of
    # the model) reproduces is that effect, not a generic structure
    available = set(screen.tests) | {n.split(".")[0] for n in design.names}
    B, names = lackfit.basis_outside(np.asarray(problem.model.t[used], float), F,
                                     problem.result.D_dot[used], problem.sliding,
                                     problem.weight, available,
                                     pose=problem.model.pose_scale(design.theta, used))
    others = [n for n, t in screen.tests.items() if t.significant and n != winner]
    wcols = design.variants[winner][screen.variant[winner]]
    ocols = [c for n in others for c in design.variants[n][screen.variant[n]]]
    cols = design.refit + wcols + ocols
    # the model's columns and the basis side by side, never joined into one array (that copy
    # was the largest temporary of a round)
    nb = B.shape[2]
    Xc = design.X[:, :, cols]
    blocks = st.Blocks.whitened(whitener, [Xc, B], design.r, s.n_blocks, by="time",
                                low=low_band_of(problem, whitener))
    fc, fb, z = Xc.reshape(-1, len(cols)), B.reshape(-1, nb), design.r.reshape(-1)
    cross = fc.T @ fb
    XtX = np.block([[fc.T @ fc, cross], [cross.T, fb.T @ fb]])
    Xtr = np.concatenate([fc.T @ z, fb.T @ z])
    basis_sq = np.diag(XtX)[len(cols):]
    del Xc, B, fc, fb

    nr, nw, no = len(design.refit), len(wcols), len(ocols)
    lower = np.r_[design.lower[cols], np.full(nb, -np.inf)]
    upper = np.r_[design.upper[cols], np.full(nb, np.inf)]
    R = list(range(nr))
    W = list(range(nr, nr + nw))
    O = list(range(nr + nw, nr + nw + no))
    G = list(range(nr + nw + no, nr + nw + no + nb))
    k_w = len(next(c for c in problem.candidates if c.name == winner).fitted)
    generic = st.fit(blocks, R + G, lower, upper)
    both = st.fit(blocks, R + G + W, lower, upper)
    _, p_winner, _ = st.f_test(generic, both, k=k_w)
    catalog = st.fit(blocks, R + W + O, lower, upper)
    everything = st.fit(blocks, R + W + O + G, lower, upper)
    _, p_generic, _ = st.f_test(catalog, everything)
    p_generic_bands = st.band_p_value(blocks, catalog, everything, nb)
    level = s.alpha / max(len(screen.tests), 1)
    parts = {}
    coef = everything.coef[len(R + W + O):]
    for j, name in enumerate(names):
        parts[name] = parts.get(name, 0.0) + float(coef[j] ** 2 * basis_sq[j])
    main = max(parts, key=parts.get) if parts else None
    gap_winner = _gap(XtX, Xtr, design.rtr, generic, both)
    gap_generic = _gap(XtX, Xtr, design.rtr, catalog, everything)
    blocked, imitates = competitor_rule(p_winner, gap_winner, p_generic, gap_generic,
                                        alpha=s.alpha, level=level, min_gap=s.min_gap)
    return {"p_winner_beyond_generic": float(p_winner), "gap_winner_beyond_generic": gap_winner,
            "p_generic_beyond_catalog": float(p_generic),
            "p_generic_bands": p_generic_bands,
            "gap_generic_beyond_catalog": gap_generic, "blocked": blocked,
            "imitates": imitates, "main_signal": main}


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
    adds = p_winner < alpha and gap_winner >= min_gap
    structure = p_generic < level and gap_generic >= min_gap
    blocked = structure and p_winner >= alpha
    imitates = not blocked and ((not adds and p_generic < level) or p_winner >= alpha)
    return bool(blocked), bool(imitates)


# -- Gauss-Newton refinement on the compiled model ---------------------------------------------


def refine(problem: Problem, theta: np.ndarray, names: list[str], whitener: st.Whitener,
           start: tuple[np.ndarray, np.ndarray] | None = None
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Newton on the named parameters within their bounds (prewhitened objective).

    ``start``, if given, is the residual (M, 6) and Jacobian (M, 6, k) at theta (which must
    lie within the bounds). Returns theta, the residual and the Jacobian at the result.
    """
    model = problem.model
    cols = [model.index[n] for n in names]
    lo = np.array([problem.bounds(n)[0] for n in names])
    hi = np.array([problem.bounds(n)[1] for n in names])
    theta = theta.copy()
    inside = bool(np.all((theta[cols] >= lo) & (theta[cols] <= hi)))
    theta[cols] = np.clip(theta[cols], lo, hi)
    if DELAY in names:
        profiled = delay_profile(problem, theta, names, whitener)
        if profiled["theta"] is not None:
            theta, inside = profiled["theta"], False

    def at(th):
        F, J = model.jacobian(th, names, rows=problem.used)
        r = problem.mask(problem.y - F[problem.used])
        J *= problem.weight[:, :, None]
        return r, J, float(np.sum(whitener.apply(r) ** 2))

    if start is not None and inside:
        r, J = start
        current = float(np.sum(whitener.apply(r) ** 2))
    else:
        r, J, current = at(theta)
    for _ in range(problem.settings.gauss_newton):
        A, b, _, _ = st.Blocks.whitened(whitener, J, r, problem.settings.n_blocks).total()
        step = st.solve(A, b, lo - theta[cols], hi - theta[cols])
        for scale in (1.0, 0.5, 0.25):
            trial = theta.copy()
            trial[cols] = np.clip(theta[cols] + scale * step, lo, hi)
            r_t, J_t, value = at(trial)
            if value <= current:
                break
        else:
            break
        gain = (current - value) / max(current, 1e-300)
        theta, r, J, current = trial, r_t, J_t, value
        if gain < 1e-5:
            break
    return theta, r, J


DELAY = "time_offset.delay"

DELAY_RANGE = 0.5
"""Half-width (s) of the delays the profile of ``delay_profile`` searches (capped by the
candidate's bounds and a quarter of the record): the largest plausible delay between the pose
and force channels of a rig (buffering, filters, clock offsets)."""

DELAY_GRID = 200
"""Number of steps of the profile's coarse grid over +-``DELAY_RANGE`` (never finer than one
sample)."""


def delay_profile(problem: Problem, theta: np.ndarray, names: list[str],
                  whitener: st.Whitener) -> dict:
    """The global estimate of ``time_offset.delay``: the profile of the prewhitened residual
    sum of squares over the delay, the other parameters of ``names`` refitted linearly at each.

    F depends on the delay only through a shift of the model's forces in time (``catalog``:
    linear interpolation), which moves friction steps and load peaks by whole samples: the
    sum of squares is a rough, many-valleyed function of the delay, and a Gauss-Newton step
    from a secant's estimate stops in the nearest valley while the refitted viscous friction
    and masses take over part of the shifted force. Here the forces and the derivatives of the
    other parameters are computed once at zero delay and shifted, so each point of the
    profile costs a shift and a small bounded least-squares fit: a coarse grid of
    ``DELAY_GRID`` steps (at least one sample) over +-``DELAY_RANGE``, then a bounded scalar
    search within one grid step either side of the best point; the current value is kept
    unless the profile's minimum is lower.

    Returns
    -------
    dict
        ``theta`` (the parameters at the profile's minimum, the others stepped by their linear
        refit; None when the current value is already best), ``delay`` (s), ``sse`` and
        ``sse_current`` (prewhitened sums of squares at the minimum and at the current delay),
        ``delays`` and ``profile`` (the coarse grid and its sums of squares).
    """
    from scipy.optimize import minimize_scalar

    from gsfric.platform.catalog import shift

    model = problem.model
    j = model.index[DELAY]
    others = [n for n in names if n != DELAY]
    cols = [model.index[n] for n in others]
    lo = np.array([problem.bounds(n)[0] for n in others]) - theta[cols]
    hi = np.array([problem.bounds(n)[1] for n in others]) - theta[cols]
    d_lo, d_hi = problem.bounds(DELAY)
    t = model.t
    span = min(DELAY_RANGE, 0.25 * float(t[-1] - t[0]))
    d_lo, d_hi = max(d_lo, -span), min(d_hi, span)
    at_zero = theta.copy()
    at_zero[j] = 0.0
    F, J = model.jacobian(at_zero, others)
    n, k = len(t), len(others)
    FJ = np.concatenate([F[:, :, None], J], axis=2).reshape(n, -1)
    del F, J
    used, weight = problem.used, problem.weight

    def value(d: float) -> tuple[float, np.ndarray]:
        moved = shift(t, FJ, d)[used].reshape(-1, 6, k + 1)
        r = problem.mask(problem.y - moved[:, :, 0])
        X = moved[:, :, 1:] * weight[:, :, None]
        A, b, c, _ = st.Blocks.whitened(whitener, X, r, 1).total()
        step = st.solve(A, b, lo, hi)
        return st.sse(A, b, c, step), step

    dt = float(np.median(np.diff(t)))
    h = max(dt, (d_hi - d_lo) / DELAY_GRID)
    delays = np.arange(d_lo, d_hi + 0.5 * h, h)
    current = float(theta[j])
    profile = np.array([value(float(d))[0] for d in delays])
    best = float(delays[int(np.argmin(profile))])
    found = minimize_scalar(lambda d: value(d)[0], bounds=(max(d_lo, best - h),
                                                           min(d_hi, best + h)),
                            method="bounded", options={"xatol": 1e-3 * dt})
    candidates = [(float(profile.min()), best), (float(found.fun), float(found.x))]
    sse_current = value(current)[0]
    sse_best, delay = min(candidates)
    out = {"theta": None, "delay": current, "sse": sse_current, "sse_current": sse_current,
           "delays": delays, "profile": profile}
    if sse_best < sse_current:
        _, step = value(delay)
        new = theta.copy()
        new[j] = delay
        # within the bounds exactly (the step's bounds were relative to theta: rounding)
        bounds = np.array([problem.bounds(n) for n in others]).reshape(-1, 2)
        new[cols] = np.clip(theta[cols] + step, bounds[:, 0], bounds[:, 1])
        out.update(theta=new, delay=delay, sse=sse_best)
    return out


# -- stability of a named effect across the halves of the record --------------------------------


def half_stability(problem: Problem, J: np.ndarray, r: np.ndarray, names: list[str],
                   effect: str, whitener: st.Whitener) -> dict:
    """Is the effect the same in both halves of the record?

    A physical effect has one value of its parameters over the record; a catalog term that
    imitates an error outside the catalog (per-leg offsets standing in for a nonlinear load
    cell, a delay standing in for a ringing mode) fits whatever that error looks like on each
    stretch of motion, and the stretches differ. The model, linearised at the final
    parameters (J (M, 6, k) with respect to ``names``, residual r (M, 6)), is fitted on the
    first and on the second half of the blocks separately, every parameter free; the
    difference of the effect's parameters is tested by a Wald test (chi-square, the two halves'
    prewhitened covariances summed), and its size is the RMS change of F it makes (N, plain,
    sliding pairs) over the RMS of the final residual.

    Returns
    -------
    dict
        ``p_value``, ``change`` (RMS change of F between the halves over the RMS residual),
        ``half_steps`` (the effect's parameters fitted on each half, as steps from the final
        values), ``stable``.
    """
    from scipy.stats import chi2

    s = problem.settings
    cols = [k for k, n in enumerate(names) if n.startswith(effect + ".")]
    if not cols or J.shape[2] == 0:
        return {"p_value": 1.0, "change": 0.0, "half_steps": [], "stable": True}
    blocks = st.Blocks.whitened(whitener, J, r, s.n_blocks)
    half = len(blocks.ztz) // 2
    k = J.shape[2]
    est = []
    for g in (slice(0, half), slice(half, None)):
        A, b, c = blocks.held(g)
        rows = float(blocks.rows[g].sum())
        inv = np.linalg.pinv(A)
        delta = inv @ b
        s2 = max(c - 2 * delta @ b + delta @ A @ delta, 0.0) / max(rows - k, 1.0)
        est.append((delta, s2 * inv))
    d = est[0][0][cols] - est[1][0][cols]
    V = est[0][1][np.ix_(cols, cols)] + est[1][1][np.ix_(cols, cols)]
    W = float(d @ np.linalg.pinv(V) @ d)
    p = float(chi2.sf(W, len(cols)))
    sliding = problem.sliding
    change_f = J[:, :, cols] @ d
    left = float(np.sqrt(np.mean(r[sliding] ** 2)))
    change = float(np.sqrt(np.mean(change_f[sliding] ** 2))) / max(left, 1e-300)
    steps = [{names[j].split(".", 1)[1]: float(e[0][j]) for j in cols} for e in est]
    stable = not (p < s.alpha and change >= STABILITY_MIN_CHANGE)
    return {"p_value": p, "change": change, "half_steps": steps, "stable": bool(stable)}


STABILITY_MIN_CHANGE = 0.3
"""Smallest change of an effect's contribution between the halves of the record, relative to
the residual left, that makes it unstable (with a Wald test p < alpha)."""
