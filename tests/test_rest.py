"""Rests and the speed band with a differentiator whose filter varies along the record: the band
follows the filter of each sample, and each sample looks for rests as far as its own window
reaches (docs/discovery.md, "The motion estimate")."""

from __future__ import annotations

import numpy as np

from gsfric.discovery.rest import (differentiator, poses_from_columns, sliding_mask,
                                   speed_uncertainty)
from gsfric.evaluation import evaluate
from gsfric.models import point_to_point, reference_platform
from gsfric.synth import synthesize
from gsfric.trajectory import Motion


def test_each_sample_looks_as_far_as_its_own_window_reaches():
    n = 600
    speed = np.full((n, 6), 0.01)
    speed[300:400] = 0.0                                  # a rest of 100 samples
    reach = np.where(np.arange(n) < 300, 40, 5)           # long windows before, short after
    sliding = sliding_mask(speed, np.full(6, 1e-4), 0.0, reach=reach)[:, 0]
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
    gain, reach = differentiator(position, rotation)
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
