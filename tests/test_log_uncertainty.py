"""The differentiation's uncertainty carried into the forces, and legs possibly at rest.

A log made like a real controller's: 100 Hz, a wrapping uint32 microsecond counter, stamps that
jitter by 1.1 % of the step, the pose in a z-down frame in mm and degrees with noise, the
controller's own velocity and acceleration columns, and rests between the moves.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from helpers import trajectory_frame

import gsfric
from gsfric import models
from gsfric.cli import main
from gsfric.errors import GsfricWarning
from gsfric.evaluation import state_array
from gsfric.evaluation.uncertainty import force_sigma, leg_speeds, possibly_at_rest
from gsfric.io.logs import LogFormat
from gsfric.io.readers import read_trajectory
from gsfric.io.tables import read_table
from gsfric.signal.local import local_polynomial_derivatives, local_polynomial_gains
from gsfric.signal.rotations import rpy_from_rotation
from gsfric.signal.savgol import savgol_filter, savgol_gains
from gsfric.signal.smoothing import evenly_spaced
from gsfric.simulate.run import simulate_file
from gsfric.sweep import sweep
from gsfric.trajectory import Motion

RATE, JITTER, HOME = 100.0, 0.011, 0.75
FLIP = np.diag([1.0, -1.0, -1.0])            # the controller's axes (z down) in the platform's
POSE_NOISE, ANGLE_NOISE = 2e-5, 2e-5         # m, rad


def _step(x: np.ndarray, ramp: float):
    """A cosine step from 0 to 1 over x in [-ramp/2, ramp/2], and its derivative."""
    phase = np.clip((x + ramp / 2) / ramp, 0.0, 1.0)
    inside = (phase > 0) & (phase < 1)
    return 0.5 - 0.5 * np.cos(np.pi * phase), np.where(
        inside, 0.5 * np.pi / ramp * np.sin(np.pi * phase), 0.0)


def _pace(t: np.ndarray, rests: list[tuple[float, float]], ramp: float = 0.4):
    """A motion time tau(t) that stands still over each rest (start, end) and runs at unit
    pace between, with cosine ramps of ``ramp`` s: tau, tau', tau'' at t (N,) each."""
    def rate(x):
        value, slope = np.ones_like(x), np.zeros_like(x)
        for start, end in rests:
            up, dup = _step(x - start, ramp)
            down, ddown = _step(x - end, ramp)
            factor = 1.0 - up * (1.0 - down)
            value, slope = value * factor, slope * factor + value * (-dup * (1.0 - down)
                                                                     + up * ddown)
        return value, slope
    fine = np.linspace(t[0] - 0.1, t[-1] + 0.1, 200 * len(t))
    pace = rate(fine)[0]
    tau = np.concatenate([[0.0], np.cumsum(0.5 * (pace[1:] + pace[:-1]) * np.diff(fine))])
    value, slope = rate(t)
    return np.interp(t, fine, tau), value, slope


def paced_motion(t: np.ndarray, rests) -> Motion:
    """``models.sinusoidal`` run at the pace of ``_pace``: still over the rests."""
    tau, rate, slope = _pace(t, rests)
    base = models.sinusoidal(tau, amplitude=(0.06, 0.05, 0.05, 0.1, 0.08, 0.1),
                             frequency=(0.6, 0.8, 1.0, 0.7, 0.9, 0.5))
    return Motion.from_arrays(
        t, base.position, base.rotation, rate[:, None] * base.velocity,
        rate[:, None] * base.omega,
        slope[:, None] * base.velocity + rate[:, None] ** 2 * base.acceleration,
        slope[:, None] * base.omega + rate[:, None] ** 2 * base.alpha)


