"""Lack of fit: does structure remain in the final residual that no catalog effect explains?

The final residual is tested against a small generic basis of signals that the common
out-of-model errors of a rig produce, none of them a catalog term in this form: the ``basis``
entries of ``outside.OUTSIDE``, which say what each suggests. Two are built apart from the
others: ``pose scale`` (a competitor of a round's winner only, ``selection.generic_competitor``)
is ``dF/de`` for a scale error e of each position axis of the recorded pose, given by the model
(``ParametricModel.pose_scale``); ``dF/dt between legs`` is dF/dt with coefficients that sum to
zero over the legs (five contrasts: leg k's against leg 6's).

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

Every catalog effect and every refitted parameter is one constant of the record. An error that
a catalog term takes only on average (a Coulomb force growing as a seal warms up, whose mean a
refitted Coulomb coefficient or a named friction takes) leaves its change over the record:
friction-shaped and changing sign between the record's start and end. ``parameter_drift``
tests the parameters' stability in time (a Chow-type test with a linear change): the friction
level varying linearly over the record, by the rules of the basis.
"""

from __future__ import annotations

import numpy as np

from gsfric.discovery import outside
from gsfric.discovery import statistics as st
from gsfric.discovery.evidence import Evidence, Rule, Structure, accept
from gsfric.discovery.settings import Settings

SIGNALS = outside.names("basis")
"""The generic signals (``outside.OUTSIDE``), in the order of the basis's columns."""

CATALOG_EQUIVALENT = {"dF/dt": "time_offset", "F": "force_scale", "sgn(v)": "seal_friction"}
"""Signals that a catalog effect reproduces (a common delay, a common gain, a common Coulomb
force): out of the catalog only when that effect is not a candidate."""


def basis(t: np.ndarray, F: np.ndarray, speed: np.ndarray, sliding: np.ndarray,
          derivatives: tuple[np.ndarray, np.ndarray] | None = None,
          pose: np.ndarray | None = None, keep: list[int] | None = None) -> np.ndarray:
    """The generic columns (M, 6, k) of ``SIGNALS`` (drift: three columns; dF/dt between legs:
    five; pose scale: the three columns of ``pose`` (M, 6, 3), dF/de per position axis, if
    given), only those of ``keep`` (their indices in ``column_names``, in order) if given;
    ``derivatives``, if given, are dF/dt and the legs' acceleration (from ``rates``), not
    computed again."""
    t = np.asarray(t, float)
    legs = F.shape[1]
    extra = 0 if pose is None else pose.shape[2]
    keep = list(range(9 + legs - 1 + extra)) if keep is None else list(keep)
    at = {j: i for i, j in enumerate(keep)}
    X = np.zeros(F.shape + (len(keep),))

    def put(j, value, leg=slice(None)) -> None:
        if j in at:
            X[:, leg, at[j]] = value

    dF, acceleration = derivatives if derivatives is not None else rates(t, F, speed)
    for j, value in enumerate((dF, F * np.abs(F), F ** 3, F, np.sign(speed) * sliding,
                               acceleration)):
        put(j, value)
    tau = 2 * (t - t[0]) / max(t[-1] - t[0], 1e-300) - 1
    for p in (1, 2, 3):
        put(5 + p, np.polynomial.legendre.legval(tau, [0] * p + [1])[:, None])
    for k in range(legs - 1):     # leg k's delay against the last leg's: sum zero
        put(9 + k, dF[:, k], k)
        put(9 + k, -dF[:, legs - 1], legs - 1)
    for e in range(extra):
        put(9 + legs - 1 + e, pose[:, :, e])
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
    X = basis(t, F, speed, sliding, derivatives, pose, keep)
    X *= weight[:, :, None]
    return X, [names[j] for j in keep]


TEST_KEYS = ("significant", "p_value", "p_bands", "gap", "cv_gain", "fold_share",
             "structure_rms", "per_leg_rms", "signals")
"""The order of ``test``'s entries in summary.json."""


