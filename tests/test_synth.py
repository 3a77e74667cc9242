"""Synthetic measured data (``gsfric synth``): format, hidden effects, noise, reproducibility."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import gsfric.synth as synth_module
from gsfric.cli import main
from gsfric.errors import InputError, InputTypeError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.io.readers import read_measured, read_trajectory
from gsfric.io.tables import write_table
from gsfric.models import HOME_HEIGHT, reference_platform, sinusoidal
from gsfric.platform.usable import check_poses, home_height
from gsfric.synth import (
    Similar,
    ar1_noise,
    excitation_motion,
    parse_effect,
    run_synth,
    similar_pose,
    synthesize,
)

COLUMNS = ["t", "x", "y", "z", "qw", "qx", "qy", "qz"] + [f"F{i}" for i in range(1, 7)] \
    + [f"D{i}" for i in range(1, 7)]


def test_noise_free_forces_are_the_true_platforms():
    data = synthesize(effects=["seal_friction:force=2"], samples=300, noise=0.0, seed=1)
    assert list(data.frame.columns) == COLUMNS
    true = reference_platform().with_effect("seal_friction", force=2.0)
    F = Evaluator(true).actuator_forces(state_array(data.motion))
    measured = data.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()
    np.testing.assert_allclose(measured, F, atol=1e-12)
    assert data.effects == {"seal_friction": {"force": 2.0}}
    # seal friction opposes the leg speed: its contribution has the sign of the speed (F reads it)
    speed = Evaluator(true).evaluate(data.motion).D_dot
    moving = np.abs(speed) > 1e-3
    np.testing.assert_allclose(data.contributions["seal_friction"][moving],
                               2.0 * np.sign(speed[moving]), atol=2e-4)  # regularised sign


def test_same_seed_same_data_other_seed_other_data():
    a = synthesize(effects=["stribeck:static=1,velocity=0.02"], samples=200, noise=0.1,
                   noise_correlation=0.5, pose_noise=1e-5, seed=7)
    b = synthesize(effects=["stribeck:static=1,velocity=0.02"], samples=200, noise=0.1,
                   noise_correlation=0.5, pose_noise=1e-5, seed=7)
    c = synthesize(effects=["stribeck:static=1,velocity=0.02"], samples=200, noise=0.1,
                   noise_correlation=0.5, pose_noise=1e-5, seed=8)
    pd.testing.assert_frame_equal(a.frame, b.frame)
    assert not np.allclose(a.frame["F1"], c.frame["F1"])


@pytest.mark.parametrize("phi", [0.0, 0.9])
def test_ar1_noise_has_the_requested_std_and_correlation(phi):
    e = ar1_noise(np.random.default_rng(3), (200_000, 2), 0.5, phi)
    assert e.std() == pytest.approx(0.5, rel=0.03)
    lag1 = np.mean(e[1:] * e[:-1]) / np.mean(e * e)
    assert lag1 == pytest.approx(phi, abs=0.01)


def test_pose_noise_moves_the_recorded_pose_only():
    clean = synthesize(samples=400, noise=0.0, pose_noise=0.0, seed=2)
    noisy = synthesize(samples=400, noise=0.0, pose_noise=1e-4, seed=2)
    dx = noisy.frame[["x", "y", "z"]].to_numpy() - clean.frame[["x", "y", "z"]].to_numpy()
    assert dx.std() == pytest.approx(1e-4, rel=0.15)
    q = noisy.frame[["qw", "qx", "qy", "qz"]].to_numpy()
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    angle = 2 * np.arccos(np.clip(np.abs(np.sum(
        q * clean.frame[["qw", "qx", "qy", "qz"]].to_numpy(), axis=1)), 0, 1))
    assert np.sqrt(np.mean(angle ** 2)) == pytest.approx(np.sqrt(3) * 1e-4, rel=0.15)
    # the forces are those of the true (noise-free) motion
    np.testing.assert_allclose(noisy.frame["F1"], clean.frame["F1"])


def test_stroke_reference_defaults_to_the_mean_leg_length():
    data = synthesize(effects=["stroke_friction:slope=20"], samples=300, noise=0.0, seed=4)
    D = Evaluator(data.model).evaluate(data.motion).D
    assert data.effects["stroke_friction"]["reference"] == pytest.approx(D.mean())


def test_effect_size_is_rms_contribution_over_noise():
    data = synthesize(effects=["quadratic_drag:coefficient=20"], samples=500, noise=0.25,
                      seed=5)
    rms = np.sqrt(np.mean(data.contributions["quadratic_drag"] ** 2))
    assert data.sizes["quadratic_drag"] == pytest.approx(rms / 0.25)


def test_excitation_motion_reverses_every_leg():
    t = np.arange(2000) / 200.0
    motion = excitation_motion(np.random.default_rng(0), t)
    speed = Evaluator(reference_platform()).evaluate(motion).D_dot
    reversals = np.sum(np.diff(np.sign(speed), axis=0) != 0, axis=0)
    assert np.all(reversals >= 6)


@pytest.mark.parametrize("text, message", [
    ("stribek:static=1", "unknown effect"),
    ("stribeck:statc=1", "unknown parameter"),
    ("stribeck:static=abc", "not a number"),
    ("stribeck:static", "expected param=value"),
])
def test_bad_effect_text(text, message):
    with pytest.raises(InputError, match=message):
        parse_effect(text)


@pytest.mark.parametrize("samples, error, message", [
    (10, InputError, r"samples: at least 20 are needed, got 10"),
    (100_000_000, InputError, (r"samples: 100,000,000 is more than the 1,000,000 a "
                               r"synthetic record holds in memory")),
    (400.0, InputTypeError, r"samples: expected an integer, got 400\.0"),
])
def test_a_number_of_samples_it_cannot_hold_is_refused_before_any_is_drawn(samples, error,
                                                                            message):
    with pytest.raises(error, match=message):
        synthesize(samples=samples)


def test_parse_effect():
    assert parse_effect("payload_offset:x=0.01, y=-0.02") == (
        "payload_offset", {"x": 0.01, "y": -0.02})
    assert parse_effect("seal_friction") == ("seal_friction", {})


def test_run_synth_writes_a_measured_data_file(tmp_path):
    path = run_synth(tmp_path / "m.parquet", effects=("sensor_bias:b1=1",), samples=100,
                     noise=0.05, seed=3)
    motion, forces, lengths = read_measured(path)
    assert forces.shape == (100, 6) and lengths.shape == (100, 6)


def test_cli_synth(tmp_path):
    out = tmp_path / "m.csv"
    result = CliRunner().invoke(main, ["synth", "--out", str(out), "--effect",
                                       "stribeck:static=2,velocity=0.01", "--samples", "200",
                                       "--noise", "0.1", "--noise-correlation", "0.8",
                                       "--pose-noise", "1e-5", "--seed", "4"])
    assert result.exit_code == 0, result.output
    assert list(pd.read_csv(out).columns) == COLUMNS


def test_cli_synth_rejects_an_unknown_effect(tmp_path):
    result = CliRunner().invoke(main, ["synth", "--out", str(tmp_path / "m.csv"), "--effect",
                                       "friction:force=1"])
    assert result.exit_code == 2
    assert "unknown effect" in result.output
    assert len(result.output.strip().splitlines()) == 1


def _scaled(factor: float):
    platform = reference_platform()
    g = platform.geometry
    return dataclasses.replace(platform, geometry=dataclasses.replace(
        g, base_joints=factor * np.asarray(g.base_joints),
        platform_joints=factor * np.asarray(g.platform_joints),
        stroke=(factor * g.stroke[0], factor * g.stroke[1])))


def test_the_reference_motion_is_the_reference_platforms_own():
    for platform in (reference_platform(), None):
        assert similar_pose(platform) == Similar((0.0, 0.0, HOME_HEIGHT), 1.0, 1.0, 1.0)


@pytest.mark.parametrize("factor", [2.0, 0.5])
def test_a_platform_of_another_size_gets_a_motion_inside_its_stroke(factor):
    """Twice and half the reference's size: the synthetic motion is the reference's carried
    over by the platform's home height and stroke, so it stays within the stroke (the readers'
    check passes) and moves about the platform's own home pose."""
    platform = _scaled(factor)
    assert home_height(platform) == pytest.approx(factor * home_height(reference_platform()))
    data = synthesize(platform, samples=400, rate=200.0, noise=0.1, seed=3)
    motion = data.motion
    check_poses(platform, motion.position, motion.rotation, motion.t)
    lengths = platform.leg_lengths(motion.position, motion.rotation)
    stroke = platform.geometry.stroke
    assert stroke[0] < lengths.min() and lengths.max() < stroke[1]
    assert np.mean(motion.position[:, 2]) == pytest.approx(HOME_HEIGHT * factor, rel=0.05)



