"""The Savitzky-Golay filter of every sample: windows and orders chosen per sample for the least
estimated error of a derivative, and the filtering with those choices."""

from __future__ import annotations

import math

import numpy as np

from gsfric._optional import optional
from gsfric._threads import in_parallel
from gsfric.signal.noise import white_noise_std
from gsfric.signal.savgol import (
    DEFAULT_POLYORDER,
    fill_ends,
    savgol_filter,
    savgol_gains,
    savgol_weights,
)

MAX_AUTO_WINDOW = 1601
"""Longest Savitzky-Golay window the automatic choice considers, samples: 0.8 s at 2 kHz, where
pose noise of 10-30 um still wants windows of more than 201 samples (on a 2 kHz multisine,
30 um: the force error of the motion estimate is 2.0 N with 201 samples at most, 0.44 N with
801 or 1601)."""


def candidate_windows(n: int, polyorder: int) -> list[int]:
    smallest = polyorder + 2 if polyorder % 2 else polyorder + 3
    largest = min(n, MAX_AUTO_WINDOW)
    windows = []
    w = smallest
    while w <= largest:
        windows.append(w)
        w = max(w + 2, int(w * 1.25) | 1)
    return windows


GCV_ROUNDING = 10.0
"""Safety factor on the rounding of the FFTs in ``gcv_window``: a transform of length L is
taken to be within ``GCV_ROUNDING * u * log2(L)`` of the exact one, relative to its norm (u the
unit roundoff; the known bound's constant is below 5)."""

GCV_DIRECT_BELOW = 40
"""Windows up to this length are filtered directly when ``gcv_window`` needs their score
closer than the spectrum gives it (cheaper than a transform of the record)."""


def gcv_window(y: np.ndarray, polyorder: int) -> int:
    """The Savitzky-Golay window minimizing the generalized cross-validation score.

    ``GCV(w) = RSS(w) / (1 - h(w))^2`` with RSS the squared residual of the smoothed signal
    (``savgol_filter``) and h the filter's central weight (the hat matrix's diagonal).

    Computed in steps that each bound their rounding, so that the window is the one filtering
    with every candidate gives (the first of equal scores), at a fraction of the cost: every
    score from the signal's spectrum (Parseval's theorem), then, for the candidates whose
    scores could still be the least, the residual from one transform of the record, and at
    last their direct filtering. On noisy poses one candidate is filtered; on noise-free ones
    the short windows, whose residuals are all rounding.
    """
    y = np.asarray(y, float)
    windows = candidate_windows(len(y), polyorder)
    if not windows:
        raise ValueError(f"gcv_window: {len(y)} samples are fewer than the shortest window")
    record = _Record(y.reshape(len(y), -1), windows[-1])
    approx, error = zip(*(record.spectral(w, polyorder) for w in windows))
    lo, hi = np.subtract(approx, error), np.add(approx, error)
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        return _every_score(y, windows, polyorder)
    exact = np.zeros(len(windows), bool)
    transformed = np.zeros(len(windows), bool)
    while True:
        open_ = np.flatnonzero((lo <= hi.min()) & ~exact)
        if not len(open_):
            break
        for i in open_:
            w = windows[i]
            if w <= GCV_DIRECT_BELOW or transformed[i]:
                lo[i] = hi[i] = _gcv_score(y, w, polyorder)
                exact[i] = True
            else:
                a, e = record.transformed(w, polyorder)
                lo[i], hi[i] = max(lo[i], a - e), min(hi[i], a + e)
                transformed[i] = True
    left = np.flatnonzero(lo <= hi.min())
    if not (len(left) and np.isfinite(lo).all() and np.isfinite(hi).all()):
        return _every_score(y, windows, polyorder)
    return windows[left[int(np.argmin(lo[left]))]]


def _every_score(y: np.ndarray, windows: list[int], polyorder: int) -> int:
    """``gcv_window`` by its definition, filtering with every candidate: for squares beyond
    the float range (absurd poses), where the bounds of the fast path say nothing."""
    return windows[int(np.argmin([_gcv_score(y, w, polyorder) for w in windows]))]


