"""What happens at the rests, which the tests on the sliding pairs cannot see: a model-free
test of a transient after each stop.

The tests of ``structure`` read only the sliding pairs. What a stop causes (a mode ringing on,
a creep of the load cell, the controller settling) lives in the rests, where friction is
static and not given by the speed's sign. ``rest_transients`` looks there without the model's
friction: within a rest the force is a constant plus noise, the noise's lagged differences are
as large at the start of a rest as at its end, and a transient after the stop makes them
larger at the start.

Within a rest nothing of the model changes: the pose is fixed, the rigid-body force and the
static friction (whatever it is, up to its static level) are constants. So the residual's
differences over a lag h, ``x_t - x_{t-h}``, are differences of noise there, and for any
stationary noise, white or as slow as it comes, their mean square is the same at every time.
A mode ringing after the stop, a creep or a relaxation of the load cell, the controller
settling are largest just after the stop. For each rest core (``rest_runs``) and lag,
``u = (e_start - e_end) / (e_start + e_end)``, with ``e`` the mean square of the lagged
differences over the first and the last ``window`` of the core; noise gives u of mean 0. The
cores are grouped by rest (the legs' cores that overlap in time: one stop of the platform),
the groups' mean u is tested against 0 (one-sided t-test, at ``alpha`` over the number of
lags), and the size is the RMS excess of the differences at the start over their level at the
end (relative, the lag of the largest); the lag with the smallest p-value reports.
"""

from __future__ import annotations

import numpy as np

from gsfric.discovery.evidence import Evidence, Rule, Structure, accept
from gsfric.discovery.pvalues import t_greater


def rest_runs(sliding: np.ndarray, reach: int, *, min_run: int
              ) -> list[tuple[int, int, int]]:
    """The rest cores of each leg: runs of not-sliding pairs with ``2 reach`` samples cut from
    each end, at least ``min_run`` samples long.

    A run of not-sliding pairs is a rest widened by the differentiator's ``reach`` on each
    side (``rest.sliding_mask``), and the rest itself begins where the differentiated speed
    enters the noise band: the last and first few samples of the moves, where the true speed
    is below the band but friction is already sliding friction and the inertia force is still
    changing, belong to it. A second ``reach`` cut from each end leaves where the leg stood
    still.

    Parameters
    ----------
    sliding : ndarray of bool, shape (M, 6)
        The sliding pairs (``rest.sliding_mask``).
    reach : int
        Half-width of the differentiator's window, samples.
    min_run : int
        Shortest core kept, samples (``Settings.rest_min_run``).

    Returns
    -------
    list of (leg, start, stop)
        Sample ranges ``start:stop`` of the cores; a run that touches either end of the record
        is not a rest between two moves and is left out.
    """
    out = []
    m = sliding.shape[0]
    cut = 2 * max(int(reach), 0)
    for leg in range(sliding.shape[1]):
        still = np.r_[False, ~sliding[:, leg], False].astype(np.int8)
        edges = np.flatnonzero(np.diff(still))
        for a, b in zip(edges[::2], edges[1::2]):
            if a == 0 or b == m:
                continue
            a, b = a + cut, b - cut
            if b - a >= min_run:
                out.append((leg, int(a), int(b)))
    return out


def rest_transients(residual: np.ndarray, runs: list[tuple[int, int, int]], *, alpha: float,
                    min_gap: float, window: float, lags: tuple[int, ...],
                    min_rests: int) -> Structure:
    """Does something happen after each stop that the noise does not do? A model-free test on
    the rests, where friction is not given by the speed's sign: the lagged differences of the
    residual at the start of each rest against those at its end (see the module docstring).

    Parameters
    ----------
    residual : ndarray, shape (M, 6)
        Residual per leg at the rest cores (measured force less the model's frictionless force),
        N; other pairs are not read.
    runs : list of (leg, start, stop)
        The rest cores (``rest_runs``).
    alpha : float
        Level of the test.
    min_gap : float
        Smallest excess RMS, relative to the level at the end of the rests, that counts.
    window : float
        Share of each core compared at its start and at its end (``Settings.rest_window``).
    lags : tuple of int
        Lags of the differences, samples (``Settings.rest_lags``).
    min_rests : int
        Fewest rests tested (``Settings.rest_min_rests``).

    Returns
    -------
    Structure
        ``gap``: excess RMS at the start of the rests over the RMS at their end, relative;
        ``structure_rms``: the excess RMS of the residual itself at the start, de-meaned per
        core; ``details``: ``lag``, ``u`` (mean u), ``rests`` (number of groups), ``cores``
        (number of cores).
    """
    legs = residual.shape[1]
    if len(runs) < 4:
        return _no_transient(legs, 0, len(runs))
    group, groups = _rest_groups(runs)
    if groups < min_rests:
        return _no_transient(legs, groups, len(runs))
    best = None
    for h in lags:
        found = _lag_test(residual, runs, group, h, window, min_rests)
        if found is not None and (best is None or found["p_value"] < best["p_value"]):
            best = found
    if best is None:
        return _no_transient(legs, groups, len(runs))
    structure_rms, per_leg = _transient_size(residual, runs, window)
    level = alpha / len(lags)
    p, gap = best.pop("p_value"), best.pop("gap")
    return Structure(accept(Evidence(p, gap=gap), Rule(level, min_gap=min_gap)), gap,
                     structure_rms, per_leg, p_value=p, details={**best, "cores": len(runs)},
                     keys=("significant", "p_value", "gap", "lag", "u", "rests",
                           "structure_rms", "per_leg_rms", "cores"))