def controller_log(seconds: float = 30.0, stamps: str = "clock", seed: int = 7,
                   noise: float = 1.0):
    """The log (DataFrame), its format and the true motion. ``stamps``: "clock" (the poses
    sampled every 10 ms, the stamps read with jitter) or "sampling" (the poses sampled at the
    jittered stamps); ``noise`` scales the pose noise."""
    rng = np.random.default_rng(seed)
    n = int(seconds * RATE)
    even = np.arange(n) / RATE
    stamped = even + rng.uniform(-0.5, 0.5, n) * JITTER / RATE
    rests = [(4.0, 7.0), (15.0, 17.5), (24.0, 26.0)]
    truth = paced_motion(even if stamps == "clock" else stamped, rests)
    position = truth.position + rng.normal(0.0, noise * POSE_NOISE, (n, 3))
    log_position = (position - [0.0, 0.0, HOME]) @ FLIP
    angles = rpy_from_rotation(FLIP @ truth.rotation @ FLIP) \
        + rng.normal(0.0, noise * ANGLE_NOISE, (n, 3))
    counts = (2**32 - 3_000_000 + np.round(stamped * 1e6).astype(np.int64)) % 2**32
    log = pd.DataFrame({"Timestamp [us]": counts.astype(np.uint32)})
    for k, name in enumerate(("Surge", "Sway", "Heave")):
        log[f"{name} [mm]"] = np.round(log_position[:, k] * 1e3, 4)
    for k, name in enumerate(("Roll", "Pitch", "Yaw")):
        log[f"{name} [deg]"] = np.round(np.degrees(angles[:, k]), 5)
    for k, name in enumerate(("Surge", "Sway", "Heave")):
        log[f"{name} vel [mm/s]"] = np.round((truth.velocity @ FLIP)[:, k] * 1e3, 3)
        log[f"{name} acc [mm/s2]"] = np.round((truth.acceleration @ FLIP)[:, k] * 1e3, 2)
    columns = {"t": "Timestamp [us]", "x": "Surge [mm]", "y": "Sway [mm]", "z": "Heave [mm]",
               "roll": "Roll [deg]", "pitch": "Pitch [deg]", "yaw": "Yaw [deg]"}
    units = {"t": "us", **dict.fromkeys("xyz", "mm"),
             **dict.fromkeys(("roll", "pitch", "yaw"), "deg")}
    for axis, name in zip("xyz", ("Surge", "Sway", "Heave")):
        columns[f"v{axis}"], units[f"v{axis}"] = f"{name} vel [mm/s]", "mm/s"
        columns[f"a{axis}"], units[f"a{axis}"] = f"{name} acc [mm/s2]", "mm/s^2"
    fmt = {"columns": columns, "units": units, "angles": "xyz", "axes": ["x", "-y", "-z"],
           "offset": {"z": HOME}, "wrap": 2**32}
    return log, fmt, truth


def _format(fmt: dict, rates: bool = True) -> LogFormat:
    fmt = dict(fmt)
    if not rates:
        fmt["columns"] = {k: v for k, v in fmt["columns"].items() if k[0] not in "va"}
        fmt["units"] = {k: v for k, v in fmt["units"].items() if k[0] not in "va"}
    return LogFormat(**fmt)


def _quiet(function, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GsfricWarning)
        return function(*args, **kwargs)


# -- the smoothers' noise gains --------------------------------------------------------------


def test_savgol_and_local_gains_are_the_noise_they_pass():
    rng = np.random.default_rng(0)
    noise = rng.standard_normal((400, 4000))
    for deriv in (1, 2):
        measured = np.std(savgol_filter(noise, 21, 4, deriv), axis=1)
        np.testing.assert_allclose(measured, savgol_gains(400, 21, 4, deriv), rtol=0.06)
    t = np.sort(rng.uniform(0.0, 4.0, 300))
    first, second = local_polynomial_gains(t, 15, 3)
    _, d1, d2 = local_polynomial_derivatives(t, noise[:300, :2000], 15, 3)
    np.testing.assert_allclose(np.std(d1, axis=1), first, rtol=0.08)
    np.testing.assert_allclose(np.std(d2, axis=1), second, rtol=0.08)


