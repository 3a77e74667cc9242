"""Decisions that hold under autocorrelated residuals.

Measurement residuals are never white: force noise is coloured, and so are the errors of a
motion differentiated from noisy poses. A least-squares fit and an F-test or BIC that assume
white noise count every sample as new information and find "effects" everywhere. The workflow
uses these tools instead, each on a linearised model (the columns of dF/dtheta):

* **Prewhitening** (``Whitener``): an AR(p) model is fitted to each leg's residual
  (Yule-Walker via Levinson-Durbin, order by BIC up to ``Settings.max_order``), and residuals
  and design columns are filtered by ``1 - sum phi_j L^j``. Generalised least squares then
  becomes ordinary least squares on filtered data, and nested F-tests on the filtered data are
  approximately valid. * **Block cross-validation** (``cross_validate``): the samples are cut
  into contiguous stretches of time, each holding an equal share of the used (sample, leg)
  pairs (``block_edges``); each fold leaves out a stretch, fits on the rest and scores the
  one-step prediction error (the prewhitened residual) of the stretch left out. Autocorrelated
  noise cannot leak between folds much further than its correlation time, which is far shorter
  than a stretch. * **Block bootstrap** (``bootstrap``): stretches are drawn with replacement
  to measure how stable the choice of effect is and how uncertain its parameters are. * **The
  slowest components on their own noise** (``low_band``, ``band_tests``): an AR model of a
  dozen lags does not see noise whose power keeps rising towards the lowest frequencies (1/f
  noise, a thermal wander), and tests of what lives at the record's slowest components (an
  offset of each channel) against it are too confident. The same F-test is made on those
  components alone, with the noise measured on them, and on the rest alone.

All of them work on cross-products of the prewhitened design per block (``Blocks``), so
a fit is a small (k x k) solve whatever the number of samples.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gsfric._optional import optional
from gsfric.discovery.pvalues import f_sf
from gsfric.signal.filters import fir_channels

# -- AR noise model ---------------------------------------------------------------------------


def _autocovariance(e: np.ndarray, max_lag: int, valid: np.ndarray | None = None
                    ) -> np.ndarray:
    """Autocovariances (max_lag + 1, k) of the columns of e (N, k) (biased estimator).

    With ``valid`` (N, k) bool, only valid samples count: each lag's sum of products over the
    valid pairs, over the number of such pairs (the estimator for series with gaps)."""
    n = e.shape[0]
    if valid is None:
        e = e - e.mean(axis=0)
        return np.stack([np.einsum("ij,ij->j", e[lag:], e[:n - lag])
                         for lag in range(max_lag + 1)]) / n
    # sums over lags directly (max_lag is small): no transform of twice the series' length
    w = valid.astype(float)
    count = np.maximum(w.sum(axis=0), 1.0)
    e = (e - (e * w).sum(axis=0) / count) * w
    num = np.stack([np.einsum("ij,ij->j", e[lag:], e[:n - lag]) for lag in range(max_lag + 1)])
    pairs = np.stack([np.einsum("ij,ij->j", w[lag:], w[:n - lag])
                      for lag in range(max_lag + 1)])
    return num / np.maximum(np.round(pairs), 1.0) * (1.0 - np.arange(max_lag + 1) / n)[:, None]


def _levinson(r: np.ndarray, order: int) -> tuple[list[np.ndarray], np.ndarray]:
    """AR coefficients of every order up to ``order`` and their innovation variances."""
    phis = [np.zeros(0)]
    variances = [r[0]]
    phi = np.zeros(0)
    v = r[0]
    for p in range(1, order + 1):
        if v <= 0:
            break
        k = (r[p] - phi @ r[p - 1:0:-1]) / v if p > 1 else r[1] / v
        if not abs(k) < 1.0:
            # the autocovariances of a series with gaps (each lag over its own pairs) need not
            # be positive definite: from this order on no AR model has them, and the
            # recursion's innovation variance is zero or negative, an order that BIC, seeing a
            # log-likelihood without bound, would always pick
            break
        phi = np.concatenate([phi - k * phi[::-1], [k]])
        v = v * (1 - k * k)
        phis.append(phi.copy())
        variances.append(v)
    return phis, np.array(variances)


@dataclass
class Whitener:
    """Per-leg AR(p) prewhitening filters.

    Attributes
    ----------
    coefficients : list of ndarray
        ``phi`` of each leg (length its order).
    innovation_std : ndarray, shape (6,)
        Standard deviation of each leg's innovations, N.
    marginal_std : ndarray, shape (6,)
        Standard deviation of each leg's residual, N.
    """

    coefficients: list[np.ndarray]
    innovation_std: np.ndarray
    marginal_std: np.ndarray
    valid: np.ndarray | None = None

    @property
    def order(self) -> int:
        """Largest order over the legs: the number of leading samples the filter drops."""
        return max(len(c) for c in self.coefficients)

    @classmethod
    def fit(cls, residual: np.ndarray, max_order: int,
            valid: np.ndarray | None = None) -> Whitener:
        """AR models of each leg's residual (N, 6), orders by BIC.

        Parameters
        ----------
        residual : ndarray, shape (N, 6)
        max_order : int
            Largest AR order tried (``Settings.max_order``; at most a tenth of N).
        valid : ndarray (N, 6) of bool, optional
            The samples that count (the others are gaps: the model is fitted on the valid
            ones, and a filtered sample whose filter window touches a gap is set to zero by
            ``apply``, so that nothing of a gap leaks into the filtered data).
        """
        n, legs = residual.shape
        max_order = int(min(max_order, max(1, n // 10)))
        acov = _autocovariance(residual, max_order, valid)
        coefs, innov = [], []
        for i in range(legs):
            phis, var = _levinson(acov[:, i], max_order)
            bic = [n * np.log(max(v, 1e-300)) + p * np.log(n) for p, v in enumerate(var)]
            p = int(np.argmin(bic))
            coefs.append(phis[p])
            innov.append(np.sqrt(max(var[p], 0.0)))
        return cls(coefs, np.array(innov), np.sqrt(np.maximum(acov[0], 0.0)),
                   None if valid is None else np.asarray(valid, bool))

    @classmethod
    def identity(cls, legs: int = 6) -> Whitener:
        """No filtering (white noise)."""
        return cls([np.zeros(0)] * legs, np.ones(legs), np.ones(legs))

    def apply(self, a: np.ndarray, valid: np.ndarray | None = None) -> np.ndarray:
        """Filter ``a`` (N, 6, ...) along time; returns (N - order, 6, ...).

        Filtered samples whose window (the sample and the ``order`` before it) touches an
        invalid one are zero: ``valid`` (N, 6) if given, else the fit's own ``valid`` when
        ``a`` has its length."""
        if valid is None and self.valid is not None and len(self.valid) == a.shape[0]:
            valid = self.valid
        out = fir_channels(self.taps(), a)
        if valid is not None:
            window = self.kept(valid)
            out *= window.reshape(window.shape + (1,) * (out.ndim - 2))
        return out

    def taps(self) -> np.ndarray:
        """The filters ``1 - sum phi_j L^j`` of the legs side by side, (order + 1, 6): column i
        holds ``[1, -phi_1, ..., -phi_p]`` of leg i, zeros beyond its own order."""
        b = np.zeros((self.order + 1, len(self.coefficients)))
        b[0] = 1.0
        for i, phi in enumerate(self.coefficients):
            b[1:len(phi) + 1, i] = -phi
        return b

    def kept(self, valid: np.ndarray | None = None, n: int | None = None) -> np.ndarray:
        """The filtered samples (N - order, 6) that ``apply`` keeps: those whose window holds
        valid samples only (``valid`` (N, 6), default the fit's own; all of them without
        one, N = ``n``)."""
        valid = self.valid if valid is None else valid
        p = self.order
        if valid is None:
            return np.ones((n - p, len(self.coefficients)), bool)
        ok = np.asarray(valid, bool)
        window = ok[p:].copy()
        for lag in range(1, p + 1):
            window &= ok[p - lag:len(ok) - lag]
        return window

    def low_band(self, t: np.ndarray, valid: np.ndarray | None = None, *, q: int
                 ) -> np.ndarray:
        """The record's ``q`` slowest components (``low_band``; ``Settings.low_band``) on
        the filtered samples that ``apply`` keeps (``kept``): t (N,) s, the times of the
        unfiltered samples; valid as ``kept``. Shape (N - order, 6, q)."""
        t = np.asarray(t, float)
        return low_band(t[self.order:], self.kept(valid, len(t)), q)

    def phi1(self) -> np.ndarray:
        """Lag-one autocorrelation implied by each leg's model, (6,)."""
        out = []
        for phi in self.coefficients:
            if len(phi) == 0:
                out.append(0.0)
                continue
            # autocorrelation at lag 1 from the Yule-Walker equations of the fitted model
            p = len(phi)
            M = np.eye(p)
            for k in range(1, p + 1):
                for j in range(1, p + 1):
                    lag = abs(k - j)
                    if lag:
                        M[k - 1, lag - 1] -= phi[j - 1]
            rho = np.linalg.solve(M, phi)
            out.append(float(rho[0]))
        return np.array(out)