def _gcv_score(y: np.ndarray, window: int, polyorder: int) -> float:
    """``gcv_window``'s score of one window, filtering directly."""
    smooth = savgol_filter(y, window, polyorder)
    centre = savgol_weights(window, polyorder)[window // 2]
    return np.sum((y - smooth) ** 2) / (1.0 - centre) ** 2


class _Record:
    """``gcv_window``'s signal y (N, k) in the frequency domain, and the approximate scores of
    windows with bounds on their distance from ``_gcv_score``'s.

    The residual inside (a whole window from each end) is y convolved with g, the identity
    less the smoothing weights reversed; g sums to zero, so the centred y gives the same one
    (to rounding, bounded). The first and last half windows are computed as ``savgol_filter``
    does (``_end_residual``)."""

    def __init__(self, y: np.ndarray, longest: int) -> None:
        self.fft = optional("scipy.fft")
        self.y, self.n = y, len(y)
        self.length = self.fft.next_fast_len(self.n + longest - 1, real=True)
        self.mean = y.mean(axis=0)
        self.centred = y - self.mean
        self.spectrum = self.fft.rfft(self.centred, self.length, axis=0)
        bins = np.full(len(self.spectrum), 2.0 / self.length)   # a bin and its mirror
        bins[0] = 1.0 / self.length
        if self.length % 2 == 0:
            bins[-1] = 1.0 / self.length
        self.power = bins * np.sum(self.spectrum.real ** 2 + self.spectrum.imag ** 2, axis=1)
        self.u = np.finfo(float).eps / 2
        self.fft_rounding = GCV_ROUNDING * self.u * np.log2(self.length)
        self.energy = np.sum(self.centred ** 2, axis=0)            # per column
        self.top, self.top_centred = np.abs(y).max(axis=0), np.abs(self.centred).max(axis=0)

    def _filter(self, window: int, polyorder: int) -> tuple[np.ndarray, np.ndarray, float]:
        h = savgol_weights(window, polyorder)
        g = -h[::-1]
        g[window // 2] += 1.0
        return h, g, (1.0 - h[window // 2]) ** 2

    def spectral(self, window: int, polyorder: int) -> tuple[float, float]:
        """The score from the energy of the whole convolution of the centred y with g
        (Parseval) less its partial overlaps at both ends (computed directly), and a bound."""
        h, g, scale = self._filter(window, polyorder)
        response = self.fft.rfft(g, self.length)
        terms = self.power * (response.real ** 2 + response.imag ** 2)
        total = float(np.sum(terms))
        partial, partial_error = _partial_overlaps(self.centred, g, self.top_centred)
        rss = max(total - partial, 0.0) + _end_residual(self.y, window, polyorder)
        l1 = np.sum(np.abs(g))
        # both transforms (each bin within the rounding times the l1 norm of g, the spectrum
        # normwise) and the pairwise sum over the bins
        spectral = 4 * self.fft_rounding * l1 * l1 * float(np.sum(self.energy)) \
            + self.u * np.log2(len(terms)) * total
        error = spectral + partial_error + self._inside(h, g, rss + spectral, 0.0)
        return rss / scale, error / scale

    def transformed(self, window: int, polyorder: int) -> tuple[float, float]:
        """The score from the residual inside as one inverse transform, and a bound."""
        h, g, scale = self._filter(window, polyorder)
        response = self.fft.rfft(g, self.length)
        inside = self.fft.irfft(self.spectrum * response[:, None], self.length,
                                axis=0)[window - 1:self.n]
        rss = float(np.sum(inside * inside)) + _end_residual(self.y, window, polyorder)
        per_sample = self.fft_rounding * np.sqrt(self.energy) * np.sqrt(np.sum(g * g))
        return rss / scale, self._inside(h, g, rss, per_sample) / scale

    def _inside(self, h: np.ndarray, g: np.ndarray, rss: float, per_sample) -> float:
        """A bound on the squared residual's error from per-sample errors inside, per column:
        ``per_sample`` (N,) or 0, the centring (g's sum times the mean; the subtraction's
        rounding through g) and the direct filtering's own rounding (w products and sums);
        and the sums' rounding."""
        u, w = self.u, len(g)
        offset = per_sample + np.abs(self.mean) * (abs(math.fsum(g)) + u) \
            + np.sum(np.abs(g)) * u * self.top_centred \
            + (2 * w * np.sum(np.abs(h)) + 1) * u * self.top
        e = float(np.sqrt(np.sum(offset ** 2)))
        return 2 * np.sqrt(self.n * max(rss, 0.0)) * e + self.n * e * e + 1e-12 * rss


def _partial_overlaps(centred: np.ndarray, g: np.ndarray, top: np.ndarray
                      ) -> tuple[float, float]:
    """The squared sum of the convolution of each column of ``centred`` (N, k) with g where
    they overlap partly (the first and last ``len(g) - 1`` values), and a bound on its
    rounding (``top`` (k,): the columns' largest magnitudes)."""
    m, n = len(g) - 1, len(centred)
    energy = 0.0
    for c in range(centred.shape[1]):
        head = np.convolve(centred[:m, c], g)[:m]
        tail = np.convolve(centred[n - m:, c], g)[m:]
        energy += float(head @ head + tail @ tail)
    size = len(g) * np.sum(np.abs(g)) * top
    u = np.finfo(float).eps / 2
    e = u * np.sqrt(np.sum(size ** 2))
    return energy, 2 * np.sqrt(2 * m * energy) * e + 2 * m * e * e + 2 * m * u * energy


def _end_residual(y: np.ndarray, window: int, polyorder: int) -> float:
    """The squared residual of ``savgol_filter`` in its first and last ``window // 2`` rows."""
    half, n = window // 2, len(y)
    ends = np.concatenate([y[:window], y[n - window:]])
    smooth = np.empty_like(ends)
    fill_ends(smooth, ends, window, polyorder)
    return float(np.sum((ends[:half] - smooth[:half]) ** 2)
                 + np.sum((ends[-half:] - smooth[-half:]) ** 2))


def _bias_degree(polyorder: int, deriv: int) -> int:
    """Lowest power of the time whose ``deriv``-th derivative a symmetric Savitzky-Golay filter
    of ``polyorder`` does not reproduce: the first power above ``polyorder`` of the parity of
    ``deriv`` (the filter is symmetric for even derivatives, antisymmetric for odd ones, so
    the powers of the other parity give the true value, zero)."""
    return polyorder + 1 if (polyorder + 1 - deriv) % 2 == 0 else polyorder + 2


BIAS_WEIGHT = 4.0


DETECTED_BIAS = 5.0
"""A filter's estimated bias at a sample counts as detected when it exceeds this many times
the filter's noise (standard deviation): on white noise alone the estimate stays below 1.2
times the noise (20,000 samples, every candidate filter)."""


def adaptive_filters(y: np.ndarray, polyorder: int = DEFAULT_POLYORDER,
                     sigma: np.ndarray | None = None, deriv: int = 2
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The Savitzky-Golay filter (polynomial order and window) of every sample for the
    ``deriv``-th derivative: the one minimizing a local estimate of that derivative's mean
    squared error (bias squared plus noise variance).

    Candidates: the orders ``polyorder`` and ``polyorder + 2``, each with the windows
    w_1 < w_2 < ... of ``candidate_windows`` (ratio about 1.25). For the estimate a_w of
    order p and window w (filter coefficients h_w):

    * its noise variance is ``sigma^2 ||h_w||^2`` (sigma the white pose noise,
      ``white_noise_std``);
    * its bias is, to leading order, ``c_w y^(m)`` with m = ``_bias_degree(p, deriv)`` (5 for
      the velocity, 6 for the acceleration with order 4) and ``c_w = sum_j h_w[j] j^m / m!``
      known exactly. So the next window's bias is ``g = c_{w'} / c_w`` (about 1.25^(m - deriv))
      times as large, and the difference ``a_w - a_{w'}`` has the mean ``(1 - g) bias_w`` and
      the exactly known noise variance ``sigma^2 ||h_w - h_{w'}||^2``. Its square averaged
      over the span of w', minus that variance, divided by ``(1 - g)^2``, estimates
      ``bias_w^2`` there without a pilot estimate of y^(m).
    * The bias grows with the window: once a window's estimated bias exceeds
      ``DETECTED_BIAS`` (5) times its noise (it is detected), no longer window of that order
      at that sample is credited with less. The
      estimate compares two windows, and where both span a whole feature of the motion (a
      triangle's period, a move with its rests) they are wrong alike and differ little: left
      to itself it would choose such a window (at 480 Hz, 583 samples across the corners of a
      0.6 Hz triangle wave, ten times the error of the 63 samples chosen with the rule).

    Each sample takes the filter of least estimated error summed over the columns (the mean
    squared error of the vector's derivative). The choice is local, so a motion whose
    frequency content changes along the record (a chirp, moves and rests) gets long windows
    where it is slow and short ones where it is fast; noise-free samples get the shortest.
    The higher order has a smaller bias for a given window and a larger noise: it wins on
    fast smooth motion. The velocity's variance falls more slowly with the window than the
    acceleration's (w^-3 against w^-5) while their biases grow alike, so the velocity's
    windows are the shorter.

    Parameters
    ----------
    y : ndarray, shape (N, k)
        Uniformly sampled signal.
    polyorder : int
        The lower of the two orders.
    sigma : ndarray, shape (k,), optional
        White-noise standard deviation of each column (default: ``white_noise_std``).
    deriv : int
        1 (velocity) or 2 (acceleration).

    Returns
    -------
    orders, windows : ndarray of int, shape (N,) each
        Odd windows, ``order < w <= min(N, MAX_AUTO_WINDOW)``.
    """

    y = np.asarray(y, float)
    n = len(y)
    if sigma is None:
        sigma = white_noise_std(y)
    scale = np.maximum(np.abs(y).max(axis=0), 1.0)
    variance = np.maximum(np.asarray(sigma, float), 1e-13 * scale) ** 2
    first = candidate_windows(n, polyorder)
    best = np.full(n, np.inf)
    orders = np.full(n, polyorder)
    windows = np.full(n, first[0])
    for p in (polyorder, polyorder + 2):
        _choose_windows(y, p, deriv, variance, best, orders, windows)
    return orders, windows


def _choose_windows(y: np.ndarray, p: int, deriv: int, variance: np.ndarray, best: np.ndarray,
                    orders: np.ndarray, windows: np.ndarray) -> None:
    """The windows of order ``p`` in ``adaptive_filters``: where one's estimated risk is below
    ``best`` (N,), it replaces ``best`` and the sample's ``orders`` and ``windows`` (in place)."""
    candidates = candidate_windows(len(y), p)
    if len(candidates) < 2:
        return
    m = _bias_degree(p, deriv)
    width = candidates[-1]

    def coefficients(w: int) -> np.ndarray:
        h = np.zeros(width)
        h[(width - w) // 2:(width + w) // 2] = savgol_weights(w, p, deriv)
        return h

    uniform_filter1d = optional("scipy.ndimage").uniform_filter1d
    j = (np.arange(width) - width // 2).astype(float)
    previous = savgol_filter(y, candidates[0], p, deriv)
    detected = np.zeros_like(y)
    # the least noise of any window after each one (a window's noise is variance * gain)
    gains = [float(np.sum(coefficients(w) ** 2)) for w in candidates[:-1]]
    least_after = [min(gains[i + 1:], default=np.inf) for i in range(len(gains))]
    for i, (w, w_next) in enumerate(zip(candidates[:-1], candidates[1:])):
        h, h_next = coefficients(w), coefficients(w_next)
        following = savgol_filter(y, w_next, p, deriv)
        growth = float(np.sum(h_next * j ** m) / np.sum(h * j ** m))
        spread = uniform_filter1d((previous - following) ** 2, size=w_next, axis=0,
                                  mode="nearest")
        bias2 = np.maximum(spread - variance * float(np.sum((h - h_next) ** 2)), 0.0) \
            / (1.0 - growth) ** 2
        noise2 = variance * float(np.sum(h ** 2))
        bias2 = np.maximum(bias2, detected)
        detected = np.where(bias2 > DETECTED_BIAS**2 * noise2, bias2, detected)
        risk = np.sum(BIAS_WEIGHT * bias2 + noise2, axis=1)
        better = risk < best
        best[better] = risk[better]
        orders[better] = p
        windows[better] = w
        previous = following
        if _settled(detected, variance * least_after[i], best):
            break


def _settled(detected: np.ndarray, least_noise: np.ndarray, best: np.ndarray) -> bool:
    """Whether no longer window can be chosen anywhere: a longer window's estimated bias
    squared is at least ``detected`` (N, k) and its noise variance at least ``least_noise``
    (k,), so its risk is at least their sum, computed as the risk is (the same rounding,
    which is monotonic); where that bound already reaches ``best`` (N,), it cannot be lower.
    """
    bound = np.sum(BIAS_WEIGHT * detected + least_noise, axis=1)
    return bool(np.all(bound >= best))


def motion_filters(y: np.ndarray, polyorder: int = DEFAULT_POLYORDER
                   ) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The filters ``Motion.from_samples`` uses at each sample of a uniformly sampled signal
    (N, k) when it chooses them (``adaptive_filters``): ((orders, windows) for the value and
    the first derivative, (orders, windows) for the second derivative), each array (N,)."""
    sigma = white_noise_std(y)
    first, second = in_parallel(lambda: adaptive_filters(y, polyorder, sigma, deriv=1),
                                lambda: adaptive_filters(y, polyorder, sigma, deriv=2))
    return first, second


def filter_pairs(orders: np.ndarray, windows: np.ndarray) -> np.ndarray:
    """The distinct (order, window) pairs of per-sample filters (N,) each, (P, 2), sorted by
    order then window (``np.unique(np.stack([orders, windows], axis=1), axis=0)``, by one
    integer key per sample)."""
    orders, windows = np.asarray(orders), np.asarray(windows)
    if len(orders) == 0:
        return np.empty((0, 2), dtype=np.result_type(orders, windows))
    base = int(windows.max()) + 1
    keys = np.unique(orders * base + windows)
    return np.stack([keys // base, keys % base], axis=1)


def savgol_adaptive(y: np.ndarray, filters, step: float) -> list[np.ndarray]:
    """``savgol_derivatives`` with each sample's own filters (``motion_filters``)."""
    out = [np.empty_like(y, dtype=float) for _ in range(3)]
    for derivatives, (orders, windows) in (((0, 1), filters[0]), ((2,), filters[1])):
        pairs = filter_pairs(orders, windows)
        for p, w in pairs:
            rows = (orders == p) & (windows == w)
            for k in derivatives:
                values = savgol_filter(y, int(w), int(p), k)
                out[k][rows] = values[rows] / step**k
    return out


def adaptive_gains(filters, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The noise gains (N,) of the first and second derivatives of ``savgol_adaptive`` with
    the per-sample ``filters`` (``motion_filters``), per unit sample step (``savgol_gains``)."""
    out = []
    for deriv, (orders, windows) in ((1, filters[0]), (2, filters[1])):
        gains = np.empty(n)
        for p, w in filter_pairs(orders, windows):
            rows = (orders == p) & (windows == w)
            gains[rows] = savgol_gains(n, int(w), int(p), deriv)[rows]
        out.append(gains)
    return out[0], out[1]
