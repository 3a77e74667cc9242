"""Lack of fit: does structure remain in the final residual that no catalog effect explains?

The final residual is tested against a small generic basis of signals that the common
out-of-model errors of a rig produce, none of them a catalog term in this form:

* ``dF/dt`` (a delay between pose and force channels),
* ``F |F|`` and ``F^3`` (a nonlinear load cell),
* ``F`` (a gain error),
* ``sgn(v)`` on sliding samples (friction of another law),
* ``a`` the leg's acceleration (an inertia or timing error),
* a cubic drift in time (a thermal drift of the load cells).

Each column is shared by the six legs (one coefficient, scaled to unit RMS over all legs): the
load cells of a rig are alike, and a delay or a nonlinearity common to them is then one
column. The residual and the columns are prewhitened with an AR model of the residual left by
the basis fit, and the basis is accepted as *structure* under the rules of a candidate
effect but one (F-test at ``alpha``, a lower held-out error of the block cross-validation in
total, a gap of at least ``min_gap`` times the noise; not "in most folds": a discrepancy
confined to part of the record is still one).
A basis that explains the residual means the catalog did not: the verdict is
``unexplained_discrepancy``, and the signals that carry the structure say what it looks like.
"""

from __future__ import annotations

import numpy as np

from gsfric.discovery import statistics as st

SIGNALS = ("dF/dt", "F|F|", "F^3", "F", "sgn(v)", "acceleration", "drift")

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
}


def basis(t: np.ndarray, F: np.ndarray, speed: np.ndarray, sliding: np.ndarray
          ) -> np.ndarray:
    """The generic columns (M, 6, k) of ``SIGNALS`` (drift: three columns)."""
    t = np.asarray(t, float)
    X = np.empty(F.shape + (9,))
    X[:, :, 0] = np.gradient(F, t, axis=0)
    X[:, :, 1] = F * np.abs(F)
    X[:, :, 2] = F ** 3
    X[:, :, 3] = F
    X[:, :, 4] = np.sign(speed) * sliding
    X[:, :, 5] = np.gradient(speed, t, axis=0)
    tau = 2 * (t - t[0]) / max(t[-1] - t[0], 1e-300) - 1
    for p in (1, 2, 3):
        X[:, :, 5 + p] = np.polynomial.legendre.legval(tau, [0] * p + [1])[:, None]
    for j in range(9):     # unit RMS per signal over all legs (one coefficient: one cause)
        scale = float(np.sqrt(np.mean(X[:, :, j] ** 2)))
        X[:, :, j] /= scale if scale > 0 else 1.0
    return X


def column_names() -> list[str]:
    """The signal of each column of ``basis`` (drift: three columns)."""
    return list(SIGNALS[:-1]) + ["drift"] * 3


def test(residual: np.ndarray, X: np.ndarray, whitener: st.Whitener, *, alpha: float,
         min_gap: float, n_blocks: int, n_folds: int, min_fold_share: float,
         names: list[str] | None = None) -> dict:
    """The lack-of-fit test of the residual (M, 6) against the basis X (M, 6, k) whose
    columns carry the signals ``names`` (default ``column_names()``).

    Returns
    -------
    dict
        ``significant``, ``p_value``, ``gap`` (RMS of the fitted structure over the RMS left),
        ``cv_gain``, ``fold_share``, ``structure_rms`` (N), ``per_leg_rms`` (N, the structure
        on each leg), ``signals`` (each signal's share of the structure), ``fitted`` (M, 6).
    """
    k = X.shape[2]
    blocks = st.Blocks.whitened(whitener, X, residual, n_blocks)
    lo, hi = np.full(k, -np.inf), np.full(k, np.inf)
    empty = st.fit(blocks, [], lo, hi)
    full = st.fit(blocks, list(range(k)), lo, hi)
    _, p, _ = st.f_test(empty, full)
    cv_null = st.cross_validate(blocks, [], lo, hi, n_folds)
    cv = st.cross_validate(blocks, list(range(k)), lo, hi, n_folds)
    cv_gain = float((cv_null.sum() - cv.sum()) / max(cv_null.sum(), 1e-300))
    share = float(np.mean(cv < cv_null))
    fitted = X @ full.coef
    left = residual - fitted
    gap = float(np.sqrt(np.mean(fitted ** 2) / max(np.mean(left ** 2), 1e-300)))
    parts = {}
    total = max(float(np.sum(fitted ** 2)), 1e-300)
    names = column_names() if names is None else names
    for j, name in enumerate(names):
        part = X[:, :, j] * full.coef[j]
        parts[name] = parts.get(name, 0.0) + float(np.sum(part * fitted)) / total
    # no share-of-folds rule: a discrepancy confined to part of the record (the fast end of a
    # chirp) is still a discrepancy; that rule is for naming a stable effect
    significant = bool(p < alpha and cv_gain > 0 and gap >= min_gap)
    return {"significant": significant, "p_value": float(p), "gap": gap, "cv_gain": cv_gain,
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
