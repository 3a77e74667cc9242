"""The model-free lack-of-fit tests: structure that repeats with the state, structure driven by
the motion beyond the residual's own past; and that neither fires on noise, white or slow."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from gsfric.discovery import structure, transients
from gsfric.discovery.settings import Settings

DEFAULTS = Settings()

M = 6000
RATE = 250.0


def _motion(rng):
    """Leg lengths (m) and speeds (m/s) of six legs moving back and forth, (M, 6)."""
    t = np.arange(M) / RATE
    f = rng.uniform(0.2, 0.6, 6)
    phase = rng.uniform(0, 2 * np.pi, 6)
    D = 0.9 + 0.04 * np.sin(2 * np.pi * f * t[:, None] + phase)
    return t, D, np.gradient(D, t, axis=0)


def _ar1(rng, phi, sigma=0.2):
    e = rng.normal(0, sigma * np.sqrt(1 - phi ** 2), (M, 6))
    return lfilter([1.0], [1.0, -phi], e, axis=0)


def _state(residual, D, v, F):
    return structure.state_structure(residual, structure.state_features(D, v, F),
                                   np.ones(residual.shape, bool), n_folds=8, min_gap=0.3,
                                   n_bins=DEFAULTS.state_bins)


def _dynamic(residual, t, v, F):
    inputs = {"dF/dt": np.gradient(F, t, axis=0), "acceleration": np.gradient(v, t, axis=0)}
    return structure.dynamic_structure(residual, inputs, np.ones(residual.shape, bool),
                                     alpha=0.01, min_gap=0.3, order=DEFAULTS.dynamic_order,
                                     lags=DEFAULTS.dynamic_lags)


@pytest.mark.parametrize("phi", [0.0, 0.9, 0.995])
def test_noise_alone_has_no_structure(phi):
    """Noise, white or as slow as AR(1) with phi = 0.995, neither repeats with the state nor
    follows the motion."""
    for seed in range(3):
        rng = np.random.default_rng(seed)
        t, D, v = _motion(rng)
        F = 50 + 300 * np.gradient(v, t, axis=0)
        r = _ar1(rng, phi)
        assert not _state(r, D, v, F).significant, seed
        assert not _dynamic(r, t, v, F).significant, seed


@pytest.mark.parametrize("phi", [0.0, 0.95])
def test_a_ripple_in_the_stroke_repeats_with_the_leg_length(phi):
    rng = np.random.default_rng(1)
    t, D, v = _motion(rng)
    F = 50 + 300 * np.gradient(v, t, axis=0)
    ripple = 0.4 * np.sin(2 * np.pi * D / 0.012 + rng.uniform(0, 6, 6))
    out = _state(ripple + _ar1(rng, phi), D, v, F)
    assert out.significant and out.details["variable"] == "leg length"
    assert out.structure_rms == pytest.approx(0.4 / np.sqrt(2), rel=0.25)


def test_crosstalk_repeats_with_the_other_legs_force():
    rng = np.random.default_rng(2)
    t, D, v = _motion(rng)
    F = 100 * rng.uniform(0.5, 1.5, 6) * np.sin(2 * np.pi * rng.uniform(0.3, 1.0, 6)
                                                 * t[:, None])
    out = _state(0.05 * np.roll(F, -2, axis=1) + _ar1(rng, 0.5), D, v, F)
    assert out.significant and out.details["variable"] == "force of leg i+2"


@pytest.mark.parametrize("phi", [0.0, 0.95])
def test_a_ringing_mode_is_driven_by_the_motion(phi):
    """A 7 Hz mode with 5 % damping excited by the force's rate: not a function of the state,
    and its spectrum an AR model could mimic; the motion predicts it beyond the residual's
    past."""
    rng = np.random.default_rng(3)
    t, D, v = _motion(rng)
    F = 50 + 300 * np.gradient(v, t, axis=0) + 20 * np.sin(2 * np.pi * 1.3 * t)[:, None]
    w, z, dt = 2 * np.pi * 7.0, 0.05, 1 / RATE
    a = np.exp(-z * w * dt)
    ring = lfilter([1.0], [1.0, -2 * a * np.cos(w * dt), a * a], np.gradient(F, t, axis=0),
                   axis=0)
    ring *= 0.5 / np.sqrt(np.mean(ring ** 2))
    out = _dynamic(ring + _ar1(rng, phi), t, v, F)
    assert out.significant and out.p_value < 1e-6
    assert out.structure_rms == pytest.approx(0.5, rel=0.3)


@pytest.mark.parametrize("noise", ["resonant", "band"])
def test_a_small_driven_part_under_resonant_noise_is_not_magnified(noise):
    """Force noise with poles near the unit circle (an AR(2) resonance of radius 0.97, or white
    noise band-passed to 6-9 Hz) and a driven part of a tenth of it (the acceleration errors of
    a motion differentiated from noisy poses): the ARX recursion shares the noise's poles and
    passes the small input coefficient through them, a "driven part" of the noise's own size
    that the noise then cancels. What it explains (the fall of the residual's mean square when
    it is taken out) stays far below ``min_gap``."""
    from scipy.signal import butter

    for seed in range(3):
        rng = np.random.default_rng(seed)
        t, D, v = _motion(rng)
        F = 50 + 300 * np.gradient(v, t, axis=0)
        acceleration = np.gradient(v, t, axis=0)
        if noise == "resonant":
            w = 2 * np.pi * 8.0 / RATE
            x = lfilter([1.0], [1.0, -2 * 0.97 * np.cos(w), 0.97 ** 2],
                        rng.normal(0, 1, (M, 6)), axis=0)
        else:
            b, a = butter(4, [6.0, 9.0], btype="band", fs=RATE)
            x = lfilter(b, a, rng.normal(0, 1, (M + 500, 6)), axis=0)[500:]
        r = 0.2 * x / x.std() + 0.02 * acceleration / acceleration.std()
        out = _dynamic(r, t, v, F)
        assert not out.significant, (seed, out.gap)
        assert out.gap < 0.2, seed


def test_pink_noise_over_a_few_moves_between_rests_has_no_state_structure():
    """Three minimum-jerk moves of 0.8 s between long rests, only the moves used, pink (1/f)
    noise centred on them (as a fitted residual is): most speed and length bins are seen in one
    fold only, and the other folds' level is pulled away from the held-out fold's by the slow
    noise. A bin the other folds never visited must predict no better than that level."""
    for seed in range(6):
        rng = np.random.default_rng(seed)
        f = np.fft.rfftfreq(M, 1 / RATE)
        f[0] = f[1]
        x = np.fft.irfft(np.fft.rfft(rng.normal(0, 1, (M, 6)), axis=0) / np.sqrt(f)[:, None],
                         M, axis=0)
        t = np.arange(M) / RATE
        D = np.full((M, 6), 0.9)
        v = np.zeros((M, 6))
        valid = np.zeros((M, 6), bool)
        tau = np.linspace(0, 1, 200)
        for start in np.sort(rng.choice(np.arange(200, M - 400, 400), 3, replace=False)):
            step = rng.uniform(-0.05, 0.05, 6)
            D[start:start + 200] = D[start - 1] + step * (10 * tau ** 3 - 15 * tau ** 4
                                                          + 6 * tau ** 5)[:, None]
            D[start + 200:] = D[start + 199]
            v[start:start + 200] = step * (30 * tau ** 2 - 60 * tau ** 3
                                           + 30 * tau ** 4)[:, None] * RATE / 200
            valid[start:start + 200] = np.abs(v[start:start + 200]) > 1e-3
        r = 0.2 * x / x.std()
        r -= (r * valid).sum(0) / valid.sum(0)
        F = 50 + 300 * np.gradient(v, t, axis=0)
        out = structure.state_structure(r, structure.state_features(D, v, F), valid, n_folds=8,
                                      min_gap=0.3, n_bins=DEFAULTS.state_bins)
        assert not out.significant, (seed, out.details["variable"], out.gap)


def test_samples_left_out_are_not_used():
    """Pairs marked not valid carry no information: a ripple confined to them is not seen."""
    rng = np.random.default_rng(4)
    t, D, v = _motion(rng)
    F = 50 + 300 * np.gradient(v, t, axis=0)
    valid = np.abs(v) > np.quantile(np.abs(v), 0.5)
    ripple = np.where(valid, 0.0, 0.5 * np.sin(2 * np.pi * D / 0.012))
    r = ripple + _ar1(rng, 0.0)
    assert _state(r, D, v, F).significant
    out = structure.state_structure(r, structure.state_features(D, v, F), valid, n_folds=8,
                                  min_gap=0.3, n_bins=DEFAULTS.state_bins)
    assert not out.significant


# -- rests ----------------------------------------------------------------------------------

REACH = 20


def _rests(rng, rests=16, rest=220, move=160):
    """A sliding mask (M, 6) of moves and rests (all legs stop together), its rest cores, and
    the sample where each rest begins."""
    period = rest + move
    m = rests * period + move
    sliding = np.ones((m, 6), bool)
    stops = []
    for k in range(rests):
        a = move + k * period
        sliding[a:a + rest] = False
        stops.append(a)
    runs = transients.rest_runs(sliding, REACH, min_run=DEFAULTS.rest_min_run)
    return sliding, runs, np.array(stops)


def _transients(r, runs):
    return transients.rest_transients(r, runs, alpha=0.01, min_gap=0.3,
                                      window=DEFAULTS.rest_window, lags=DEFAULTS.rest_lags,
                                      min_rests=DEFAULTS.rest_min_rests)


def test_rest_cores_leave_out_the_ends_of_the_moves():
    """A core is the run of not-sliding pairs less twice the differentiator's reach at each
    end; a run touching an end of the record is no rest between two moves."""
    sliding, runs, stops = _rests(np.random.default_rng(0), rests=3)
    assert len(runs) == 3 * 6
    assert {(a, b) for _, a, b in runs} == {(s + 2 * REACH, s + 220 - 2 * REACH) for s in stops}
    sliding[:50, 2] = False                      # standing at the start of the record
    assert len(transients.rest_runs(sliding, REACH, min_run=DEFAULTS.rest_min_run)) == 3 * 6
    # cores shorter than rest_min_run
    assert transients.rest_runs(sliding, 45, min_run=DEFAULTS.rest_min_run) == []


@pytest.mark.parametrize("phi", [0.0, 0.9, 0.995])
def test_noise_at_rests_has_no_transient(phi):
    """Noise, white or as slow as AR(1) with phi = 0.995, plus a static friction of its own
    in each rest (up to 2 N, constant while the leg stands still), is as large at the start of
    a rest as at its end."""
    fired = 0
    for seed in range(10):
        rng = np.random.default_rng(seed)
        sliding, runs, stops = _rests(rng)
        r = np.zeros(sliding.shape)
        for s in stops:
            r[s:s + 220] += rng.uniform(-2, 2, 6)
        e = rng.normal(0, 0.2 * np.sqrt(1 - phi ** 2), r.shape)
        r += lfilter([1.0], [1.0, -phi], e, axis=0)
        out = _transients(r, runs)
        assert out.details["rests"] == 16 and out.details["cores"] == 96
        fired += out.significant
    assert fired == 0


@pytest.mark.parametrize("phi", [0.0, 0.95])
def test_a_mode_ringing_after_each_stop_is_a_transient(phi):
    """A 7 Hz mode with 5 % damping rings after each stop, with the sign and size of the
    deceleration that excites it: of zero mean over the rests, and an AR model of the
    residual could mimic its spectrum; it is largest at the start of each rest."""
    rng = np.random.default_rng(5)
    sliding, runs, stops = _rests(rng)
    r = np.zeros(sliding.shape)
    tau = np.arange(220) / RATE
    ring = np.exp(-0.05 * 2 * np.pi * 7 * tau) * np.sin(2 * np.pi * 7 * tau)
    for s in stops:
        r[s:s + 220] += ring[:, None] * rng.normal(0, 0.5, 6)
    e = rng.normal(0, 0.2 * np.sqrt(1 - phi ** 2), r.shape)
    out = _transients(r + lfilter([1.0], [1.0, -phi], e, axis=0), runs)
    assert out.significant and out.p_value < 1e-4
    assert out.gap > 0.5
