"""Model-free structure tests of the final residual: does it repeat with the state, follow
the motion, follow each reversal, or change after each stop?

A discrepancy need not take any of these forms (a gas spring or cable carrier pulling with the
stroke, a screw's ripple, crosstalk between the load cells' channels). What every such error
shares, and noise does not, is that it repeats: it comes back whenever the rig comes back to the
same state. ``state_structure`` tests exactly that, without a model: the residual is averaged
in bins of one state variable at a time (each leg's length, each leg's speed, the model force of
each leg), and the bin means of the other folds of the block cross-validation predict the
held-out fold. Noise, white or slow, does not repeat at the same state in another stretch of
time, so the held-out error grows; a function of the state is predicted, so it falls. The test
needs no prewhitening (the folds are long contiguous stretches) and no dense design matrix
(bin sums per fold).

Nor need it repeat with the state: a lightly damped mode of the rig's structure, excited by the
motion, rings on after every change of force. Its residual follows the motion through a filter,
and an AR noise model can mimic the filter's spectrum, so whitening hides it from the basis.
``dynamic_structure`` asks the question that separates the two (a Granger test): does the
motion (the model force's rate and the legs' acceleration, now and a few samples back) predict
the residual *beyond the residual's own past*? The residual's past absorbs coloured noise
however slow; an input-driven part, delayed, filtered or resonant, is predicted by the input.

Play in a joint and pre-sliding friction are functions of neither the state nor the speed but
of the travel since the last reversal, and their pulses sit right after each reversal, where
the speed is small. ``reversal_structure`` bins the residual, signed by the direction of
travel, by that travel (``travel_since_reversal``) and asks, as ``state_structure`` does,
whether the bin means of the other folds predict the held-out fold.

A friction that the speed describes, whatever its law, is the same at the same speed early and
late in a stroke. Play (no friction while the leg travels through it) and pre-sliding friction
(a stiffness before sliding, a hysteresis loop after each reversal) are functions of the travel
since the last reversal instead, and their pulses sit right after each reversal and each start
in the other direction, where the speed is small and the tests binned by speed see few
samples. ``reversal_structure`` needs no model of either: the residual signed by the direction
of travel, ``r d``, is averaged in bins of the travel since the reversal
(``Settings.travel_edges``), and the bin means of the other contiguous folds predict the
held-out fold, against a single level per fold; where every reversal lies in one fold, the
other legs predict a held-out leg. Noise, white or slow, does not repeat after every reversal
in another stretch of time; a pulse that every reversal leaves does. The size is measured on
the pairs within the last edge of a reversal, where such a pulse lives (its share of all pairs
does not dilute it), and a one-way test of the bins against one level gives the p-value: the
pairs of one reversal, leg and bin are averaged to one value first (the unit of independence
under slow noise), and each bin keeps its own variance (Alexander-Govern: the units of the
short bins near the reversal average fewer pairs than those far from it; the classic F-test's
common variance made it fire on 13 % of white-noise records at the 1 % level).
"""

from __future__ import annotations

import numpy as np

from gsfric.discovery.evidence import Evidence, Rule, Structure, accept
from gsfric.discovery.pvalues import alexander_govern, f_sf
from gsfric.signal.filters import all_pole, fir


def state_features(D: np.ndarray, speed: np.ndarray, F: np.ndarray) -> dict[str, np.ndarray]:
    """The state variables binned by ``state_structure``, each (M, 6): the leg's length (m),
    speed (m/s) and model force (N), and the model force of every other leg (column i of
    ``"force of leg i+k"`` is leg (i + k) mod 6's force)."""
    out = {"leg length": D, "leg speed": speed, "model force": F}
    for k in range(1, F.shape[1]):
        out[f"force of leg i+{k}"] = np.roll(F, -k, axis=1)
    return out


STATE_KEYS = ("significant", "variable", "gap", "cv_gain", "structure_rms", "per_leg_rms",
              "gains")
"""The order of ``state_structure``'s entries in summary.json."""


