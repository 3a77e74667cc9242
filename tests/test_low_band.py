"""The record's slowest components tested on their own noise (``statistics.band_tests``)."""

import numpy as np
import pytest
from helpers import pink_noise as pink

from gsfric.discovery import statistics as st
from gsfric.discovery.settings import Settings

DEFAULTS = Settings()


def offset_tests(residual, rate=1000.0, valid=None):
    """The F-test of a per-leg offset (six columns) against nothing, and the band tests."""
    n = len(residual)
    X = np.zeros((n, 6, 6))
    X[:, np.arange(6), np.arange(6)] = 1.0
    w = st.Whitener.fit(residual, DEFAULTS.max_order, valid=valid)
    low = w.low_band(np.arange(n) / rate, valid, q=DEFAULTS.low_band)
    blocks = st.Blocks.whitened(w, X, residual, 40, ridge=DEFAULTS.ridge, low=low)
    lo, hi = np.full(6, -np.inf), np.full(6, np.inf)
    none, offsets = st.fit(blocks, [], lo, hi), st.fit(blocks, list(range(6)), lo, hi)
    return st.f_test(none, offsets)[1], st.band_tests(blocks, none, offsets, 6)


def test_the_mean_of_1_over_f_noise_between_rests_is_not_an_offset():
    """1/f noise seen only during three moves of 0.4 s between rests (8000 samples at 2 kHz):
    the AR model (12 lags at most) gives the slow wander too little power, and the plain
    F-test takes the mean of the moves for an offset of every channel in most records.
    Measured against the slowest components' own noise, it rarely does."""
    rng = np.random.default_rng(3)
    n, rate = 8000, 2000.0
    t = np.arange(n) / rate
    plain, bands = 0, 0
    for _ in range(20):
        moving = np.zeros((n, 6), bool)
        for start in rng.uniform(0.0, 3.6, 3):
            moving[(t > start) & (t < start + 0.4)] = True
        p, (p_low, p_high) = offset_tests(pink(rng, n), rate, moving)
        plain += p < 1e-3
        bands += min(1.0, 2 * min(p_low, p_high)) < 1e-3
    assert plain >= 8, plain
    assert bands <= 1, bands


def test_a_real_offset_stands_out_of_white_and_of_1_over_f_noise():
    """An offset of 0.2 times the noise's standard deviation on white noise, of 2 times on
    1/f noise (whose record mean wanders by a good part of its standard deviation), 4000
    samples: the slowest components alone find it, and nothing is left for the rest."""
    rng = np.random.default_rng(5)
    sign = rng.choice([-1.0, 1.0], 6)
    for noise, size in ((rng.standard_normal((4000, 6)), 0.2), (pink(rng, 4000), 2.0)):
        p, (p_low, p_high) = offset_tests(noise + size * sign)
        assert p_low < 1e-6, p_low
        assert p_high > 1e-3, p_high


def test_slowest_components_are_orthonormal_on_the_kept_samples_of_each_leg():
    """With gaps (moves between rests), each leg's components are orthonormal over its kept
    samples and zero elsewhere, and ``Whitener.kept`` is where ``apply`` keeps samples."""
    rng = np.random.default_rng(1)
    n = 3000
    t = np.sort(rng.uniform(0, 6.0, n))
    valid = np.abs(np.sin(2 * np.pi * 0.4 * t[:, None] + rng.uniform(0, 6, 6))) > 0.7
    w = st.Whitener.fit(rng.standard_normal((n, 6)) + 0.5 * np.sin(40 * t)[:, None],
                        DEFAULTS.max_order, valid=valid)
    kept = w.kept(valid)
    assert np.array_equal(kept, w.apply(np.ones((n, 6)) + rng.uniform(1, 2, (n, 6)), valid) != 0)
    low = st.low_band(t[w.order:], kept, DEFAULTS.low_band)
    for leg in range(6):
        Q = low[:, leg, :]
        assert np.allclose(Q[~kept[:, leg]], 0.0)
        assert np.allclose(Q.T @ Q, np.eye(Q.shape[1]), atol=1e-10)


def test_an_offset_beside_many_fitted_columns_keeps_its_slowest_components():
    """An offset tested beside twelve other fitted columns (per-leg gains on a fast force
    and fast common signals, as the refit and the effects already named are): on the
    slowest components alone (6 x 3 of them) a refit of all 18 columns would leave no
    degrees of freedom. Fitted once on all the data, the other columns spend little of
    them, and the offset is still found; without it, the test finds nothing."""
    rng = np.random.default_rng(11)
    n, rate = 4000, 1000.0
    t = np.arange(n) / rate
    X = np.zeros((n, 6, 18))
    force = np.sin(2 * np.pi * 7.0 * t)[:, None] * rng.uniform(0.5, 2.0, 6)
    X[:, np.arange(6), np.arange(6)] = force
    for j in range(6):
        X[:, :, 6 + j] = np.sin(2 * np.pi * rng.uniform(3, 30) * t + rng.uniform(0, 6))[:, None]
    X[:, np.arange(6), 12 + np.arange(6)] = 1.0
    coef = np.r_[rng.uniform(0.5, 1, 12), 0.3 * rng.choice([-1.0, 1.0], 6)]
    noise = rng.standard_normal((n, 6))
    w = st.Whitener.fit(noise, DEFAULTS.max_order)
    low = w.low_band(t, q=DEFAULTS.low_band)
    lo, hi = np.full(18, -np.inf), np.full(18, np.inf)
    null, alternative = list(range(12)), list(range(18))
    for size, found in ((1.0, True), (0.0, False)):
        coef_ = coef.copy()
        coef_[12:] *= size
        blocks = st.Blocks.whitened(w, X, noise + X @ coef_, 40, ridge=DEFAULTS.ridge, low=low)
        p_low, p_high = st.band_tests(blocks, st.fit(blocks, null, lo, hi),
                                      st.fit(blocks, alternative, lo, hi), 6)
        assert (p_low < 1e-6) == found, (size, p_low)
        assert p_high > 1e-3, (size, p_high)


@pytest.mark.slow
def test_1_over_f_noise_on_moves_between_rests_is_no_discrepancy():
    """``discover`` on moves of 0.7 s between rests of 3 s at 1 kHz, with 1/f force noise and
    no missing effect: the slow wander of the moves' mean is not named as a sensor bias (nor
    as a gain error or a payload offset), and the refit that follows it is not a gap closed."""
    from test_discovery_folds import discover_log, moves_with_long_rests

    from gsfric.models import reference_platform
    from gsfric.synth import synthesize

    platform = reference_platform(friction_model="paper")
    for seed in (2, 5):
        data = synthesize(platform, [], motion=moves_with_long_rests(rate=1000.0, seed=seed),
                          noise=0.0, pose_noise=1e-6, seed=seed)
        columns = [f"F{i}" for i in range(1, 7)]
        data.frame[columns] += 0.2 * pink(np.random.default_rng(seed), len(data.frame))
        r = discover_log(data, platform)
        assert r.names == [], (seed, r.names)
        assert r.verdict == "no_discrepancy", (seed, r.verdict)