# -- the time base -----------------------------------------------------------------------------


@pytest.mark.parametrize("stamps, noise, even", [("clock", 0.1, True), ("sampling", 0.1, False),
                                                 ("sampling", 1.0, True)])
def test_the_time_base_is_the_one_the_poses_are_smooth_on(stamps, noise, even, tmp_path):
    # the stamps are used where the motion times their error is the larger part of the
    # noise; below the pose noise the even grid is kept
    log, fmt, _ = controller_log(20.0, stamps, noise=noise)
    t = (log["Timestamp [us]"].to_numpy().astype(np.int64) - int(log.iloc[0, 0])) % 2**32 / 1e6
    position = log[["Surge [mm]", "Sway [mm]", "Heave [mm]"]].to_numpy() / 1e3
    assert evenly_spaced(t, position) is even
    motion = _quiet(read_trajectory, _write(log, tmp_path), log_format=_format(fmt, rates=False))
    assert motion.differentiation().even is even
    assert "1.1 % jitter" in motion.differentiation().describe()


def _write(log: pd.DataFrame, folder: Path) -> Path:
    path = folder / "log.csv"
    log.to_csv(path, index=False)
    return path


# -- sigma_F -----------------------------------------------------------------------------------


@pytest.mark.parametrize("stamps", ["clock", "sampling"])
def test_sigma_f_is_the_spread_of_the_forces_about_the_truth(stamps, tmp_path):
    log, fmt, truth = controller_log(30.0, stamps)
    motion = _quiet(read_trajectory, _write(log, tmp_path), log_format=_format(fmt, rates=False))
    platform = gsfric.reference_platform()
    evaluator = gsfric.Evaluator(platform)
    sigma = force_sigma(evaluator, motion)
    exact = _quiet(gsfric.evaluate, platform, truth).F
    result = _quiet(gsfric.evaluate, platform, motion)
    np.testing.assert_allclose(result.sigma_F, sigma)
    moving = np.all(np.abs(_quiet(gsfric.evaluate, platform, truth).D_dot) > 0.01, axis=1)
    moving[:30] = moving[-30:] = False
    ratio = np.abs(result.F - exact)[moving] / sigma[moving]
    # |error| / sigma of a normal error has the median 0.67; the smoother's bias adds a little
    assert 0.3 < np.median(ratio) < 1.5
    assert result.to_frame().attrs["units"]["sigma_F1"] == "N"


@pytest.mark.integration
@pytest.mark.parametrize("stamps", ["clock", "sampling"])
def test_own_rates_differ_from_the_differentiated_ones_by_what_sigma_f_says(tmp_path, stamps):
    log, fmt, _ = controller_log(60.0, stamps)
    path = _write(log, tmp_path)
    summary = _quiet(simulate_file, path, tmp_path / "own.csv", log_format=_format(fmt))
    comparison = summary.rates
    assert comparison.rates == ("velocity", "acceleration")
    assert comparison.median_ratio <= 3.0
    assert np.all(comparison.largest_difference > 0)
    # the same numbers as two runs, with and without the log's rates
    own = read_table(tmp_path / "own.csv")
    _quiet(simulate_file, path, tmp_path / "derived.csv", log_format=_format(fmt, rates=False))
    derived = read_table(tmp_path / "derived.csv")
    F = [f"F{i}" for i in range(1, 7)]
    sigma = derived[[f"sigma_F{i}" for i in range(1, 7)]].to_numpy()
    difference = np.abs(own[F].to_numpy() - derived[F].to_numpy())
    assert np.median(difference / sigma) == pytest.approx(comparison.median_ratio, rel=1e-6)