# -- cross-products by blocks -----------------------------------------------------------------


@dataclass(frozen=True)
class FoldSums:
    """The cross-products of each fold of a cross-validation (``Blocks.fold_sums``).

    Attributes
    ----------
    held_A, held_b, held_c : ndarray, shapes (F, k, k), (F, k), (F,)
        XtX, Xtz and ztz summed over each fold's held-out blocks.
    train_A, train_b, train_c : ndarray, shapes (F, k, k), (F, k), (F,)
        The same summed over each fold's training blocks (all the others).
    """

    held_A: np.ndarray
    held_b: np.ndarray
    held_c: np.ndarray
    train_A: np.ndarray
    train_b: np.ndarray
    train_c: np.ndarray


@dataclass
class Blocks:
    """Cross-products of a prewhitened design per contiguous block of samples.

    Attributes
    ----------
    XtX : ndarray, shape (B, k, k)
    Xtz : ndarray, shape (B, k)
    ztz : ndarray, shape (B,)
    rows : ndarray, shape (B,)
        Number of scalar observations (samples x legs) in each block.
    ridge : float
        Ridge of every solve on these cross-products (``solve``, ``Settings.ridge``).
    """

    XtX: np.ndarray
    Xtz: np.ndarray
    ztz: np.ndarray
    rows: np.ndarray
    ridge: float
    low_X: np.ndarray | None = None
    low_z: np.ndarray | None = None
    low_rows: float = 0.0
    _sums: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    """Sums kept once computed: ``fold_sums`` by fold count, ``total``'s under "total"."""

    @classmethod
    def build(cls, X: np.ndarray, z: np.ndarray, n_blocks: int, *, ridge: float) -> Blocks:
        """Blocks of a design X (M, 6, k) and target z (M, 6), cut into ``n_blocks`` stretches
        of equal length (the last one takes the remainder), solved with ``ridge``."""
        m, legs, k = X.shape
        length = m // n_blocks
        cut = length * n_blocks
        Xb = np.ascontiguousarray(X[:cut]).reshape(n_blocks, length * legs, k)
        zb = np.ascontiguousarray(z[:cut]).reshape(n_blocks, length * legs, 1)
        XtX = np.einsum("bik,bil->bkl", Xb, Xb)
        Xtz = np.einsum("bik,bi->bk", Xb, zb[:, :, 0])
        ztz = np.einsum("bi,bi->b", zb[:, :, 0], zb[:, :, 0])
        rows = np.full(n_blocks, float(length * legs))
        if cut < m:
            Xr = X[cut:].reshape(-1, k)
            zr = z[cut:].reshape(-1)
            XtX[-1] += np.einsum("ik,il->kl", Xr, Xr)
            Xtz[-1] += np.einsum("ik,i->k", Xr, zr)
            ztz[-1] += zr @ zr
            rows[-1] += zr.size
        return cls(XtX, Xtz, ztz, rows, ridge)

    @classmethod
    def whitened(cls, whitener: "Whitener", X: np.ndarray | Sequence[np.ndarray], z: np.ndarray,
                 n_blocks: int, *, ridge: float, by: str = "pairs",
                 low: np.ndarray | None = None) -> Blocks:
        """The blocks of ``whitener.apply(X)`` and ``whitener.apply(z)``, solved with
        ``ridge`` (``solve``), computed block by
        block without holding a whitened copy of X (the filter is a short FIR filter, so each
        block needs only ``order`` samples before it). X may be a sequence of arrays
        (M, 6, k_i), the design's columns side by side, without joining them.

        ``by="pairs"``: the blocks are contiguous stretches holding equal shares of the
        whitener's valid pairs (``block_edges``); ``by="time"`` or without a valid mask, of
        equal lengths (``build``'s cut).

        ``low`` (M - order, 6, q), the record's slowest components (``low_band``): the
        projections of the whitened X and z on them are kept too (``low_X`` (6, q, k),
        ``low_z`` (6, q); ``low_rows``, the number of components), for ``band_tests``."""
        if by not in ("pairs", "time"):
            raise ValueError(f"by must be 'pairs' or 'time', not {by!r}")
        p = whitener.order
        parts = list(X) if isinstance(X, (list, tuple)) else [X]
        m, legs = parts[0].shape[:2]
        k = sum(a.shape[2] for a in parts)
        rows_w = m - p
        valid = None if whitener.valid is None or by == "time" else whitener.valid[p:]
        edges = block_edges(valid, rows_w, n_blocks)
        XtX = np.empty((n_blocks, k, k))
        Xtz = np.empty((n_blocks, k))
        ztz = np.empty(n_blocks)
        rows = np.empty(n_blocks)
        low_X = None if low is None else np.zeros((legs, low.shape[2], k))
        low_z = None if low is None else np.zeros((legs, low.shape[2]))
        for b in range(n_blocks):
            start, stop = edges[b], edges[b + 1]
            v = None if whitener.valid is None else whitener.valid[start:stop + p]
            Xw = np.concatenate([whitener.apply(a[start:stop + p], v) for a in parts],
                                axis=2) if len(parts) > 1 else \
                whitener.apply(parts[0][start:stop + p], v)
            zw = whitener.apply(z[start:stop + p], v)
            Xb, zb = Xw.reshape(-1, k), zw.reshape(-1)
            XtX[b] = Xb.T @ Xb
            Xtz[b] = Xb.T @ zb
            ztz[b] = zb @ zb
            # rows zeroed by a gap carry no observation
            rows[b] = zb.size if v is None else np.count_nonzero(zb)
            if low is not None:
                # per leg, the components' products with the columns (BLAS, leg by leg)
                legs_low = low[start:stop].transpose(1, 2, 0)
                low_X += legs_low @ Xw.transpose(1, 0, 2)
                low_z += (legs_low @ zw.T[:, :, None])[:, :, 0]
        low_rows = 0.0 if low is None else float(np.count_nonzero(np.any(low != 0, axis=0)))
        return cls(XtX, Xtz, ztz, rows, ridge, low_X, low_z, low_rows)

    def total(self, weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, float,
                                                               float]:
        """Summed (XtX, Xtz, ztz, rows), blocks weighted by ``weights`` (counts) if given.
        The unweighted sums are summed once and shared (read-only arrays)."""
        if weights is None:
            if "total" not in self._sums:
                XtX, Xtz = self.XtX.sum(0), self.Xtz.sum(0)
                XtX.flags.writeable = Xtz.flags.writeable = False
                self._sums["total"] = (XtX, Xtz, float(self.ztz.sum()), float(self.rows.sum()))
            return self._sums["total"]
        w = np.asarray(weights, float)
        return (np.tensordot(w, self.XtX, 1), w @ self.Xtz, float(w @ self.ztz),
                float(w @ self.rows))

    def without(self, held: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Summed (XtX, Xtz, ztz) of the blocks not in ``held`` (indices): a fold's training
        blocks. Summed, not the total less the held-out blocks: a column that is zero on
        every training block (an effect only the held-out stretch reaches) is then exactly
        zero, not a rounding residue that a solve would scale into a huge coefficient."""
        keep = np.ones(len(self.ztz), bool)
        keep[held] = False
        return (self.XtX[keep].sum(0), self.Xtz[keep].sum(0), float(self.ztz[keep].sum()))

    def folds(self, n_folds: int) -> list[np.ndarray]:
        """The block indices of each fold of a cross-validation: ``n_folds`` contiguous
        groups of blocks, as equal as they divide."""
        return np.array_split(np.arange(len(self.ztz)), n_folds)

    def fold_sums(self, n_folds: int) -> FoldSums:
        """The held-out and the training cross-products of every fold of ``folds``, summed
        once per fold count (``held``, ``without``) and stacked for the solves of a
        cross-validation."""
        if n_folds not in self._sums:
            groups = self.folds(n_folds)
            held = [self.held(g) for g in groups]
            train = [self.without(g) for g in groups]
            arrays = (np.stack([h[0] for h in held]), np.stack([h[1] for h in held]),
                      np.array([h[2] for h in held]), np.stack([t[0] for t in train]),
                      np.stack([t[1] for t in train]), np.array([t[2] for t in train]))
            for a in arrays:
                a.flags.writeable = False       # shared by every cross-validation
            self._sums[n_folds] = FoldSums(*arrays)
        return self._sums[n_folds]

    def held(self, fold) -> tuple[np.ndarray, np.ndarray, float]:
        """Summed (XtX, Xtz, ztz) of the blocks ``fold`` (indices or a slice): a fold's
        held-out data."""
        return (self.XtX[fold].sum(0), self.Xtz[fold].sum(0), float(self.ztz[fold].sum()))


def block_edges(valid: np.ndarray | None, rows: int, n_blocks: int) -> np.ndarray:
    """Edges (n_blocks + 1,) of contiguous blocks over ``rows`` samples, each holding an equal
    share of the valid pairs ``valid`` (rows, 6); equal lengths without it (``build``'s cut).

    A block is the unit of the cross-validation and of the bootstrap: it should hold a share of
    the observations, not a share of the clock. Cut by time, a record of a few moves between
    long rests leaves most folds without a sliding pair, so a structure of the moves is
    predicted from one other move or from none (14 s of rest, then two moves: a sensor bias of
    2.9 times the noise was not named, ``no_discrepancy`` with 4.1 times the noise left).
    Cut by the pairs, the folds of such a record fall within the moves, each still one
    contiguous stretch; on a record that slides throughout, the cut is the same as by time.
    Every block keeps at least one sample.

    The tests of the generic out-of-model basis (``lackfit.test`` and the competitor of each
    round's winner) cut by time instead: with free coefficients on F, F^3, sgn(v) and a drift,
    that basis follows slow noise along one smooth move, and a fold held out within a move was
    predicted by its neighbours (two pink-noise records without any effect, one move of
    4.5 s each, were reported as unexplained). Cut by time, a structure must hold in another
    stretch of the record."""
    equal = np.r_[np.arange(n_blocks) * (rows // n_blocks), rows]
    if valid is None:
        return equal
    count = np.cumsum(np.count_nonzero(valid, axis=1))
    if count[-1] < n_blocks:
        return equal
    edges = np.r_[0, np.searchsorted(count, count[-1] * np.arange(1, n_blocks) / n_blocks) + 1,
                  rows]
    for b in range(1, n_blocks):
        edges[b] = min(max(edges[b], edges[b - 1] + 1), rows - (n_blocks - b))
    return edges


# -- bounded least squares on cross-products ---------------------------------------------------


def solve(A: np.ndarray, b: np.ndarray, lower: np.ndarray | None = None,
          upper: np.ndarray | None = None, *, ridge: float) -> np.ndarray:
    """argmin ``t' A t - 2 b' t`` within bounds (A symmetric positive semi-definite).

    Columns are scaled to unit diagonal and ``ridge`` (``Settings.ridge``), added to the
    scaled diagonal, keeps confounded columns solvable.
    Within the bounds when the unconstrained solution is not: ``_bounded``.
    """
    return solve_stacked(A[None], b[None], lower, upper, ridge=ridge)[0]


def solve_stacked(A: np.ndarray, b: np.ndarray, lower: np.ndarray | None = None,
                  upper: np.ndarray | None = None, *, ridge: float) -> np.ndarray:
    """``solve`` for F problems at once (the folds of a cross-validation): A (F, k, k),
    b (F, k), the bounds (k,) shared; returns (F, k). Each problem's result is the one it
    has alone: the unconstrained solves are LAPACK's, one matrix at a time, in one call."""
    n, k = b.shape
    if k == 0:
        return np.zeros((n, 0))
    diagonal = np.diagonal(A, axis1=1, axis2=2)
    d = np.sqrt(np.maximum(diagonal, 1e-300))
    As = A / (d[:, :, None] * d[:, None, :])
    steps = np.arange(k)
    As[:, steps, steps] += ridge
    # a column without data (zero diagonal) carries no information: its coefficient is 0
    bs = np.where(diagonal > 0, b, 0.0) / d
    t = np.linalg.solve(As, bs[:, :, None])[:, :, 0]
    if lower is None and upper is None:
        return t / d
    lo = np.full((n, k), -np.inf) if lower is None else np.asarray(lower, float) * d
    hi = np.full((n, k), np.inf) if upper is None else np.asarray(upper, float) * d
    for f in np.flatnonzero(~((t >= lo) & (t <= hi)).all(axis=1)):
        t[f] = _bounded(As[f], bs[f], lo[f], hi[f], t[f])
    return t / d


def _bounded(A: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray,
             unbounded: np.ndarray) -> np.ndarray:
    """Box-constrained convex QP ``min t'At - 2b't``, ``lo <= t <= hi`` (A positive definite),
    from the ``unbounded`` minimiser.

    The coefficients held on a bound are those of the bounded least squares
    ``min |L't - L^-1 b|^2``, ``A = L L'``, by BVLS (``scipy.optimize.lsq_linear``; a
    coefficient whose bounds are equal is held there, a pinned parameter); the others are
    solved from their normal equations, as an unbounded fit solves them: a column held at zero
    then leaves the others' fit exactly as it is without that column, and the F-tests and
    cross-validations that compare the two fits find no difference, not a rounding one.

    Most often the coefficients held are those the unbounded minimiser puts beyond a bound:
    when that choice meets the optimality conditions of the QP (the others within their bounds,
    the held ones pushed outward by the gradient), it is the optimum's, and BVLS is not run.
    """
    pinned = lo >= hi
    guess = pinned | (unbounded < lo) | (unbounded > hi)
    t = _held_solution(A, b, lo, hi, guess, np.where(unbounded > hi, hi, lo))
    if _optimal(A, b, lo, hi, guess, t):
        return t
    held = pinned.copy()
    t = np.where(held, lo, 0.0)
    if not held.all():
        free, kept = np.flatnonzero(~held), np.flatnonzero(held)
        L = np.linalg.cholesky(A[free[:, None], free])
        c = np.linalg.solve(L, b[free] - A[free[:, None], kept] @ t[kept])
        side = optional("scipy.optimize").lsq_linear(L.T, c, (lo[free], hi[free]),
                                                     method="bvls").active_mask
        t[free] = np.select([side < 0, side > 0], [lo[free], hi[free]], 0.0)
        held[free] = side != 0
    return _held_solution(A, b, lo, hi, held, t)


def _held_solution(A: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                   held: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The coefficients ``held`` at their values in ``at``, the others from their normal
    equations (clipped to their bounds)."""
    t = np.where(held, at, 0.0)
    free = np.flatnonzero(~held)
    if free.size:
        kept = np.flatnonzero(held)
        rhs = b[free] - A[free[:, None], kept] @ t[kept]
        t[free] = np.clip(np.linalg.solve(A[free[:, None], free], rhs), lo[free], hi[free])
    return t


def _optimal(A: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray,
             held: np.ndarray, t: np.ndarray) -> bool:
    """Whether t, with the coefficients ``held`` on a bound, meets the Karush-Kuhn-Tucker
    conditions of ``min t'At - 2b't`` within the bounds: each free coefficient strictly inside
    its bounds, and the gradient ``At - b`` of each held one pointing out of the box (>= 0 at
    a lower bound, <= 0 at an upper one; either at a pinned one)."""
    free = ~held
    if (t[free] <= lo[free]).any() or (t[free] >= hi[free]).any():
        return False
    gradient = A[held] @ t - b[held]
    pinned = (lo >= hi)[held]
    at_lower = t[held] == lo[held]
    return bool((pinned | np.where(at_lower, gradient >= 0, gradient <= 0)).all())


def sse(A: np.ndarray, b: np.ndarray, c: float, t: np.ndarray) -> float:
    """Residual sum of squares ``c - 2 b't + t'A t`` of coefficients t."""
    return float(c - 2 * b @ t + t @ A @ t)


@dataclass
class Fit:
    """A linearised least-squares fit on a subset of the design's columns.

    Attributes
    ----------
    columns : list[int]
        Indices of the design columns used.
    coef : ndarray, shape (k,)
        Parameter steps from the linearisation point.
    sse : float
        Residual sum of squares of the prewhitened data.
    rows : float
        Number of scalar observations.
    """

    columns: list[int]
    coef: np.ndarray
    sse: float
    rows: float


def fit(blocks: Blocks, columns: Sequence[int], lower: np.ndarray, upper: np.ndarray,
        weights: np.ndarray | None = None) -> Fit:
    """Bounded fit of the named columns on (weighted) blocks; bounds are per design column."""
    A, b, c, rows = blocks.total(weights)
    cols = list(columns)
    idx = np.ix_(cols, cols)
    t = solve(A[idx], b[cols], lower[cols], upper[cols], ridge=blocks.ridge)
    return Fit(cols, t, sse(A[idx], b[cols], c, t), rows)


def f_test(null: Fit, alternative: Fit, k: int | None = None) -> tuple[float, float, int]:
    """Nested F-test on prewhitened data: (F, p-value, numerator degrees of freedom).

    ``k``, the number of parameters tested, defaults to the difference in columns.
    """
    if k is None:
        k = len(alternative.columns) - len(null.columns)
    dof = alternative.rows - len(null.columns) - k
    if k <= 0 or alternative.sse <= 0 or dof <= 0:
        return 0.0, 1.0, max(k, 0)
    F = max(null.sse - alternative.sse, 0.0) / k / (alternative.sse / dof)
    return float(F), f_sf(F, k, dof), k


def cross_validate(blocks: Blocks, columns: Sequence[int], lower: np.ndarray,
                   upper: np.ndarray, n_folds: int,
                   variants: Sequence[Sequence[int]] = ((),)) -> np.ndarray:
    """Held-out prewhitened SSE of each fold (contiguous groups of blocks), shape (n_folds,),
    of the fit of ``columns`` on the fold's training blocks. With ``variants`` (column lists
    added to ``columns``, e.g. a candidate's delays), each fold's error is that of the variant
    that fits its training blocks best: the choice is part of what is validated."""
    folds = blocks.fold_sums(n_folds)
    out = np.empty(len(folds.train_c))
    best = np.empty(len(folds.train_c))
    for first, variant in enumerate(variants):
        cols = list(columns) + list(variant)
        idx = np.ix_(cols, cols)
        A = folds.train_A[:, cols][:, :, cols]
        b = folds.train_b[:, cols]
        t = solve_stacked(A, b, lower[cols], upper[cols], ridge=blocks.ridge)
        for f in range(len(out)):
            train = sse(A[f], b[f], folds.train_c[f], t[f])
            if first == 0 or train < best[f]:
                best[f] = train
                out[f] = sse(folds.held_A[f][idx], folds.held_b[f][cols], folds.held_c[f],
                             t[f])
    return out


def fold_share(blocks: Blocks, cv: np.ndarray, cv_null: np.ndarray, n_folds: int) -> float:
    """Share of the folds whose held-out error ``cv`` is below the null's ``cv_null`` (both
    (n_folds,), from ``cross_validate``), among the folds that hold observations: a fold
    without any (a stretch of the record where no pair is used, a long rest) can neither
    confirm nor refute a candidate."""
    held = np.array([blocks.rows[g].sum() > 0 for g in blocks.folds(n_folds)])
    if not held.any():
        return 0.0
    return float(np.mean((np.asarray(cv) < np.asarray(cv_null))[held]))


def low_band(t: np.ndarray, kept: np.ndarray, q: int) -> np.ndarray:
    """The record's slowest components, per leg: the cosines ``cos(pi j tau)``, j = 0..q-1,
    of the time scaled to tau in [0, 1] (the mean and periods down to 2 T / (q - 1)),
    orthonormal over each leg's kept samples and zero on the others; shape (M, 6, q).

    t : ndarray (M,), s, the time of the filtered samples; kept : ndarray (M, 6) of bool,
    the samples the filter keeps (``Whitener.kept``); q : int, the number of components
    (``Settings.low_band``). A cosine that the kept samples cannot
    tell from the slower ones (a record that moves only in short stretches) is left out
    (zero)."""
    t = np.asarray(t, float)
    tau = (t - t[0]) / max(t[-1] - t[0], 1e-300)
    C = np.cos(np.pi * np.arange(q)[None, :] * tau[:, None])
    out = np.zeros(kept.shape + (q,))
    for leg in range(kept.shape[1]):
        rows = np.flatnonzero(kept[:, leg])
        if len(rows) <= q:
            continue
        Q, R = np.linalg.qr(C[rows])
        independent = np.abs(np.diag(R)) > 1e-6 * np.sqrt(len(rows))
        out[rows, leg, :] = Q * independent
    return out


def band_tests(blocks: Blocks, null: Fit, alternative: Fit, k: int) -> tuple[float, float]:
    """p-values of the nested F-test of ``alternative`` against ``null`` (fits on ``blocks``,
    ``k`` parameters tested) on the record's slowest components alone and on the rest alone
    (``Blocks.whitened`` with ``low``): each band's noise level measured in that band.

    The AR noise model describes the noise where its few lags see it; noise whose spectrum
    keeps rising towards the lowest frequencies (1/f noise, a slow thermal wander of the
    load cells) has more power at the record's slowest components than the model gives it.
    An effect whose evidence lives there (a constant offset of each channel, a force
    proportional to a slowly changing load) is then tested against too little noise. On the
    slowest components alone, the noise is measured where the evidence is: the test is the
    low-frequency t-test of econometrics (the long-run variance from the lowest cosine
    projections), and the rest is tested with the slowest components left out.

    Both models are fitted once, on all the data (the fits given); each band's sums of
    squares are then those of the same coefficients, and its residual degrees of freedom its observations
    less the alternative's parameters spent on it (the trace of the hat matrix over the
    band). Fitted on the slowest components alone, the refitted parameters and the effects
    already named (a dozen columns and more, mostly determined by the rest) would use up
    their 6 q observations (``low_band``)."""
    A, b, c, rows = blocks.total()
    PX, pz = blocks.low_X, blocks.low_z
    AL = np.einsum("lqk,lqm->km", PX, PX)
    bL = np.einsum("lqk,lq->k", PX, pz)
    cL = float(np.sum(pz ** 2))
    fits = []
    for f in (null, alternative):
        idx = np.ix_(f.columns, f.columns)
        low = sse(AL[idx], bL[f.columns], cL, f.coef)
        fits.append((low, sse(A[idx], b[f.columns], c, f.coef) - low))
    cols = list(alternative.columns)
    idx = np.ix_(cols, cols)
    d = np.sqrt(np.maximum(np.diag(A[idx]), 1e-300))
    scaled = A[idx] / np.outer(d, d) + blocks.ridge * np.eye(len(cols))
    spent = float(np.trace(np.linalg.solve(scaled, AL[idx] / np.outer(d, d)))) if cols else 0.0
    out = []
    for band, (n, used) in enumerate(((blocks.low_rows, spent),
                                      (rows - blocks.low_rows, len(cols) - spent))):
        dof = n - used
        left = fits[1][band]
        if dof <= 0 or left <= 0:
            out.append(1.0)
            continue
        F = max(fits[0][band] - left, 0.0) / k / (left / dof)
        out.append(f_sf(F, k, dof))
    return out[0], out[1]


def band_p_value(blocks: Blocks, null: Fit, alternative: Fit, k: int) -> float:
    """The smaller p-value of ``band_tests``, times two (Bonferroni over the two parts): the
    alternative passes on the slowest components alone or on the rest alone."""
    return min(1.0, 2 * min(band_tests(blocks, null, alternative, k)))


def rms(a: np.ndarray) -> float:
    """Root mean square of every element of ``a``, in ``a``'s unit."""
    return float(np.sqrt(np.mean(a ** 2)))


def bootstrap_weights(rng: np.random.Generator, n_blocks: int, n_draws: int) -> np.ndarray:
    """Counts (n_draws, n_blocks) of blocks drawn with replacement (block bootstrap)."""
    draws = rng.integers(0, n_blocks, size=(n_draws, n_blocks))
    counts = np.zeros((n_draws, n_blocks))
    np.add.at(counts, (np.arange(n_draws)[:, None], draws), 1.0)
    return counts
