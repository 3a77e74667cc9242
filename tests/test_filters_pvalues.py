"""The discovery's filters and p-values against SciPy's own (scipy.signal, scipy.stats).

The comparisons allow a relative 1e-12: the same quantities computed in another order differ by
a few units in the last place, amplified at most by the recursion's or the distribution's
condition (about 1e3 here); a wrong coefficient, lag or degree of freedom is off by far more."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal, stats

from gsfric.discovery import pvalues
from gsfric.signal import filters
from gsfric.signal.filters import all_pole, fir, fir_channels


@pytest.mark.parametrize("seed", range(4))
def test_all_pole_after_fir_is_lfilter(seed):
    rng = np.random.default_rng(seed)
    poles = np.r_[0.97 * np.exp(1j * rng.uniform(0.05, 3, 2)), rng.uniform(-0.9, 0.9, 2)]
    den = np.real(np.poly(np.r_[poles, np.conj(poles[:2])]))
    b = rng.normal(size=5)
    x = rng.normal(size=(20_000, 2))
    expected = signal.lfilter(b, den, x, axis=0)
    taps = fir(b, np.concatenate([np.zeros((4, 2)), x]), start=4)
    got = all_pole(den, taps)
    assert np.max(np.abs(got - expected)) <= 1e-12 * np.max(np.abs(expected))
    assert np.array_equal(all_pole(np.array([2.0]), x), x / 2)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("stretch", [None, 7])
def test_fir_channels_is_each_channels_fir_to_the_bit(seed, stretch, monkeypatch):
    # the whitener's filter of every leg at once: the same sums in the same order as fir
    # (lfilter), zeros where a channel's order is shorter, and exact zeros kept; the same
    # when it is computed a few samples at a time (FIR_BYTES, a stretch of 7 samples here)
    if stretch:
        monkeypatch.setattr(filters, "FIR_BYTES", stretch * 6 * 3 * 8)
    rng = np.random.default_rng(seed)
    orders = rng.integers(0, 12, size=6)
    p = int(orders.max())
    x = rng.normal(size=(300, 6, 3)) * 10.0 ** rng.integers(-6, 6)
    x[rng.random(x.shape) < 0.2] = 0.0
    b = np.zeros((p + 1, 6))
    b[0] = 1.0
    expected = np.empty((300 - p, 6, 3))
    for i, q in enumerate(orders):
        b[1:q + 1, i] = rng.normal(scale=0.3, size=q)
        expected[:, i] = fir(b[:q + 1, i], x[:, i], start=p)
    got = fir_channels(b, x)
    assert np.array_equal(got, expected)
    assert np.array_equal(np.signbit(got), np.signbit(expected))
    assert np.array_equal(fir_channels(np.ones((1, 6)), x), x)


def test_all_pole_singular():
    with pytest.raises(ValueError, match="singular"):
        all_pole(np.array([0.0, 1.0]), np.ones(4))


@given(seed=st.integers(0, 2**32 - 1), k=st.integers(2, 6))
@settings(max_examples=40, deadline=None)
def test_p_values_agree_with_scipy_stats(seed, k):
    rng = np.random.default_rng(seed)
    values = rng.normal(rng.normal(), rng.uniform(0.1, 3), size=rng.integers(3, 30))
    assert pvalues.t_greater(values) == pytest.approx(
        stats.ttest_1samp(values, 0.0, alternative="greater").pvalue, rel=1e-12)
    f, dfn, dfd = rng.uniform(0, 5), int(rng.integers(1, 20)), int(rng.integers(5, 5000))
    assert pvalues.f_sf(f, dfn, dfd) == pytest.approx(stats.f.sf(f, dfn, dfd), rel=1e-12)
    assert pvalues.chi2_sf(f * k, k) == pytest.approx(stats.chi2.sf(f * k, k), rel=1e-12)


def test_without_spread_is_nan():
    assert np.isnan(pvalues.alexander_govern([np.ones(4), np.array([1.0, 2.0, 3.0])]))
    assert np.isnan(pvalues.t_greater(np.array([1.0])))