def test(residual: np.ndarray, X: np.ndarray, whitener: st.Whitener, *, alpha: float,
         min_gap: float, n_blocks: int, n_folds: int, ridge: float,
         names: list[str] | None = None, low: np.ndarray | None = None,
         nuisance: int = 0, by: str = "time") -> Structure:
    """The lack-of-fit test of the residual (M, 6) against the basis X (M, 6, k) whose
    columns carry the signals ``names`` (default ``column_names()``), its fits solved with
    ``ridge`` (``statistics.solve``); with ``low``, the
    record's slowest components (``statistics.low_band``), the F-test must also hold on them
    alone or on the rest alone (``statistics.band_tests``: a drift that slow noise makes as
    large is not a structure).

    The first ``nuisance`` columns are fitted under the null as well (tested: the others
    beyond them; ``names`` then names the tested columns only). ``by``: the blocks of the
    cross-validation (``statistics.Blocks.whitened``), stretches of equal time (default: the
    basis follows slow noise within one move) or of equal shares of the valid pairs.

    Returns
    -------
    Structure
        ``gap``: RMS of the fitted structure over the RMS left; ``fitted`` (M, 6): the tested
        columns' part; ``details``: ``p_bands`` (0 without ``low``), ``cv_gain``,
        ``fold_share``, ``signals`` (each signal's share of the structure).
    """
    columns = X.shape[2]
    k = columns - nuisance
    blocks = st.Blocks.whitened(whitener, X, residual, n_blocks, ridge=ridge, by=by, low=low)
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
    rule = Rule(alpha, min_gap=min_gap, min_cv_gain=k / max(float(blocks.rows.sum()), 1.0))
    significant = accept(Evidence(p, p_bands, cv_gain, gap=gap), rule)
    return Structure(significant, gap, float(np.sqrt(np.mean(fitted ** 2))),
                     [float(v) for v in np.sqrt(np.mean(fitted ** 2, axis=0))],
                     p_value=float(p),
                     details={"p_bands": float(p_bands), "cv_gain": cv_gain,
                              "fold_share": share,
                              "signals": {k_: max(v, 0.0) for k_, v in parts.items()}},
                     fitted=fitted, keys=TEST_KEYS)


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


# -- parameter stability in time: what drifts over the record ----------------------------------


DRIFT_SIGNALS = ("sgn(v) drift",)
"""The tested column of ``drift_basis``: the friction level changing linearly over the record
(the level itself, ``sgn(v)``, is fitted beside it under the null as well)."""

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


def parameter_drift(residual: np.ndarray, X: np.ndarray, valid: np.ndarray, t: np.ndarray,
                    settings: Settings) -> Structure:
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
    settings : Settings
        ``alpha``, ``min_gap``, ``n_blocks``, ``n_folds``, and the noise model's and the
        fits' ``max_order``, ``ridge`` and ``low_band``.

    Returns
    -------
    Structure
        As ``test``; ``fitted`` (M, 6): the change alone, the level left out.
    """
    s = settings
    whitener = whitener_beyond(residual, X, valid, s)
    return test(residual, X, whitener, alpha=s.alpha, min_gap=s.min_gap, n_blocks=s.n_blocks,
                n_folds=s.n_folds, ridge=s.ridge,
                names=list(DRIFT_SIGNALS), low=whitener.low_band(t, valid, q=s.low_band),
                nuisance=1, by="pairs")


def whitener_beyond(residual: np.ndarray, X, valid: np.ndarray, settings: Settings,
                    cols=None, cross: tuple[np.ndarray, np.ndarray] | None = None
                    ) -> st.Whitener:
    """The AR noise model of the residual (M, 6) left by its least-squares fit by the columns
    X (M, 6, k), on the ``valid`` pairs (M, 6): the largest model's, so that the structure
    the columns test is not whitened away before it is tested. The fit is solved with
    ``settings.ridge``, the AR model's order is at most ``settings.max_order``.

    ``cols``: only these columns of X, read one at a time (X may then be a round's design,
    ``residuals.Columns``: no copy of it); ``cross``: their cross-products (X'X (k, k),
    X'r (k,)) when known, else computed from X (an array)."""
    if cross is None:
        flat = (X if cols is None else X[:, :, list(cols)])
        flat = flat.reshape(-1, flat.shape[2])
        cross = (flat.T @ flat, flat.T @ residual.reshape(-1))
    coef = st.solve(*cross, ridge=settings.ridge)
    if cols is None:
        return st.Whitener.fit(residual - X @ coef, settings.max_order, valid=valid)
    left = residual.copy()
    for c, value in zip(cols, coef):
        left -= X[:, :, c] * value
    return st.Whitener.fit(left, settings.max_order, valid=valid)


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
