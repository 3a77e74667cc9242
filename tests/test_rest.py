"""Rests and the speed band with a differentiator whose filter varies along the record: the band
follows the filter of each sample, and each sample looks for rests as far as its own window
reaches (docs/explanation/discovery.md, "The motion estimate")."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from gsfric.discovery.rest import (
    differentiator,
    poses_from_columns,
    sliding_mask,
    speed_uncertainty,
    spline_differentiator,
)
from gsfric.discovery.settings import Settings
from gsfric.simulate.api import evaluate
from gsfric.models import minimum_jerk_moves, point_to_point, reference_platform
from gsfric.signal.noise import divided_noise_std_every_window
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.synth import synthesize
from gsfric.trajectory import Motion

DEFAULTS = Settings()
MOVE = DEFAULTS.move_to_noise


def test_each_sample_looks_as_far_as_its_own_window_reaches():
    n = 600
    speed = np.full((n, 6), 0.01)
    speed[300:400] = 0.0                                  # a rest of 100 samples
    reach = np.where(np.arange(n) < 300, 40, 5)           # long windows before, short after
    sliding = sliding_mask(speed, np.full(6, 1e-4), 0.0, reach=reach,
                           rest_band=DEFAULTS.rest_band)[:, 0]
    assert not sliding[260:300].any() and sliding[:259].all()     # 40 before the rest
    assert not sliding[400:405].any() and sliding[406:].all()     # 5 after it


def test_speed_band_matches_the_differentiated_speed_at_rest_and_in_motion():
    """At rest the differentiated leg speed is the pose noise through the sample's own filter:
    its spread matches the predicted sigma_v there."""
    platform = reference_platform(friction_model="paper")
    motion = point_to_point(np.random.default_rng(4), 4000)
    data = synthesize(platform, motion=motion, noise=0.1, pose_noise=2e-5, seed=4)
    fr = data.frame
    position = fr[["x", "y", "z"]].to_numpy()
    quaternion = fr[["qw", "qx", "qy", "qz"]].to_numpy()
    estimate = Motion.from_samples(fr.t.to_numpy(), position, quaternion=quaternion)
    _, rotation = poses_from_columns(fr)
    gain, reach = differentiator(position, rotation, move_to_noise=MOVE)
    sigma = speed_uncertainty(platform, fr.t.to_numpy(), position, rotation, gain=gain)
    assert sigma.shape == (4000, 6) and reach.shape == (4000,)
    v_true = evaluate(platform, data.motion).D_dot
    v_est = evaluate(platform, estimate).D_dot
    rest = np.all(np.abs(v_true) < 1e-9, axis=1)
    rest[:200] = rest[-200:] = False
    # deep inside rests (the filter's span wholly at rest)
    deep = rest.copy()
    for shift in range(1, 25):
        deep[shift:] &= rest[:-shift]
        deep[:-shift] &= rest[shift:]
    assert deep.sum() > 100
    spread = np.sqrt(np.mean(v_est[deep] ** 2, axis=0))
    predicted = np.sqrt(np.mean(sigma[deep] ** 2, axis=0))
    assert np.all(predicted > 0.6 * spread) and np.all(predicted < 1.6 * spread)
    # the band follows each sample's filter: a different filter, a different band
    assert np.ptp(gain) > 0 and np.allclose(sigma / gain[:, None], sigma[0] / gain[0])


def moves_and_rests(t: np.ndarray) -> np.ndarray:
    """Positions (N, 3), m: minimum-jerk moves of 1.5 s between fixed targets, each followed
    by a rest of 1 s, evaluated in closed form at any times."""
    targets = np.array([[0.0, 0.0, 0.95], [0.02, -0.01, 0.96], [-0.015, 0.02, 0.94],
                        [0.01, 0.015, 0.95], [0.0, 0.0, 0.95]])
    period, move = 2.5, 1.5
    k = np.minimum((t // period).astype(int), len(targets) - 2)
    s = np.clip((t - k * period) / move, 0.0, 1.0)
    shape = 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5
    return targets[k] + shape[:, None] * (targets[k + 1] - targets[k])


def test_jittered_time_base_gets_a_speed_band_of_its_own():
    """On a log whose sample times jitter (+-20 % of the step) the smoothing spline's own noise
    gain gives the band: it matches the spread of the differentiated leg speed deep inside the
    rests, where a band from differences that ignore the jitter would count the motion."""
    rng = np.random.default_rng(8)
    platform = reference_platform(friction_model="paper")
    step = 1 / 200.0
    t = np.arange(2000) * step + rng.uniform(-0.2, 0.2, 2000) * step
    t[0] = 0.0
    exact = moves_and_rests(t)
    position = exact + rng.normal(0, 2e-5, exact.shape)
    rotation = Rotation.from_rotvec(rng.normal(0, 2e-5, (len(t), 3))).as_matrix()
    quaternion = quaternion_from_rotation(rotation)
    estimate = Motion.from_samples(t, position, quaternion=quaternion)
    gain, reach = spline_differentiator(t, position, rotation, DEFAULTS.spline_noise_draws)
    D = platform.leg_lengths(position, rotation)
    sigma_D = divided_noise_std_every_window(t, D)
    np.testing.assert_allclose(sigma_D, 2e-5, rtol=0.5)      # the leg lengths mix x, y, z
    sigma = gain[:, None] * sigma_D[None, :]
    v_est = evaluate(platform, estimate).D_dot
    phase = t % 2.5
    deep = (phase > 1.75) & (phase < 2.25) & (t > 1.0) & (t < t[-1] - 1.0)
    spread = np.sqrt(np.mean(v_est[deep] ** 2, axis=0))
    predicted = np.sqrt(np.mean(sigma[deep] ** 2, axis=0))
    assert np.all(predicted > 0.6 * spread) and np.all(predicted < 1.6 * spread)
    assert reach.min() >= 3


def test_seal_force_on_a_jittered_log_with_rests_is_named():
    """Discovery on a log with jittered times (+-20 % of the step) and rests (30 % of the
    time): the rests are found with the splines' own band, so a seal force is named and the
    residual is at the noise (without a band, the friction flipping at rest leaves a residual
    twice the noise, named as other effects)."""
    from gsfric.discovery import discover

    rng = np.random.default_rng(3)
    step, n = 1 / 200.0, 4000
    t = np.arange(n) * step + rng.uniform(-0.2, 0.2, n) * step
    t[0] = 0.0
    targets = np.c_[rng.uniform(-0.02, 0.02, (12, 2)), 0.95 + rng.uniform(-0.01, 0.01, 12)]
    motion = minimum_jerk_moves(t, targets, period=2.0, move=1.4)
    platform = reference_platform(friction_model="paper")
    data = synthesize(platform, ["seal_friction:force=1.0"], motion=motion, noise=0.2,
                      pose_noise=1e-5, seed=2)
    fr = data.frame
    recorded = Motion.from_samples(fr.t.to_numpy(), fr[["x", "y", "z"]].to_numpy(),
                                   quaternion=fr[["qw", "qx", "qy", "qz"]].to_numpy())
    result = discover(recorded, fr[[f"F{i}" for i in range(1, 7)]].to_numpy(), platform,
                      poses=poses_from_columns(fr), n_bootstrap=20, n_threads=1)
    assert result.names == ["seal_friction"]
    assert result.noise.not_sliding_share > 0.25
    assert result.rms_after < 1.15 * float(np.sqrt(np.mean(data.noise ** 2)))


def _recorded_point_to_point():
    """A point-to-point record with 10 um of pose noise (paper base): the platform, the log's
    frame, its positions and the motion ``Motion.from_samples`` makes of them."""
    platform = reference_platform(friction_model="paper")
    data = synthesize(platform, motion=point_to_point(np.random.default_rng(5), 3000),
                      noise=0.1, pose_noise=1e-5, seed=5)
    fr = data.frame
    position = fr[["x", "y", "z"]].to_numpy()
    estimate = Motion.from_samples(fr.t.to_numpy(), position,
                                   quaternion=fr[["qw", "qx", "qy", "qz"]].to_numpy())
    return platform, fr, position, estimate


def test_differentiator_from_the_motions_own_filters():
    """The gains and reaches from the filters ``Motion.from_samples`` chose for the recorded
    samples are those chosen again from the recorded poses (the filters are chosen once)."""
    _, fr, position, estimate = _recorded_point_to_point()
    _, rotation = poses_from_columns(fr)
    filters = estimate.sample_filters()
    assert filters is not None and estimate.slice(0, 100).sample_filters() is None
    assert estimate.sample_filters(polyorder=2) is None
    again = differentiator(position, rotation, move_to_noise=MOVE)
    once = differentiator(position, rotation, filters=filters, move_to_noise=MOVE)
    assert np.array_equal(again[0], once[0]) and np.array_equal(again[1], once[1])
    # a motion given its own window chose none
    fixed = Motion.from_samples(fr.t.to_numpy(), position, window=31,
                                quaternion=fr[["qw", "qx", "qy", "qz"]].to_numpy())
    assert fixed.sample_filters() is None


def test_a_fixed_orientation_does_not_widen_the_rests():
    """Translations only, the orientation held (noise-free, or with noise of its own): the
    orientation's filter is the longest there is (nothing to resolve), and its reach does not
    count; the position's does. A rotating platform keeps the longer of the two."""
    from gsfric.discovery.rest import moves
    from gsfric.signal.windows import motion_filters

    rng = np.random.default_rng(6)
    rate, seconds = 500.0, 12.0
    t = np.arange(int(rate * seconds)) / rate
    targets = np.c_[rng.uniform(-0.03, 0.03, (12, 2)), 0.95 + rng.uniform(-0.02, 0.02, 12)]
    position = minimum_jerk_moves(t, targets, 1.2, 0.3).position
    for rotation_noise in (0.0, 1e-5):
        angles = rng.normal(0, rotation_noise, (len(t), 3))
        rotation = Rotation.from_rotvec(angles).as_matrix()
        q = quaternion_from_rotation(rotation)
        assert not moves(q, MOVE)
        _, reach = differentiator(position, rotation, move_to_noise=MOVE)
        np.testing.assert_array_equal(reach, motion_filters(position)[0][1] // 2)
    turning = Rotation.from_rotvec(np.c_[np.zeros((len(t), 2)), 0.2 * np.sin(t)]).as_matrix()
    _, reach = differentiator(position, turning, move_to_noise=MOVE)
    q_reach = motion_filters(quaternion_from_rotation(turning))[0][1] // 2
    np.testing.assert_array_equal(reach, np.maximum(motion_filters(position)[0][1] // 2,
                                                    q_reach))


def test_the_motion_keeps_its_recorded_poses_for_the_speed_band():
    """A motion made from samples keeps them: ``discover`` without ``poses`` measures the pose
    noise on the recorded samples, as the command line does with the log's columns (on the
    smoothed poses the band was 0.015 times as wide)."""
    from gsfric.discovery.residuals import Problem
    from gsfric.discovery.settings import Settings

    platform, fr, position, estimate = _recorded_point_to_point()
    kept, rotation = estimate.recorded_poses()
    np.testing.assert_array_equal(kept, position)
    np.testing.assert_allclose(rotation, poses_from_columns(fr)[1], atol=1e-12)
    assert estimate.slice(0, 100).recorded_poses() is None
    forces = fr[[f"F{i}" for i in range(1, 7)]].to_numpy()
    default = Problem(estimate, forces, platform, Settings(n_threads=1))
    given = Problem(estimate, forces, platform, Settings(n_threads=1),
                    poses=poses_from_columns(fr))
    np.testing.assert_allclose(default.sigma_v, given.sigma_v, rtol=1e-9)
    np.testing.assert_array_equal(default.sliding, given.sliding)
    smoothed = Problem(estimate, forces, platform, Settings(n_threads=1),
                       poses=(estimate.position, estimate.rotation))
    assert np.all(smoothed.sigma_v < 0.1 * given.sigma_v)


def test_time_stamps_rounded_in_the_log_keep_the_motions_filters():
    """A log's time stamps rounded to 0.1 us (ms with four decimals) are uniform for
    ``Motion.from_samples``, which differentiates with its Savitzky-Golay filters; the speed
    band and the rests' reach must come from those filters, not from the smoothing splines of
    a jittered time base."""
    from gsfric.discovery.residuals import Problem
    from gsfric.discovery.settings import Settings

    platform, fr, position, _ = _recorded_point_to_point()
    exact = fr.t.to_numpy() * 0.997311 + 1.0
    rounded = np.round(exact * 1e7) / 1e7
    assert np.ptp(np.diff(rounded)) > 1e-6 * np.mean(np.diff(rounded))
    forces = fr[[f"F{i}" for i in range(1, 7)]].to_numpy()
    quaternion = fr[["qw", "qx", "qy", "qz"]].to_numpy()
    problems = [Problem(Motion.from_samples(times, position, quaternion=quaternion), forces,
                        platform, Settings(n_threads=1), poses=poses_from_columns(fr))
                for times in (exact, rounded)]
    assert problems[1].model.motion.sample_filters() is not None
    np.testing.assert_array_equal(problems[0].reach, problems[1].reach)
    np.testing.assert_allclose(problems[0].sigma_v, problems[1].sigma_v, rtol=1e-3)
    np.testing.assert_array_equal(problems[0].sliding, problems[1].sliding)