def state_structure(residual: np.ndarray, features: dict[str, np.ndarray],
                    valid: np.ndarray, *, n_folds: int, min_gap: float,
                    n_bins: int) -> Structure:
    """Does the residual repeat as a function of one state variable? (see the module docstring)

    Parameters
    ----------
    residual : ndarray, shape (M, 6)
        Final residual per leg, N.
    features : dict of str -> ndarray, shape (M, 6)
        State variables per leg (the column of leg i is the variable binned for leg i's
        residual), in any units.
    valid : ndarray of bool, shape (M, 6)
        The (sample, leg) pairs to use (sliding pairs).
    n_folds : int
        Contiguous folds of the cross-validation.
    min_gap : float
        Smallest held-out structure, relative to the RMS left, that counts.
    n_bins : int
        Bins per state variable and leg (``Settings.state_bins``).

    Returns
    -------
    Structure
        ``gap``: held-out structure RMS over the RMS left; ``structure_rms``: of the in-sample
        bin means; no p-value; ``details``: ``variable`` (the best state variable),
        ``cv_gain`` (share of the held-out squared residual that the bin means of the other
        folds predict), ``gains`` (every variable's ``cv_gain``).
    """
    r = np.asarray(residual, float)
    m = len(r)
    fold = np.minimum(np.arange(m) * n_folds // max(m, 1), n_folds - 1)
    gains, fitted_by = {}, {}
    for name, z in features.items():
        gains[name], fitted_by[name] = _binned_gain(r, z, valid, fold, n_folds, n_bins)
    if not gains:
        return Structure(False, 0.0, 0.0, [0.0] * r.shape[1],
                         details={"variable": None, "cv_gain": 0.0, "gains": {}},
                         keys=STATE_KEYS)
    best = max(gains, key=gains.get)
    g = gains[best]
    gap = _gap_of_gain(g)
    fitted = fitted_by[best]
    return Structure(accept(Evidence(gap=gap), Rule(min_gap=min_gap)), gap,
                     **_sizes(fitted, valid),
                     details={"variable": best, "cv_gain": float(g),
                              "gains": {k: float(v) for k, v in gains.items()}},
                     keys=STATE_KEYS)


def _binned_gain(r: np.ndarray, z: np.ndarray, valid: np.ndarray, fold: np.ndarray,
                 n_folds: int, n_bins: int) -> tuple[float, np.ndarray]:
    """``state_structure`` for one state variable z (M, 6): the share of the held-out squared
    residual r (M, 6) that the bin means of the other folds predict (``fold`` (M,), each
    sample's fold), and the in-sample bin means less each leg's mean, (M, 6)."""
    held_err = held_null = 0.0
    fitted = np.zeros_like(r)
    for leg in range(r.shape[1]):
        ok = valid[:, leg] & np.isfinite(z[:, leg])
        if np.count_nonzero(ok) < 4 * n_bins:
            continue
        zi, ri, fi = z[ok, leg], r[ok, leg], fold[ok]
        edges = np.unique(np.quantile(zi, np.linspace(0, 1, n_bins + 1)[1:-1]))
        b = np.searchsorted(edges, zi)
        nb = len(edges) + 1
        key = fi * nb + b
        count = np.bincount(key, minlength=n_folds * nb).reshape(n_folds, nb)
        total = np.bincount(key, ri, minlength=n_folds * nb).reshape(n_folds, nb)
        rest_count = count.sum(0) - count           # the other folds, per fold and bin
        rest_total = total.sum(0) - total
        level = rest_total.sum(1) / np.maximum(rest_count.sum(1), 1)   # the null: a mean
        # a bin the other folds did not visit says nothing about the state: it predicts
        # what the null does (a prediction of zero there beat the null's level whenever
        # slow noise moved the other folds' level away from zero: a few short moves
        # between long rests under pink noise, most bins seen in one fold only)
        mean = np.where(rest_count >= 5, rest_total / np.maximum(rest_count, 1),
                        level[:, None])
        held_err += float(np.sum((ri - mean[fi, b]) ** 2))
        held_null += float(np.sum((ri - level[fi]) ** 2))
        all_mean = total.sum(0) / np.maximum(count.sum(0), 1)
        fitted[np.flatnonzero(ok), leg] = all_mean[b] - ri.mean()
    return (1.0 - held_err / held_null if held_null > 0 else 0.0), fitted


def dynamic_structure(residual: np.ndarray, inputs: dict[str, np.ndarray], valid: np.ndarray,
                      *, alpha: float, min_gap: float, order: int, lags: int) -> Structure:
    """Is the residual driven by the motion beyond its own past? (see the module docstring)

    An ARX model per leg, ``r_t = sum_k a_k r_{t-k} + sum_u sum_j b_uj u_{t-j} + e_t``, with AR
    coefficients per leg and input coefficients shared by the legs (inputs scaled per leg to
    unit RMS), against the AR model alone: an F-test of the input block, and the gap the
    input-driven part (the inputs' term passed through the fitted AR recursion) closes: the
    fall of the residual's mean square when it is taken out, relative to what is left.

    Parameters
    ----------
    residual : ndarray, shape (M, 6)
        Final residual per leg, N.
    inputs : dict of str -> ndarray, shape (M, 6)
        Input signals per leg.
    valid : ndarray of bool, shape (M, 6)
        Pairs to use; a row enters when it and the ``max(order, lags)`` rows before it are valid.
    alpha : float
        Level of the F-test.
    min_gap : float
        Smallest input-driven part, relative to the RMS left, that counts.
    order : int
        Lagged residuals per leg (``Settings.dynamic_order``).
    lags : int
        Lags 0..lags of each input, samples (``Settings.dynamic_lags``).

    Returns
    -------
    Structure
        ``structure_rms``: of the driven part; ``details``: ``inputs`` (each input's share of
        the driven part).
    """
    r = np.asarray(residual, float)
    legs = r.shape[1]
    names = list(inputs)
    k_in = len(names) * (lags + 1)
    k = legs * order + k_in
    A, b, yy, rows, scaled, design = _arx_equations(r, inputs, valid, order, lags)
    empty = Structure(False, 0.0, 0.0, [0.0] * legs, p_value=1.0, details={"inputs": {}})
    if rows <= k + 10:
        return empty
    coef, rss_full, rss_ar = _arx_fit(A, b, yy, legs * order)
    df2 = rows - k
    if rss_full <= 0 or df2 <= 0:
        return empty
    f = ((rss_ar - rss_full) / k_in) / (rss_full / df2)
    p = f_sf(f, k_in, df2)
    driven, shares = _driven_part(r, coef, scaled, design, names, order, lags)
    mask = np.zeros_like(valid)
    for leg in range(legs):
        if design[leg] is not None:
            mask[design[leg], leg] = True
    gap = _driven_gap(r, driven, mask)
    total = max(sum(shares.values()), 1e-300)
    return Structure(accept(Evidence(p, gap=gap), Rule(alpha, min_gap=min_gap)), float(gap),
                     **_sizes(driven, mask), p_value=p,
                     details={"inputs": {n: v / total for n, v in shares.items()}})


def _arx_fit(A: np.ndarray, b: np.ndarray, yy: float, n_ar: int
             ) -> tuple[np.ndarray, float, float]:
    """The least-squares ARX coefficients of the normal equations A (k, k), b (k,), y'y, and
    the residual sums of squares of the full model and of its first ``n_ar`` (AR) columns
    alone."""
    scale = np.sqrt(np.maximum(np.diag(A), 1e-300))
    An = A / np.outer(scale, scale)
    coef = np.linalg.lstsq(An, b / scale, rcond=1e-10)[0] / scale
    rss_full = yy - 2 * coef @ b + coef @ A @ coef
    ar_cols = np.arange(n_ar)
    Ar = A[np.ix_(ar_cols, ar_cols)]
    coef_ar = np.linalg.lstsq(Ar, b[ar_cols], rcond=1e-10)[0]
    rss_ar = yy - 2 * coef_ar @ b[ar_cols] + coef_ar @ Ar @ coef_ar
    return coef, rss_full, rss_ar


def _driven_gap(r: np.ndarray, driven: np.ndarray, mask: np.ndarray) -> float:
    """The gap the driven part (M, 6) closes in the residual r (M, 6) over the pairs of
    ``mask``: the fall of the residual's mean square when it is taken out, over what is left.
    Under resonant or narrow-band noise the AR recursion has poles near the unit circle and
    magnifies a small input coefficient into a large "driven part" that the noise then
    cancels (taking it out leaves more than before): its RMS alone is no measure of what it
    explains."""
    left = float(np.sqrt(np.mean((r - driven)[mask] ** 2)))
    whole = float(np.mean(r[mask] ** 2))
    closed = max(whole - left ** 2, 0.0)
    return float(np.sqrt(closed) / left) if left > 0 else np.inf


def _arx_equations(r: np.ndarray, inputs: dict[str, np.ndarray], valid: np.ndarray,
                   order: int, lags: int) -> tuple:
    """The normal equations of ``dynamic_structure``'s ARX model over the legs: A (k, k),
    b (k,), y'y and the number of rows; each leg's inputs scaled to unit RMS over its valid
    pairs, and each leg's rows (None: none), for ``_driven_part``."""
    m, legs = r.shape
    back = max(order, lags)
    names = list(inputs)
    k_in = len(names) * (lags + 1)
    k = legs * order + k_in
    A = np.zeros((k, k))
    b = np.zeros(k)
    yy = 0.0
    rows = 0
    scaled = {}
    design = []
    for leg in range(legs):
        ok = valid[:, leg].copy()
        run = np.convolve(~ok, np.ones(back + 1), mode="full")[:m] == 0   # the row and back
        run[:back] = False
        idx = np.flatnonzero(run)
        us = []
        for name in names:
            u = np.asarray(inputs[name][:, leg], float)
            s = np.sqrt(np.mean(u[ok] ** 2)) if ok.any() else 0.0
            us.append(u / s if s > 0 else u * 0.0)
        scaled[leg] = us
        if len(idx) == 0:
            design.append(None)
            continue
        ar = np.stack([r[idx - j, leg] for j in range(1, order + 1)], axis=1)
        ins = np.stack([u[idx - j] for u in us for j in range(lags + 1)], axis=1)
        cols = np.concatenate([np.arange(leg * order, (leg + 1) * order),
                               legs * order + np.arange(k_in)])
        X = np.concatenate([ar, ins], axis=1)
        y = r[idx, leg]
        A[np.ix_(cols, cols)] += X.T @ X
        b[cols] += X.T @ y
        yy += float(y @ y)
        rows += len(idx)
        design.append(idx)
    return A, b, yy, rows, scaled, design


def _driven_part(r: np.ndarray, coef: np.ndarray, scaled: dict, design: list,
                 names: list[str], order: int, lags: int) -> tuple[np.ndarray, dict]:
    """The input-driven part (M, 6) of ``dynamic_structure``'s ARX fit ``coef``: the inputs'
    term through each leg's AR recursion (if stable); and each input's sum of squares of it
    over the rows used."""
    legs = r.shape[1]
    driven = np.zeros_like(r)
    shares = dict.fromkeys(names, 0.0)
    for leg in range(legs):
        if design[leg] is None:
            continue
        a = coef[leg * order:(leg + 1) * order]
        den = np.concatenate([[1.0], -a])
        stable = np.all(np.abs(np.roots(den)) < 0.999) if order else True
        # each input through its taps from rest, then all of them through the recursion
        taps = np.stack([fir(coef[legs * order + n_i * (lags + 1):
                                  legs * order + (n_i + 1) * (lags + 1)],
                             np.concatenate([np.zeros(lags), scaled[leg][n_i]]), start=lags)
                         for n_i in range(len(names))], axis=1)
        parts = all_pole(den, taps) if stable else taps
        for n_i, name in enumerate(names):
            driven[:, leg] += parts[:, n_i]
            shares[name] += float(np.sum(parts[design[leg], n_i] ** 2))
    return driven, shares


# -- reversals: what the speed does not describe ----------------------------------------------


def _next_sliding_sign(sign: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """Each sample's ``sign`` (M, 6) at the first sliding sample of its leg at or after it; 0
    after the leg's last sliding sample."""
    m = len(sign)
    rows = np.where(sliding, np.arange(m)[:, None], m)
    following = np.minimum.accumulate(rows[::-1], axis=0)[::-1]
    padded = np.vstack([sign, np.zeros((1, sign.shape[1]))])
    return np.take_along_axis(padded, following, axis=0)


def travel_since_reversal(D: np.ndarray, speed: np.ndarray, sliding: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Each leg's direction of travel and its travel since the last reversal of that direction.

    The direction is the sign of the speed on the sliding pairs; a not-sliding stretch (a
    reversal's noise band, a rest) takes the direction of the sliding pair after it, so a rest
    between two moves the same way is no reversal (a play stays taken up, a pre-sliding
    deflection stays developed) and a reversal's band starts the new direction. The travel is
    measured from the turning point: ``d (D - D_turn)`` with ``D_turn`` the extreme length
    (lowest when moving out, highest when moving in) reached since the direction began.

    Parameters
    ----------
    D : ndarray, shape (M, 6)
        Leg lengths, m.
    speed : ndarray, shape (M, 6)
        Leg speeds dD/dt, m/s.
    sliding : ndarray of bool, shape (M, 6)
        The sliding pairs.

    Returns
    -------
    direction : ndarray, shape (M, 6)
        +1 (extending), -1 (retracting), 0 before the first sliding pair of the leg.
    travel : ndarray, shape (M, 6)
        Travel since the last reversal, m (NaN where the direction is 0 or no reversal has been
        seen yet: the travel since an unseen reversal is unknown).
    """
    D = np.asarray(D, float)
    d = _next_sliding_sign(np.sign(speed), sliding)
    travel = np.full(D.shape, np.nan)
    for leg in range(D.shape[1]):
        col = d[:, leg]
        starts = np.flatnonzero(np.r_[True, col[1:] != col[:-1]])
        stops = np.r_[starts[1:], len(col)]
        for i, (a, b) in enumerate(zip(starts, stops)):
            if col[a] == 0 or i == 0 or col[starts[i - 1]] == 0:
                continue                # no reversal seen before this run
            x = col[a] * D[a:b, leg]
            travel[a:b, leg] = x - np.minimum.accumulate(x)
    return d, travel


REVERSAL_KEYS = ("significant", "p_value", "gap", "cv_gain", "structure_rms", "per_leg_rms",
                 "profile", "reversals")
"""The order of ``reversal_structure``'s entries in summary.json."""


def reversal_structure(residual: np.ndarray, direction: np.ndarray, travel: np.ndarray,
                       valid: np.ndarray, *, n_folds: int, alpha: float, min_gap: float,
                       edges: np.ndarray) -> Structure:
    """Does the friction-like residual depend on the travel since the last reversal? The
    residual signed by the direction of travel, binned by that travel, held out fold by fold
    (see the module docstring).

    Parameters
    ----------
    residual : ndarray, shape (M, 6)
        Final residual per leg, N.
    direction, travel : ndarray, shape (M, 6)
        From ``travel_since_reversal``.
    valid : ndarray of bool, shape (M, 6)
        The pairs to use (sliding pairs).
    n_folds : int
        Contiguous folds of the cross-validation.
    alpha : float
        Level of the one-way test.
    min_gap : float
        Smallest held-out structure near the reversals, relative to the RMS left there, that
        counts.
    edges : ndarray, shape (E,)
        Upper travel edges of the bins, m, increasing (``Settings.travel_edges``).

    Returns
    -------
    Structure
        ``structure_rms``: of the bin means near the reversals; ``details``: ``cv_gain``,
        ``profile`` (the mean ``r d`` per bin, N, with the bins' upper travel edges, m),
        ``reversals`` (reversals seen).
    """
    edges, r = np.asarray(edges, float), np.asarray(residual, float)
    m, legs = r.shape
    empty = Structure(False, 0.0, 0.0, [0.0] * legs, p_value=1.0, keys=REVERSAL_KEYS,
                      details={"cv_gain": 0.0, "profile": [], "reversals": 0})
    ok = valid & np.isfinite(travel) & (direction != 0)
    if np.count_nonzero(ok) < 10 * (len(edges) + 1):
        return empty
    fold = np.minimum(np.arange(m) * n_folds // max(m, 1), n_folds - 1)
    rows, legs_of = np.nonzero(ok)
    y = r[rows, legs_of] * direction[rows, legs_of]
    b, nb = np.searchsorted(edges, travel[rows, legs_of]), len(edges) + 1
    near = b < nb - 1
    f, groups = _prediction_groups(fold[rows], legs_of, near, n_folds, legs)
    count, total, mean, level = _other_groups(f, b, y, groups, nb)
    if not near.any():
        return empty
    g = _held_out_share(y, mean[f, b], level[f], near)
    gap = _gap_of_gain(g)
    turn = _turns(direction)
    p = _one_way_p(y, b, nb, (turn[rows, legs_of] * legs + legs_of) * nb + b)
    all_mean = total.sum(0) / np.maximum(count.sum(0), 1)
    fitted = np.zeros_like(r)
    fitted[rows, legs_of] = (all_mean[b] - y.mean()) * direction[rows, legs_of]
    profile = _profile(list(edges) + [float(np.nanmax(travel[ok]))], all_mean, count.sum(0))
    return Structure(accept(Evidence(p, gap=gap), Rule(alpha, min_gap=min_gap)), gap,
                     **_sizes(fitted, _pairs(ok.shape, rows[near], legs_of[near])), p_value=p,
                     details={"cv_gain": float(g), "profile": profile,
                              "reversals": int(turn.max(axis=0).sum())}, keys=REVERSAL_KEYS)


def _pairs(shape: tuple[int, int], rows: np.ndarray, legs: np.ndarray) -> np.ndarray:
    """A mask of the given shape (M, 6), true at the (sample, leg) pairs ``rows``, ``legs``."""
    mask = np.zeros(shape, bool)
    mask[rows, legs] = True
    return mask


def _sizes(fitted: np.ndarray, mask: np.ndarray) -> dict:
    """``structure_rms`` and ``per_leg_rms`` (N) of the fitted structure (M, 6) over the
    pairs of ``mask`` (M, 6)."""
    return {"structure_rms": float(np.sqrt(np.mean(fitted[mask] ** 2))),
            "per_leg_rms": [float(np.sqrt(np.mean(fitted[mask[:, k], k] ** 2)))
                            if mask[:, k].any() else 0.0 for k in range(fitted.shape[1])]}


def _profile(upper: list[float], means: np.ndarray, counts: np.ndarray
             ) -> list[tuple[float, float]]:
    """(upper edge, mean) of each bin that holds values."""
    return [(float(e), float(v)) for e, v, c in zip(upper, means, counts) if c > 0]


def _held_out_share(y: np.ndarray, predicted: np.ndarray, null: np.ndarray,
                    near: np.ndarray) -> float:
    """The share of the held-out squared values y, over the entries ``near``, that the
    prediction explains beyond the null's (0 without any)."""
    held_err = float(np.sum(((y - predicted) ** 2)[near]))
    held_null = float(np.sum(((y - null) ** 2)[near]))
    return 1.0 - held_err / held_null if held_null > 0 else 0.0


def _turns(direction: np.ndarray) -> np.ndarray:
    """The number of changes of direction (M, 6) of each leg up to each sample."""
    turn = np.zeros(direction.shape, int)
    turn[1:] = np.cumsum(direction[1:] != direction[:-1], axis=0)
    return turn


def _prediction_groups(f: np.ndarray, legs_of: np.ndarray, near: np.ndarray, n_folds: int,
                       legs: int) -> tuple[np.ndarray, int]:
    """The groups whose other members predict each value of ``reversal_structure``: its fold
    f, or, when every value ``near`` a reversal lies in one fold (one move after a rest: no
    other stretch of time can predict it), its leg (the legs' load cells have noises of their
    own); and the number of groups."""
    if len(np.unique(f[near])) < 2:
        return legs_of, legs
    return f, n_folds


def _other_groups(f: np.ndarray, b: np.ndarray, y: np.ndarray, groups: int, nb: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Counts and sums of the values y in each (group f, bin b), (groups, nb); the mean of
    each bin over the other groups (zero where they hold fewer than 5 values), and the level
    of the other groups (the null's prediction), (groups,)."""
    key = f * nb + b
    count = np.bincount(key, minlength=groups * nb).reshape(groups, nb)
    total = np.bincount(key, y, minlength=groups * nb).reshape(groups, nb)
    rest_count = count.sum(0) - count
    rest_total = total.sum(0) - total
    mean = np.where(rest_count >= 5, rest_total / np.maximum(rest_count, 1), 0.0)
    level = rest_total.sum(1) / np.maximum(rest_count.sum(1), 1)
    return count, total, mean, level


def _gap_of_gain(g: float) -> float:
    """The held-out structure's RMS over the RMS left, from the share g of the held-out
    squared residual that it predicts: ``sqrt(g / (1 - g))`` (inf for g >= 1, 0 for g <= 0)."""
    return float(np.sqrt(g / (1.0 - g))) if 0.0 < g < 1.0 else (np.inf if g >= 1.0 else 0.0)


def _one_way_p(y: np.ndarray, b: np.ndarray, nb: int, unit: np.ndarray) -> float:
    """``reversal_structure``'s one-way test of the bins b (of nb) of the values y: one value
    per ``unit`` (reversal, leg, bin), the mean of its pairs; each bin its own variance
    (Alexander-Govern); 1 with fewer than two bins of three units."""
    _, inv, n_u = np.unique(unit, return_inverse=True, return_counts=True)
    u_mean = np.bincount(inv, y) / n_u
    u_bin = np.bincount(inv, b, minlength=len(n_u)) // n_u
    groups = [u_mean[u_bin == k] for k in range(nb) if np.count_nonzero(u_bin == k) >= 3]
    p = alexander_govern(groups) if len(groups) >= 2 else 1.0
    return p if np.isfinite(p) else 1.0
