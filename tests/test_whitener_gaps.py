"""The AR noise model of a residual with gaps (only the sliding pairs count)."""

import numpy as np
from scipy.signal import butter, lfilter

from gsfric.discovery import statistics as st
from gsfric.discovery.settings import Settings

MAX_ORDER = Settings().max_order


def test_band_passed_noise_with_gaps_gets_a_stationary_model():
    """White noise band-passed to a few hertz at 513 Hz, seen only where |sin| of a 0.3 Hz motion
    passes a threshold (the sliding pairs): the autocovariances over each lag's own pairs need
    not be positive definite, and the Levinson recursion then reaches a reflection coefficient
    of magnitude one or more. Every fitted model is still an AR model: a positive innovation
    variance, no larger than the residual's, and its roots inside the unit circle."""
    rate, n = 513.0, 5000
    t = np.arange(n) / rate
    for seed in range(6):
        rng = np.random.default_rng(seed)
        low = rng.uniform(2.0, 40.0)
        b, a = butter(4, [low, low + rng.uniform(2.0, 8.0)], btype="band", fs=rate)
        x = lfilter(b, a, rng.normal(0.0, 1.0, (n + 500, 6)), axis=0)[500:]
        valid = np.abs(np.sin(2 * np.pi * 0.3 * t[:, None] + rng.uniform(0, 6, 6))) \
            > rng.uniform(0.2, 0.9)
        w = st.Whitener.fit(x, MAX_ORDER, valid=valid)
        assert np.all(w.innovation_std > 1e-4 * w.marginal_std), (seed, w.innovation_std)
        assert np.all(w.innovation_std <= w.marginal_std * (1 + 1e-12)), seed
        for phi in w.coefficients:
            if len(phi):
                assert np.all(np.abs(np.roots(np.r_[1.0, -phi])) < 1.0), (seed, phi)


def test_white_noise_with_gaps_keeps_a_low_order():
    """White noise with the same gaps: the order chosen stays low and the innovations are the
    noise itself (the guard changes nothing where the autocovariances are admissible)."""
    rate, n = 513.0, 5000
    t = np.arange(n) / rate
    rng = np.random.default_rng(7)
    x = rng.normal(0.0, 0.3, (n, 6))
    valid = np.abs(np.sin(2 * np.pi * 0.3 * t[:, None] + rng.uniform(0, 6, 6))) > 0.5
    w = st.Whitener.fit(x, MAX_ORDER, valid=valid)
    assert w.order <= 2
    assert np.allclose(w.innovation_std, 0.3, rtol=0.05)
