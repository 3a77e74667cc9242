"""Lack of fit: does structure remain in the final residual that no catalog effect explains?

The final residual is tested against a small generic basis of signals that the common
out-of-model errors of a rig produce, none of them a catalog term in this form:

* ``dF/dt`` (a delay between pose and force channels),
* ``F |F|`` and ``F^3`` (a nonlinear load cell),
* ``F`` (a gain error),
* ``sgn(v)`` on sliding samples (friction of another law),
* ``a`` the leg's acceleration (an inertia or timing error),
* a cubic drift in time (a thermal drift of the load cells),
* as a competitor of a round's winner only (``selection.generic_competitor``), ``dF/de`` for a
  scale error e of each position axis of the recorded pose (x, y, z read ``1 + e`` times the
  true ones, velocity and acceleration with them: a pose measurement's calibration), given by
  the model (``ParametricModel.pose_scale``),
* ``dF/dt`` with coefficients that sum to zero over the legs (five contrasts: leg k's against
  leg 6's; a delay that differs between the force channels beyond their common delay).

Each other column is shared by the six legs (one coefficient, scaled to unit RMS over all
legs): the load cells of a rig are alike, and a delay or a nonlinearity common to them is then
one column. The contrasts reproduce no common delay, so they stay outside the catalog when
``time_offset`` is in it. The residual and the columns are prewhitened with an AR model of
the residual left by the basis fit, and the basis is accepted as *structure* under the
rules of a candidate effect but one (F-test at ``alpha``, a lower held-out error of the block
cross-validation in total, a gap of at least ``min_gap`` times the noise; not "in most
folds": a discrepancy confined to part of the record is still one).
A basis that explains the residual means the catalog did not: the verdict is
``unexplained_discrepancy``, and the signals that carry the structure say what it looks like.

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

All three read only the sliding pairs. What a stop causes (a mode ringing on, a creep of the
load cell, the controller settling) lives in the rests, where friction is static and not given
by the speed's sign. ``rest_transients`` looks there without the model's friction: within a
rest the force is a constant plus noise, the noise's lagged differences are as large at the
start of a rest as at its end, and a transient after the stop makes them larger at the start.

Play in a joint and pre-sliding friction are functions of neither the state nor the speed but
of the travel since the last reversal, and their pulses sit right after each reversal, where
the speed is small. ``reversal_structure`` bins the residual, signed by the direction of
travel, by that travel (``travel_since_reversal``) and asks, as ``state_structure`` does,
whether the bin means of the other folds predict the held-out fold.

Every catalog effect and every refitted parameter is one constant of the record. An error that
a catalog term takes only on average (a Coulomb force growing as a seal warms up, whose mean a
refitted Coulomb coefficient or a named friction takes) leaves its change over the record:
friction-shaped and changing sign between the record's start and end. ``parameter_drift``
tests the parameters' stability in time (a Chow-type test with a linear change): the friction
level varying linearly over the record, by the rules of the basis.
"""

from __future__ import annotations

import numpy as np

from gsfric.discovery import statistics as st

SIGNALS = ("dF/dt", "F|F|", "F^3", "F", "sgn(v)", "acceleration", "drift", "dF/dt between legs",
           "pose scale")

CATALOG_EQUIVALENT = {"dF/dt": "time_offset", "F": "force_scale", "sgn(v)": "seal_friction"}
"""Signals that a catalog effect reproduces (a common delay, a common gain, a common Coulomb
force): out of the catalog only when that effect is not a candidate."""

MEANING = {
    "dF/dt": "correlated with the rate of change of the force: a delay between the pose and "
             "force channels, or a dynamic sensor",
    "F|F|": "growing with the square of the force: a nonlinear load cell",
    "F^3": "growing with the cube of the force: a nonlinear (saturating) load cell",
    "F": "proportional to the force: a gain error of the load cells",
    "sgn(v)": "friction-like, following the sign of the leg speed with a law outside the catalog",
    "acceleration": "correlated with the legs' acceleration: an inertia or timing error",
    "drift": "a slow drift in time: a thermal drift or a zero shift of the load cells",
    "dF/dt between legs": "correlated with the rate of change of the force, differently on each "
                          "leg: a delay that differs between the force channels",
    "pose scale": "what a scale error of the recorded position (x, y or z) makes of the "
                  "rigid-body force: a calibration error of the pose measurement",
}


STATE_MEANING = {
    "leg length": "a function of the stroke position, the same at every visit: a spring or "
                  "cable force, a screw's ripple, a position-dependent friction",
    "leg speed": "a function of the leg speed, the same at every visit: a friction or damping "
                 "law outside the catalog",
    "model force": "a function of the leg's own force: a nonlinear or hysteretic load cell",
}
"""What a repeatable residual in bins of each state variable of ``state_features`` suggests;
the force of another leg means crosstalk between the load cells' channels."""