def test_a_short_stroke_gets_a_motion_inside_it_and_a_large_rig_the_same_accelerations():
    """A stroke of a sixth of the reference's on the same joints: the rotations shrink with
    the translations (a turn moves the legs by the radius times the angle), and the motion
    stays inside it. Ten times the reference's size: the periods grow by the square root of
    the size, so the accelerations (and the inertial loads against the weight) stay the
    reference's instead of growing tenfold."""
    short = reference_platform().with_geometry(stroke=(0.7, 0.8))
    motion = synthesize(short, samples=2000, rate=200.0, seed=1).motion
    lengths = short.leg_lengths(motion.position, motion.rotation)
    assert 0.7 < lengths.min() and lengths.max() < 0.8
    reference = synthesize(samples=2000, rate=200.0, seed=1).motion
    large = synthesize(_scaled(10.0), samples=2000, rate=200.0, seed=1).motion
    ratio = np.abs(large.acceleration).max() / np.abs(reference.acceleration).max()
    assert 0.5 < ratio < 2.0
    assert np.ptp(large.position, axis=0).max() > 5 * np.ptp(reference.position, axis=0).max()


def test_synth_drives_a_trajectory_file_such_as_an_excitation(tmp_path):
    """``--motion``: the record follows the file's poses at its own times (an excitation
    rehearsed from the command line); --samples beside it is refused, not ignored."""
    motion = sinusoidal(np.arange(301) / 100.0)
    write_table(motion.to_frame(), tmp_path / "motion.csv")
    runner = CliRunner()
    result = runner.invoke(main, ["synth", "--motion", str(tmp_path / "motion.csv"), "--out",
                                  str(tmp_path / "m.csv"), "--noise", "0"])
    assert result.exit_code == 0, result.output
    measured, forces, _ = read_measured(tmp_path / "m.csv")
    np.testing.assert_allclose(measured.t, motion.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(measured.position, motion.position, rtol=0, atol=1e-9)
    driven = read_trajectory(tmp_path / "motion.csv")     # the file, as every command reads it
    truth = Evaluator(reference_platform()).evaluate_quiet(driven).F
    np.testing.assert_allclose(forces, truth, rtol=1e-12, atol=1e-9)
    result = runner.invoke(main, ["synth", "--motion", str(tmp_path / "motion.csv"), "--out",
                                  str(tmp_path / "n.csv"), "--samples", "100"])
    assert result.exit_code == 2 and "--samples: the --motion file's own times" in result.output
    assert not (tmp_path / "n.csv").exists()


def test_a_motion_given_sets_the_samples_and_is_checked_as_a_file_is(tmp_path, monkeypatch):
    """With a motion, ``samples`` is not used (nor checked); the motion's own length is held
    to the limit; a motion file outside the platform's stroke is refused naming the file,
    before any physics."""
    motion = sinusoidal(np.arange(40) / 100.0)
    assert len(synthesize(motion=motion, samples=5).frame) == 40
    monkeypatch.setattr(synth_module, "MAX_SAMPLES", 30)
    with pytest.raises(InputError, match=r"motion: 40 steps, more than the 30"):
        synthesize(motion=motion)
    monkeypatch.undo()
    write_table(motion.to_frame(), tmp_path / "motion.csv")
    short = reference_platform().with_geometry(stroke=(0.5, 0.6))
    short.to_toml(tmp_path / "short.toml")
    with pytest.raises(InputError, match=r"motion\.csv: 40 of 40 steps have a leg outside"):
        run_synth(tmp_path / "m.csv", platform_file=tmp_path / "short.toml",
                  motion_file=tmp_path / "motion.csv")
    assert not (tmp_path / "m.csv").exists()