def test_simulate_prints_the_comparison_and_can_leave_the_uncertainty_out(tmp_path):
    log, fmt, _ = controller_log(20.0, "clock")
    path = _write(log, tmp_path)
    runner = CliRunner()
    out = tmp_path / "forces.csv"
    args = ["simulate", "--trajectory", str(path), "--column-map", str(_toml(fmt, tmp_path)),
            "--out", str(out)]
    result = runner.invoke(main, args, catch_exceptions=False)
    assert result.exit_code == 0, result.output
    assert "the log's own velocity, acceleration against its poses differentiated" \
        in result.stdout and "median |dF| / sigma_F" in result.stdout
    assert "possibly at rest" in result.stdout
    frame = read_table(out)
    assert {f"sigma_F{i}" for i in range(1, 7)} <= set(frame.columns) and "rest" in frame
    result = runner.invoke(main, [*args, "--no-uncertainty"], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    frame = read_table(out)
    assert "sigma_F1" not in frame and "rest" not in frame
    assert "sigma_F" not in result.stdout


def test_a_platform_held_still_without_noise_has_every_leg_possibly_at_rest(tmp_path):
    """Poses written exactly and never changing: the rate uncertainty is 0 and the legs'
    speeds are round-off; every leg of every step is possibly at rest (rest = 63), while a
    moving record of the same exact poses has none."""
    moving = trajectory_frame(100)
    still = moving.copy()
    for name in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        still[name] = still[name].iloc[0]
    rests = {}
    for name, frame in (("still", still), ("moving", moving)):
        frame.to_csv(tmp_path / f"{name}.csv", index=False)
        summary = simulate_file(tmp_path / f"{name}.csv", tmp_path / f"{name}-F.csv")
        rests[name] = (summary.rest_steps, read_table(tmp_path / f"{name}-F.csv")["rest"])
    assert rests["still"][0] == 100 and (rests["still"][1] == 63).all()
    assert rests["moving"][0] == 0 and (rests["moving"][1] == 0).all()


def _toml(fmt: dict, folder: Path) -> Path:
    lines = ['angles = "xyz"', 'axes = ["x", "-y", "-z"]', f"wrap = {2**32}", "",
             "[offset]", f"z = {HOME}", "", "[columns]"]
    lines += [f'{k} = "{v}"' for k, v in fmt["columns"].items()]
    lines += ["", "[units]"] + [f'{k} = "{v}"' for k, v in fmt["units"].items()]
    path = folder / "log.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.integration
def test_a_large_sigma_f_is_a_warning_naming_the_share(tmp_path):
    t = np.arange(3000) / 100.0
    truth = models.sinusoidal(t)
    rng = np.random.default_rng(3)
    frame = pd.DataFrame({"t": t})
    frame[["x", "y", "z"]] = truth.position + rng.normal(0.0, 2e-4, truth.position.shape)
    frame[["qw", "qx", "qy", "qz"]] = truth.quaternion()
    path = tmp_path / "noisy.csv"
    frame.to_csv(path, index=False)
    # a short window passes much of 0.2 mm of noise into the accelerations
    with pytest.warns(GsfricWarning, match=r"sigma_F is .* % of its peak \|F\|"):
        simulate_file(path, tmp_path / "short.csv", window=9)
    with warnings.catch_warnings():
        warnings.simplefilter("error", GsfricWarning)
        simulate_file(path, tmp_path / "chosen.csv")          # the filters chosen per sample


# -- possibly at rest ------------------------------------------------------------------------


def test_legs_at_rest_are_marked_and_moving_ones_are_not(tmp_path):
    log, fmt, truth = controller_log(30.0, "clock")
    path = _write(log, tmp_path)
    _quiet(simulate_file, path, tmp_path / "out.csv", log_format=_format(fmt, rates=False))
    rest = read_table(tmp_path / "out.csv")["rest"].to_numpy().astype(int)
    speed = np.abs(_quiet(gsfric.evaluate, gsfric.reference_platform(), truth).D_dot)
    still = speed.max(axis=1) < 1e-9                    # every leg at rest (inside the rests)
    fast = speed.min(axis=1) > 0.02                     # every leg sliding fast
    inner_still = still & np.r_[False, still[:-1]] & np.r_[still[1:], False]
    assert np.mean(rest[inner_still] == 63) > 0.8       # all six legs marked at most rest steps
    assert np.all(rest[fast] == 0)


def test_possibly_at_rest_is_the_band_of_standard_deviations():
    speed = np.array([[0.0, 1e-3, -3e-3, 5e-3, -1e-2, 2e-2]])
    assert possibly_at_rest(speed, np.full(6, 2e-3)).tolist() == \
        [[True, True, True, False, False, False]]
    assert possibly_at_rest(speed, np.full(6, 2e-3), band=5.0)[0, :5].all()


def test_leg_speeds_are_the_evaluations_d_dot():
    truth = paced_motion(np.arange(600) / RATE, [(2.0, 3.0)])
    platform = gsfric.reference_platform()
    result = _quiet(gsfric.evaluate, platform, truth)
    np.testing.assert_allclose(leg_speeds(platform, truth), result.D_dot, rtol=1e-9,
                               atol=1e-12)


@pytest.mark.integration
def test_sweep_counts_the_steps_at_rest_as_simulate_does(tmp_path):
    log, fmt, _ = controller_log(20.0, "clock")
    motion = _quiet(read_trajectory, _write(log, tmp_path), log_format=_format(fmt, False))
    frame = motion.to_frame()[["t", "x", "y", "z", "qw", "qx", "qy", "qz"]]
    frame["t"] = motion.t
    frame.to_csv(tmp_path / "motion.csv", index=False)
    _quiet(simulate_file, tmp_path / "motion.csv", tmp_path / "forces.csv")
    rest = read_table(tmp_path / "forces.csv")["rest"].to_numpy()
    result = _quiet(sweep, tmp_path / "sweep", trajectories=str(tmp_path / "motion.csv"),
                    scheduler="serial", plots=False)
    at_rest = set(result.envelopes["at_rest"])
    assert at_rest == {int(np.count_nonzero(rest))} and np.count_nonzero(rest) > 100


@pytest.mark.parametrize("n, start", [(1000, 0), (1000, 3), (45, 2)])
def test_sigma_f_between_the_grid_steps_is_the_linear_interpolation(n, start):
    t = np.arange(n) / 1000.0                          # a grid step every 100 steps at 1 kHz
    truth = models.sinusoidal(t)
    rng = np.random.default_rng(5)
    motion = Motion.from_samples(t, truth.position + rng.normal(0, 1e-5, (n, 3)),
                                 quaternion=truth.quaternion(), window=31)
    evaluator = gsfric.Evaluator(gsfric.reference_platform())
    sigma = force_sigma(evaluator, motion, start=start)
    grid = np.flatnonzero((np.arange(n) + start) % 100 == 0)
    grid = np.r_[np.arange(grid[0]), grid, np.arange(grid[-1] + 1, n)] if len(grid) \
        else np.arange(n)
    for i in range(6):
        np.testing.assert_allclose(sigma[:, i], np.interp(np.arange(n), grid, sigma[grid, i]),
                                   rtol=1e-12, atol=1e-12 * sigma.max())
    # at a grid step, one standard deviation of each rate moved by itself, added in quadrature
    k = grid[len(grid) // 2]
    x = state_array(motion.slice(k, k + 1))
    parts = []
    for j, s in enumerate(motion.rate_uncertainty().stacked()[k]):
        up, down = x.copy(), x.copy()
        up[0, 12 + j] += s
        down[0, 12 + j] -= s
        parts.append((evaluator.actuator_forces(up) - evaluator.actuator_forces(down))[0] / 2)
    np.testing.assert_allclose(sigma[k], np.sqrt(np.sum(np.square(parts), axis=0)), rtol=1e-9)