DYNAMIC_MEANING = ("driven by the motion through a filter (it follows the force's rate or the legs' "
                   "acceleration beyond the residual's own past): a resonance of the structure, "
                   "a delay or the dynamics of the sensor")


def state_features(D: np.ndarray, speed: np.ndarray, F: np.ndarray) -> dict[str, np.ndarray]:
    """The state variables binned by ``state_structure``, each (M, 6): the leg's length (m),
    speed (m/s) and model force (N), and the model force of every other leg (column i of
    ``"force of leg i+k"`` is leg (i + k) mod 6's force)."""
    out = {"leg length": D, "leg speed": speed, "model force": F}
    for k in range(1, F.shape[1]):
        out[f"force of leg i+{k}"] = np.roll(F, -k, axis=1)
    return out


def state_meaning(variable: str) -> str:
    """Plain words for a repeatable residual in bins of ``variable``."""
    if variable.startswith("force of leg"):
        return ("a function of another leg's force: crosstalk between the load cells' channels "
                "or a load path the model does not have")
    return STATE_MEANING.get(variable, "")


def basis(t: np.ndarray, F: np.ndarray, speed: np.ndarray, sliding: np.ndarray,
          derivatives: tuple[np.ndarray, np.ndarray] | None = None,
          pose: np.ndarray | None = None) -> np.ndarray:
    """The generic columns (M, 6, k) of ``SIGNALS`` (drift: three columns; dF/dt between legs:
    five; pose scale: the three columns of ``pose`` (M, 6, 3), dF/de per position axis, if
    given); ``derivatives``, if given, are dF/dt and the legs' acceleration (from ``rates``),
    not computed again."""
    t = np.asarray(t, float)
    legs = F.shape[1]
    extra = 0 if pose is None else pose.shape[2]
    X = np.zeros(F.shape + (9 + legs - 1 + extra,))
    dF, acceleration = derivatives if derivatives is not None else rates(t, F, speed)
    X[:, :, 0] = dF
    X[:, :, 1] = F * np.abs(F)
    X[:, :, 2] = F ** 3
    X[:, :, 3] = F
    X[:, :, 4] = np.sign(speed) * sliding
    X[:, :, 5] = acceleration
    tau = 2 * (t - t[0]) / max(t[-1] - t[0], 1e-300) - 1
    for p in (1, 2, 3):
        X[:, :, 5 + p] = np.polynomial.legendre.legval(tau, [0] * p + [1])[:, None]
    for k in range(legs - 1):     # leg k's delay against the last leg's: sum zero
        X[:, k, 9 + k] = dF[:, k]
        X[:, legs - 1, 9 + k] = -dF[:, legs - 1]
    if extra:
        X[:, :, 9 + legs - 1:] = pose
    for j in range(X.shape[2]):     # unit RMS per signal over all legs (one coefficient: one cause)
        scale = float(np.sqrt(np.mean(X[:, :, j] ** 2)))
        X[:, :, j] /= scale if scale > 0 else 1.0
    return X