def _no_transient(legs: int, rests: int, cores: int) -> Structure:
    """``rest_transients``' result when nothing could be tested: ``rests`` rests and
    ``cores`` cores over ``legs`` legs."""
    return Structure(False, 0.0, 0.0, [0.0] * legs, p_value=1.0,
                     details={"lag": 0, "u": 0.0, "rests": rests, "cores": cores},
                     keys=("significant", "p_value", "gap", "lag", "structure_rms",
                           "per_leg_rms", "rests", "cores", "u"))


def _rest_groups(runs: list[tuple[int, int, int]]) -> tuple[np.ndarray, int]:
    """The rest (group) of each core of ``runs``: cores overlapping in time are one stop of
    the platform; and the number of rests."""
    order = np.argsort([a for _, a, _ in runs])
    group = np.empty(len(runs), int)
    g, end = -1, -1
    for i in order:
        _, a, b = runs[i]
        if a >= end:
            g += 1
        group[i] = g
        end = max(end, b)
    return group, g + 1


def _lag_test(residual: np.ndarray, runs: list[tuple[int, int, int]], group: np.ndarray,
              h: int, window: float, min_rests: int) -> dict | None:
    """``rest_transients``' t-test at lag h: p-value, gap, lag, mean u and the rests tested;
    None when too few cores or rests are long enough, or the rests' means do not differ."""
    e0, e1, keep = [], [], []
    for k, (leg, a, b) in enumerate(runs):
        w = max(int(round(window * (b - a))), 2)
        if w <= h + 1:
            continue
        x = residual[a:b, leg]
        d0 = x[h:w] - x[:w - h]                 # lagged differences at the start
        d1 = x[b - a - w + h:] - x[b - a - w:b - a - h]      # and at the end
        e0.append(float(np.mean(d0 ** 2)))
        e1.append(float(np.mean(d1 ** 2)))
        keep.append(k)
    if len(e0) < 4:
        return None
    e0, e1 = np.asarray(e0), np.asarray(e1)
    u = np.where(e0 + e1 > 0, (e0 - e1) / np.maximum(e0 + e1, 1e-300), 0.0)
    gk = group[keep]
    means = np.array([u[gk == k].mean() for k in np.unique(gk)])
    if len(means) < min_rests or np.ptp(means) == 0:
        return None
    p = t_greater(means)
    excess = max(float(e0.mean() - e1.mean()), 0.0)
    gap = float(np.sqrt(excess / e1.mean())) if e1.mean() > 0 else 0.0
    return {"p_value": p, "gap": gap, "lag": int(h), "u": float(means.mean()),
            "rests": int(len(means))}


def _transient_size(residual: np.ndarray, runs: list[tuple[int, int, int]], window: float
                    ) -> tuple[float, list[float]]:
    """The size of the transient itself (N): the RMS excess of the residual at the start of
    each core over its end, each de-meaned; over all cores and per leg."""
    s0, s1, legs_of = [], [], []
    for leg, a, b in runs:
        w = max(int(round(window * (b - a))), 2)
        x = residual[a:b, leg]
        s0.append(float(np.mean((x[:w] - x[:w].mean()) ** 2)))
        s1.append(float(np.mean((x[-w:] - x[-w:].mean()) ** 2)))
        legs_of.append(leg)
    s0, s1, legs_of = np.asarray(s0), np.asarray(s1), np.asarray(legs_of)
    per_leg = [float(np.sqrt(max(s0[legs_of == k].mean() - s1[legs_of == k].mean(), 0.0)))
               if np.any(legs_of == k) else 0.0 for k in range(residual.shape[1])]
    return float(np.sqrt(max(s0.mean() - s1.mean(), 0.0))), per_leg