def rates(t: np.ndarray, F: np.ndarray, speed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dF/dt (N/s) and the legs' acceleration (m/s^2), each (M, 6), by central differences."""
    t = np.asarray(t, float)
    return np.gradient(F, t, axis=0), np.gradient(speed, t, axis=0)


def column_names(pose: int = 0) -> list[str]:
    """The signal of each column of ``basis`` (drift: three columns; dF/dt between legs:
    five; pose scale: ``pose`` columns)."""
    return list(SIGNALS[:-3]) + ["drift"] * 3 + ["dF/dt between legs"] * 5 + \
        ["pose scale"] * pose


def basis_outside(t: np.ndarray, F: np.ndarray, speed: np.ndarray, sliding: np.ndarray,
                  weight: np.ndarray, catalog,
                  derivatives: tuple[np.ndarray, np.ndarray] | None = None,
                  pose: np.ndarray | None = None) -> tuple[np.ndarray, list[str]]:
    """``basis`` without the signals that an effect of ``catalog`` reproduces
    (``CATALOG_EQUIVALENT``: that effect's parameter, not a structure outside the catalog),
    weighted per (sample, leg) by ``weight`` (M, 6); returns the columns (M, 6, k) and their
    signals."""
    names = column_names(0 if pose is None else pose.shape[2])
    keep = [j for j, name in enumerate(names) if CATALOG_EQUIVALENT.get(name) not in catalog]
    X = basis(t, F, speed, sliding, derivatives, pose)
    if len(keep) < X.shape[2]:
        X = X[:, :, keep]
    X *= weight[:, :, None]
    return X, [names[j] for j in keep]


def test(residual: np.ndarray, X: np.ndarray, whitener: st.Whitener, *, alpha: float,
         min_gap: float, n_blocks: int, n_folds: int, min_fold_share: float,
         names: list[str] | None = None, low: np.ndarray | None = None,
         nuisance: int = 0, by: str = "time") -> dict:
    """The lack-of-fit test of the residual (M, 6) against the basis X (M, 6, k) whose
    columns carry the signals ``names`` (default ``column_names()``); with ``low``, the
    record's slowest components (``statistics.low_band``), the F-test must also hold on them
    alone or on the rest alone (``statistics.band_tests``: a drift that slow noise makes as
    large is not a structure).

    The first ``nuisance`` columns are fitted under the null as well (tested: the others
    beyond them; ``names`` then names the tested columns only). ``by``: the blocks of the
    cross-validation (``statistics.Blocks.whitened``), stretches of equal time (default: the
    basis follows slow noise within one move) or of equal shares of the valid pairs.

    Returns
    -------
    dict
        ``significant``, ``p_value``, ``p_bands`` (0 without ``low``), ``gap`` (RMS of the
        fitted structure over the RMS left), ``cv_gain``, ``fold_share``, ``structure_rms``
        (N), ``per_leg_rms`` (N, the structure on each leg), ``signals`` (each signal's share
        of the structure), ``fitted`` (M, 6); the structure is the tested columns' part.
    """
    columns = X.shape[2]
    k = columns - nuisance
    blocks = st.Blocks.whitened(whitener, X, residual, n_blocks, by=by, low=low)
    lo, hi = np.full(columns, -np.inf), np.full(columns, np.inf)
    null = list(range(nuisance))
    empty = st.fit(blocks, null, lo, hi)
    full = st.fit(blocks, list(range(columns)), lo, hi)
    _, p, _ = st.f_test(empty, full)
    p_bands = 0.0 if low is None else st.band_p_value(blocks, empty, full, k)
    cv_null = st.cross_validate(blocks, null, lo, hi, n_folds)
    cv = st.cross_validate(blocks, list(range(columns)), lo, hi, n_folds)
    cv_gain = float((cv_null.sum() - cv.sum()) / max(cv_null.sum(), 1e-300))
    share = float(np.mean(cv < cv_null))
    fitted = X[:, :, nuisance:] @ full.coef[nuisance:]
    left = residual - X @ full.coef
    gap = float(np.sqrt(np.mean(fitted ** 2) / max(np.mean(left ** 2), 1e-300)))
    parts = {}
    total = max(float(np.sum(fitted ** 2)), 1e-300)
    names = column_names() if names is None else names
    for j, name in enumerate(names):
        part = X[:, :, nuisance + j] * full.coef[nuisance + j]
        parts[name] = parts.get(name, 0.0) + float(np.sum(part * fitted)) / total
    # no share-of-folds rule: a discrepancy confined to part of the record (the fast end of a
    # chirp) is still a discrepancy; that rule is for naming a stable effect. The held-out gain
    # must exceed k / n, what k columns fitted to white noise gain in-sample (and lose
    # held-out): a smaller one is within the cross-validation's own scatter
    significant = bool(p < alpha and p_bands < alpha
                       and cv_gain > k / max(float(blocks.rows.sum()), 1.0) and gap >= min_gap)
    return {"significant": significant, "p_value": float(p), "p_bands": float(p_bands),
            "gap": gap, "cv_gain": cv_gain,
            "fold_share": share, "structure_rms": float(np.sqrt(np.mean(fitted ** 2))),
            "per_leg_rms": [float(v) for v in np.sqrt(np.mean(fitted ** 2, axis=0))],
            "signals": {k_: max(v, 0.0) for k_, v in parts.items()}, "fitted": fitted}


def dominant_frequency(t: np.ndarray, residual: np.ndarray) -> float:
    """Frequency (Hz) of the largest peak of the residual's power spectrum (legs summed)."""
    n = len(t)
    if n < 8:
        return 0.0
    step = float(np.mean(np.diff(t)))
    r = residual - residual.mean(axis=0)
    power = np.sum(np.abs(np.fft.rfft(r, axis=0)) ** 2, axis=1)
    freqs = np.fft.rfftfreq(n, step)
    return float(freqs[1:][np.argmax(power[1:])])


STATE_BINS = 24
"""Bins per state variable and leg in ``state_structure`` (quantiles of the used samples)."""


def state_structure(residual: np.ndarray, features: dict[str, np.ndarray],
                    valid: np.ndarray, *, n_folds: int, min_gap: float,
                    n_bins: int = STATE_BINS) -> dict:
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

    Returns
    -------
    dict
        ``significant``; ``variable`` (the best state variable); ``gap`` (held-out structure
        RMS over the RMS left); ``cv_gain`` (share of the held-out squared residual that the
        bin means of the other folds predict); ``structure_rms`` (N, in-sample bin means);
        ``per_leg_rms`` (N); ``gains`` (every variable's ``cv_gain``).
    """
    r = np.asarray(residual, float)
    m = len(r)
    fold = np.minimum(np.arange(m) * n_folds // max(m, 1), n_folds - 1)
    gains, fitted_by = {}, {}
    for name, z in features.items():
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
        gains[name] = 1.0 - held_err / held_null if held_null > 0 else 0.0
        fitted_by[name] = fitted
    if not gains:
        return {"significant": False, "variable": None, "gap": 0.0, "cv_gain": 0.0,
                "structure_rms": 0.0, "per_leg_rms": [0.0] * r.shape[1], "gains": {}}
    best = max(gains, key=gains.get)
    g = gains[best]
    gap = float(np.sqrt(g / (1.0 - g))) if 0.0 < g < 1.0 else (np.inf if g >= 1.0 else 0.0)
    fitted = fitted_by[best]
    return {"significant": bool(gap >= min_gap), "variable": best, "gap": gap,
            "cv_gain": float(g), "structure_rms": float(np.sqrt(np.mean(fitted[valid] ** 2))),
            "per_leg_rms": [float(np.sqrt(np.mean(fitted[valid[:, k], k] ** 2)))
                            if valid[:, k].any() else 0.0 for k in range(r.shape[1])],
            "gains": {k: float(v) for k, v in gains.items()}}


DYNAMIC_ORDER = 6
"""Lagged residuals per leg in ``dynamic_structure`` (the noise's own past)."""
DYNAMIC_LAGS = 4
"""Current and lagged samples of each input in ``dynamic_structure`` (lags 0..DYNAMIC_LAGS)."""
DYNAMIC_MIN_GAP = 0.5
"""Smallest input-driven part, relative to the RMS left, that the workflow counts (at least
``Settings.min_gap``). A motion differentiated from noisy poses leaves a force error that
follows the accelerations (the smoothing's bias at the fast end of a chirp): on the chirps of
``benchmarks/discovery_rates.py`` (1-2 Hz, heavy payload, AR(1) noise) it reached 0.31 times
the noise left, with the true effect named; a resonance or a delay of the size of the noise is
above 0.6."""


def dynamic_structure(residual: np.ndarray, inputs: dict[str, np.ndarray], valid: np.ndarray,
                      *, alpha: float, min_gap: float, order: int = DYNAMIC_ORDER,
                      lags: int = DYNAMIC_LAGS) -> dict:
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

    Returns
    -------
    dict
        ``significant``, ``p_value``, ``gap``, ``structure_rms`` (N), ``per_leg_rms`` (N),
        ``inputs`` (each input's share of the driven part).
    """
    from scipy import stats
    from scipy.signal import lfilter

    r = np.asarray(residual, float)
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
    empty = {"significant": False, "p_value": 1.0, "gap": 0.0, "structure_rms": 0.0,
             "per_leg_rms": [0.0] * legs, "inputs": {}}
    if rows <= k + 10:
        return empty
    scale = np.sqrt(np.maximum(np.diag(A), 1e-300))
    An = A / np.outer(scale, scale)
    coef = np.linalg.lstsq(An, b / scale, rcond=1e-10)[0] / scale
    rss_full = yy - 2 * coef @ b + coef @ A @ coef
    ar_cols = np.arange(legs * order)
    Ar = A[np.ix_(ar_cols, ar_cols)]
    coef_ar = np.linalg.lstsq(Ar, b[ar_cols], rcond=1e-10)[0]
    rss_ar = yy - 2 * coef_ar @ b[ar_cols] + coef_ar @ Ar @ coef_ar
    df2 = rows - k
    if rss_full <= 0 or df2 <= 0:
        return empty
    f = ((rss_ar - rss_full) / k_in) / (rss_full / df2)
    p = float(stats.f.sf(f, k_in, df2))
    # the input-driven part: the inputs' term through each leg's AR recursion (if stable)
    driven = np.zeros_like(r)
    shares = dict.fromkeys(names, 0.0)
    for leg in range(legs):
        if design[leg] is None:
            continue
        a = coef[leg * order:(leg + 1) * order]
        den = np.concatenate([[1.0], -a])
        stable = np.all(np.abs(np.roots(den)) < 0.999) if order else True
        for n_i, name in enumerate(names):
            bj = coef[legs * order + n_i * (lags + 1):legs * order + (n_i + 1) * (lags + 1)]
            part = lfilter(bj, den if stable else [1.0], scaled[leg][n_i])
            driven[:, leg] += part
            shares[name] += float(np.sum(part[design[leg]] ** 2))
    mask = np.zeros_like(valid)
    for leg in range(legs):
        if design[leg] is not None:
            mask[design[leg], leg] = True
    size = float(np.sqrt(np.mean(driven[mask] ** 2)))
    left = float(np.sqrt(np.mean((r - driven)[mask] ** 2)))
    # the gap the driven part closes: the fall of the residual's mean square when it is taken
    # out, over what is left. Under resonant or narrow-band noise the AR recursion has poles
    # near the unit circle and magnifies a small input coefficient into a large "driven part"
    # that the noise then cancels (taking it out leaves more than before): its RMS alone is
    # no measure of what it explains.
    whole = float(np.mean(r[mask] ** 2))
    closed = max(whole - left ** 2, 0.0)
    gap = float(np.sqrt(closed) / left) if left > 0 else np.inf
    total = max(sum(shares.values()), 1e-300)
    return {"significant": bool(p < alpha and gap >= min_gap), "p_value": p, "gap": float(gap),
            "structure_rms": size,
            "per_leg_rms": [float(np.sqrt(np.mean(driven[mask[:, j], j] ** 2)))
                            if mask[:, j].any() else 0.0 for j in range(legs)],
            "inputs": {n: v / total for n, v in shares.items()}}


# -- rests: what the tests on sliding pairs cannot see ----------------------------------------


REST_MIN_RUN = 48
"""Shortest rest core (samples) that ``rest_runs`` keeps: three windows of 16 samples (the
mean square of fewer lagged differences is too uncertain to compare)."""
REST_MIN_RESTS = 6
"""Fewest rests (groups of overlapping cores) that ``rest_transients`` tests: a t-test on
fewer group means rests on too few numbers to trust its tail."""


def rest_runs(sliding: np.ndarray, reach: int, min_run: int = REST_MIN_RUN
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
        Shortest core kept.

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


REST_WINDOW = 1 / 3
"""Share of each rest core compared at its start and at its end in ``rest_transients``."""
REST_LAGS = (1, 4, 16)
"""Lags (samples) of the differences whose energy ``rest_transients`` compares: fast and slow
transients."""


def rest_transients(residual: np.ndarray, runs: list[tuple[int, int, int]], *, alpha: float,
                    min_gap: float, window: float = REST_WINDOW,
                    lags: tuple[int, ...] = REST_LAGS) -> dict:
    """Does something happen after each stop that the noise does not do? A model-free test on
    the rests, where friction is not given by the speed's sign.

    Within a rest nothing of the model changes: the pose is fixed, the rigid-body force and the
    static friction (whatever it is, up to its static level) are constants. So the residual's
    differences over a lag h, ``x_t - x_{t-h}``, are differences of noise there, and for any
    stationary noise, white or as slow as it comes, their mean square is the same at every
    time. A mode ringing after the stop, a creep or a relaxation of the load cell, the
    controller settling are largest just after the stop. For each core and lag,
    ``u = (e_start - e_end) / (e_start + e_end)``, with ``e`` the mean square of the lagged
    differences over the first and the last ``window`` of the core; noise gives u of mean 0.
    The cores are grouped by rest (the legs' cores that overlap in time: one stop of the
    platform), the groups' mean u is tested against 0 (one-sided t-test, at ``alpha`` over the
    number of lags), and the size is the RMS excess of the differences at the start over their
    level at the end (relative, the lag of the largest); the lag with the smallest p-value
    reports.

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

    Returns
    -------
    dict
        ``significant``, ``p_value``, ``gap`` (excess RMS at the start of the rests over the
        RMS at their end, relative), ``lag``, ``structure_rms`` (N, the excess RMS of the
        residual itself at the start, de-meaned per core), ``per_leg_rms`` (N), ``rests``
        (number of groups), ``cores`` (number of cores), ``u`` (mean u).
    """
    from scipy import stats

    legs = residual.shape[1]
    empty = {"significant": False, "p_value": 1.0, "gap": 0.0, "lag": 0, "structure_rms": 0.0,
             "per_leg_rms": [0.0] * legs, "rests": 0, "cores": len(runs), "u": 0.0}
    if len(runs) < 4:
        return empty
    # group the cores by rest: overlapping in time = one stop of the platform
    order = np.argsort([a for _, a, _ in runs])
    group = np.empty(len(runs), int)
    g, end = -1, -1
    for i in order:
        _, a, b = runs[i]
        if a >= end:
            g += 1
        group[i] = g
        end = max(end, b)
    if g + 1 < REST_MIN_RESTS:
        return {**empty, "rests": g + 1}
    best = None
    for h in lags:
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
            continue
        e0, e1 = np.asarray(e0), np.asarray(e1)
        u = np.where(e0 + e1 > 0, (e0 - e1) / np.maximum(e0 + e1, 1e-300), 0.0)
        gk = group[keep]
        means = np.array([u[gk == k].mean() for k in np.unique(gk)])
        if len(means) < REST_MIN_RESTS or np.ptp(means) == 0:
            continue
        p = float(stats.ttest_1samp(means, 0.0, alternative="greater").pvalue)
        excess = max(float(e0.mean() - e1.mean()), 0.0)
        gap = float(np.sqrt(excess / e1.mean())) if e1.mean() > 0 else 0.0
        if best is None or p < best["p_value"]:
            best = {"p_value": p, "gap": gap, "lag": int(h), "u": float(means.mean()),
                    "rests": int(len(means))}
    if best is None:
        return {**empty, "rests": g + 1}
    # the size of the transient itself: the residual at the start of each core over its end,
    # each de-meaned
    s0, s1, legs_of = [], [], []
    for leg, a, b in runs:
        w = max(int(round(window * (b - a))), 2)
        x = residual[a:b, leg]
        s0.append(float(np.mean((x[:w] - x[:w].mean()) ** 2)))
        s1.append(float(np.mean((x[-w:] - x[-w:].mean()) ** 2)))
        legs_of.append(leg)
    s0, s1, legs_of = np.asarray(s0), np.asarray(s1), np.asarray(legs_of)
    per_leg = [float(np.sqrt(max(s0[legs_of == k].mean() - s1[legs_of == k].mean(), 0.0)))
               if np.any(legs_of == k) else 0.0 for k in range(legs)]
    level = alpha / len(lags)
    return {"significant": bool(best["p_value"] < level and best["gap"] >= min_gap),
            **best, "structure_rms": float(np.sqrt(max(s0.mean() - s1.mean(), 0.0))),
            "per_leg_rms": per_leg, "cores": len(runs)}


REST_MEANING = ("largest just after each stop and dying out during the rest: a mode of the "
                "structure ringing after the stop, a creep or relaxation of the load cells, or "
                "the controller settling")


# -- reversals: what the speed does not describe ----------------------------------------------


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
    import pandas as pd

    D = np.asarray(D, float)
    d = pd.DataFrame(np.where(sliding, np.sign(speed), np.nan)).bfill().fillna(0.0).to_numpy()
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


TRAVEL_EDGES = np.geomspace(2e-5, 1e-2, 10)
"""Edges (m) of the bins of travel since a reversal in ``reversal_structure``: geometric, from
20 um (the smallest play or pre-sliding length resolved at the pose noise of a rig) to 10 mm;
longer travels form the last bin, the reference where the sliding law holds."""


def reversal_structure(residual: np.ndarray, direction: np.ndarray, travel: np.ndarray,
                       valid: np.ndarray, *, n_folds: int, alpha: float, min_gap: float,
                       edges: np.ndarray = TRAVEL_EDGES) -> dict:
    """Does the friction-like residual depend on the travel since the last reversal?

    A friction that the speed describes, whatever its law, is the same at the same speed early
    and late in a stroke. Play in a joint (no friction while the leg travels through it) and
    pre-sliding friction (a stiffness before sliding, a hysteresis loop after each reversal)
    are functions of the travel since the last reversal instead, and their pulses sit right
    after each reversal and each start in the other direction, where the speed is small and
    the tests binned by speed see few samples. This test needs no model of either: the
    residual signed by the direction of travel, ``r d``, is averaged in bins of the travel
    since the reversal (``TRAVEL_EDGES``), and the bin means of the other contiguous folds
    predict the held-out fold (as ``state_structure``), against a single level per fold; where
    every reversal lies in one fold, the other legs predict a held-out leg. Noise,
    white or slow, does not repeat after every reversal in another stretch of time; a pulse
    that every reversal leaves does. The size is measured on the pairs within the last edge of
    a reversal, where such a pulse lives (its share of all pairs does not dilute it), and a
    one-way test of the bins against one level gives the p-value: the pairs of one reversal,
    leg and bin are averaged to one value first (the unit of independence under slow noise),
    and each bin keeps its own variance (Alexander-Govern: the units of the short bins near
    the reversal average fewer pairs than those far from it; the classic F-test's common
    variance made it fire on 13 % of white-noise records at the 1 % level).

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

    Returns
    -------
    dict
        ``significant``, ``p_value``, ``gap``, ``cv_gain``, ``structure_rms`` (N, the bin means
        near the reversals), ``per_leg_rms`` (N), ``profile`` (the mean ``r d`` per bin, N,
        with the bins' upper travel edges, m), ``reversals`` (reversals seen).
    """
    from scipy import stats

    r = np.asarray(residual, float)
    m, legs = r.shape
    empty = {"significant": False, "p_value": 1.0, "gap": 0.0, "cv_gain": 0.0,
             "structure_rms": 0.0, "per_leg_rms": [0.0] * legs, "profile": [], "reversals": 0}
    ok = valid & np.isfinite(travel) & (direction != 0)
    if np.count_nonzero(ok) < 10 * (len(edges) + 1):
        return empty
    fold = np.minimum(np.arange(m) * n_folds // max(m, 1), n_folds - 1)
    rows, legs_of = np.nonzero(ok)
    y = r[rows, legs_of] * direction[rows, legs_of]
    b = np.searchsorted(edges, travel[rows, legs_of])
    nb = len(edges) + 1
    f = fold[rows]
    groups = n_folds
    if len(np.unique(f[b < nb - 1])) < 2:
        # every reversal in one stretch of time (one move after a rest): no other stretch can
        # predict it, but the other legs can; the legs' load cells have noises of their own
        f, groups = legs_of, legs
    key = f * nb + b
    count = np.bincount(key, minlength=groups * nb).reshape(groups, nb)
    total = np.bincount(key, y, minlength=groups * nb).reshape(groups, nb)
    rest_count = count.sum(0) - count
    rest_total = total.sum(0) - total
    mean = np.where(rest_count >= 5, rest_total / np.maximum(rest_count, 1), 0.0)
    level = rest_total.sum(1) / np.maximum(rest_count.sum(1), 1)
    near = b < nb - 1
    if not near.any():
        return empty
    held_err = float(np.sum(((y - mean[f, b]) ** 2)[near]))
    held_null = float(np.sum(((y - level[f]) ** 2)[near]))
    g = 1.0 - held_err / held_null if held_null > 0 else 0.0
    gap = float(np.sqrt(g / (1.0 - g))) if 0.0 < g < 1.0 else (np.inf if g >= 1.0 else 0.0)
    # the one-way test: one value per (reversal, leg, bin), the mean of its pairs
    turn = np.zeros((m, legs), int)
    turn[1:] = np.cumsum(direction[1:] != direction[:-1], axis=0)
    unit = (turn[rows, legs_of] * legs + legs_of) * nb + b
    _, inv, n_u = np.unique(unit, return_inverse=True, return_counts=True)
    u_mean = np.bincount(inv, y) / n_u
    u_bin = np.bincount(inv, b, minlength=len(n_u)) // n_u
    groups = [u_mean[u_bin == k] for k in range(nb) if np.count_nonzero(u_bin == k) >= 3]
    p = float(stats.alexandergovern(*groups).pvalue) if len(groups) >= 2 else 1.0
    p = p if np.isfinite(p) else 1.0
    all_mean = total.sum(0) / np.maximum(count.sum(0), 1)
    fitted = np.zeros_like(r)
    fitted[rows, legs_of] = (all_mean[b] - y.mean()) * direction[rows, legs_of]
    mask = np.zeros_like(ok)
    mask[rows[near], legs_of[near]] = True
    upper = list(edges) + [float(np.nanmax(travel[ok]))]
    return {"significant": bool(p < alpha and gap >= min_gap), "p_value": p, "gap": gap,
            "cv_gain": float(g), "structure_rms": float(np.sqrt(np.mean(fitted[mask] ** 2))),
            "per_leg_rms": [float(np.sqrt(np.mean(fitted[mask[:, k], k] ** 2)))
                            if mask[:, k].any() else 0.0 for k in range(legs)],
            "profile": [(float(e), float(v)) for e, v, c in zip(upper, all_mean, count.sum(0))
                        if c > 0],
            "reversals": int(turn.max(axis=0).sum())}


REVERSAL_MEANING = ("a friction-like force that depends on the travel since the last reversal, "
                    "not on the speed: play in a joint, a pre-sliding (Dahl-like) friction, or "
                    "a friction that builds up after each reversal")


# -- parameter stability in time: what drifts over the record ----------------------------------


DRIFT_SIGNALS = ("sgn(v) drift",)
"""The tested column of ``drift_basis``: the friction level changing linearly over the record
(the level itself, ``sgn(v)``, is fitted beside it under the null as well)."""

DRIFT_MEANING = ("a friction that changes over the record (the friction-like part of the "
                 "residual grows or shrinks with time): a seal or lubricant warming up or "
                 "wearing in")


def drift_basis(t: np.ndarray, speed: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """The columns (M, 6, 2) of the drift test: the friction level ``sgn(v)`` and its change
    ``sgn(v) tau`` (``DRIFT_SIGNALS``) on the sliding pairs, with ``tau`` the time mapped
    linearly onto [-1, 1] over the record (t (M,) s, speed (M, 6) m/s), each scaled to unit
    RMS over all legs (one coefficient for the six legs, as the basis's signals). A gain
    drifting with time (``F tau``) is not a column: on a creep under pink noise it is a slow
    wave like the noise's own wander, and it made a correctly named ``stroke_friction`` read
    unexplained."""
    t = np.asarray(t, float)
    tau = (2 * (t - t[0]) / max(t[-1] - t[0], 1e-300) - 1)[:, None]
    level = np.sign(speed) * sliding
    X = np.stack([level, level * tau], axis=2)
    for j in range(X.shape[2]):
        scale = float(np.sqrt(np.mean(X[:, :, j] ** 2)))
        X[:, :, j] /= scale if scale > 0 else 1.0
    return X


def parameter_drift(residual: np.ndarray, X: np.ndarray, valid: np.ndarray, t: np.ndarray, *,
                    alpha: float, min_gap: float, n_blocks: int, n_folds: int) -> dict:
    """Is the friction level the same over the whole record? (a Chow-type test)

    Every catalog effect and every refitted parameter is a constant of the record. An error
    outside the catalog that a catalog term takes only on average (a Coulomb force that grows
    as a seal warms up, whose mean the refitted Coulomb coefficient or a named friction takes)
    leaves the difference between its value at each time and that mean: friction-shaped
    (``sgn(v)``), changing sign over the record. That residual is tested against the friction
    level's first-order change in time (``drift_basis``: varying linearly over the record, one
    coefficient for the six legs; no catalog effect has such a column), with the level itself
    fitted under the null as well: what the catalog took of the mean is not exactly the mean
    (a Stribeck curve or a viscous refit takes part of a friction that differs between moves
    of different speeds), and a level left over is a friction law's error, not a change. By
    the rules of the generic basis (``test``): prewhitened with the AR model of the residual
    left by the columns, F-test at ``alpha`` also on the record's slowest components alone or
    on the rest alone (``statistics.band_tests``: a wander of slow noise between the moves is
    measured there), a lower held-out error of the block cross-validation, and a gap of at
    least ``min_gap``. The blocks hold equal shares of the sliding pairs: on moves between
    long rests, blocks of equal time put whole moves in one fold, and a change of level is
    not predicted from the other one or two moves.

    Parameters
    ----------
    residual : ndarray, shape (M, 6)
        Final residual per leg (weighted as the fit's), N.
    X : ndarray, shape (M, 6, 2)
        ``drift_basis``, weighted as the residual.
    valid : ndarray of bool, shape (M, 6)
        The pairs of the noise model (sliding pairs).
    t : ndarray, shape (M,)
        Sample times, s.

    Returns
    -------
    dict
        As ``test``: ``significant``, ``p_value``, ``p_bands``, ``gap``, ``cv_gain``,
        ``structure_rms`` (N), ``per_leg_rms`` (N), ``signals``, ``fitted`` (M, 6): of the
        change alone, the level left out.
    """
    whitener = whitener_beyond(residual, X, valid)
    return test(residual, X, whitener, alpha=alpha, min_gap=min_gap, n_blocks=n_blocks,
                n_folds=n_folds, min_fold_share=0.0, names=list(DRIFT_SIGNALS),
                low=whitener.low_band(t, valid), nuisance=1, by="pairs")


def whitener_beyond(residual: np.ndarray, X: np.ndarray, valid: np.ndarray) -> st.Whitener:
    """The AR noise model of the residual (M, 6) left by its least-squares fit by the columns
    X (M, 6, k), on the ``valid`` pairs (M, 6): the largest model's, so that the structure
    the columns test is not whitened away before it is tested."""
    flat = X.reshape(-1, X.shape[2])
    coef = st.solve(flat.T @ flat, flat.T @ residual.reshape(-1))
    return st.Whitener.fit(residual - X @ coef, valid=valid)


def friction_levels(t: np.ndarray, residual: np.ndarray, speed: np.ndarray,
                    valid: np.ndarray, parts: int = 3) -> list[tuple[float, float, float]]:
    """The friction-like level of the residual in each of ``parts`` equal stretches of the
    record: the mean of ``r sgn(v)`` (N; negative: less friction than the model) over the valid
    pairs, with each stretch's first and last time (s); ``(t0, t1, nan)`` for a stretch without
    valid pairs. t (M,) s; residual, speed (M, 6) N and m/s; valid (M, 6) bool."""
    out = []
    for g in np.array_split(np.arange(len(t)), parts):
        if len(g) == 0:
            continue
        ok = valid[g]
        level = (float(np.mean((residual[g] * np.sign(speed[g]))[ok])) if ok.any()
                 else float("nan"))
        out.append((float(t[g[0]]), float(t[g[-1]]), level))
    return out
