"""The honest verdict: the noise floor (the user's force noise, a recording at rest, or a
robust estimate; the pose noise through the model), the generic dictionary of out-of-catalog
structure, and the verdict's decision and reason."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from gsfric.cli import main
from gsfric.discovery import Settings, dictionary, discover
from gsfric.discovery.floor import (
    noise_floor,
    pose_noise_forces,
    read_noise_record,
)
from gsfric.discovery.rest import poses_from_columns
from gsfric.discovery.selection import NoiseModel
from gsfric.discovery.verdict import decide
from gsfric.errors import InputError
from gsfric.evaluation.evaluator import Evaluator
from gsfric.io.logs import LogFormat
from gsfric.platform.usable import check_force_sign
from gsfric.signal.noise import ForceNoise, spectral_noise_std
from gsfric.synth import synthesize
from gsfric.trajectory import Motion

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

RATE = 200.0

# -- the floor -----------------------------------------------------------------------------------


def test_spectral_noise_ignores_lines_and_steps_but_not_white_noise():
    rng = np.random.default_rng(3)
    n, sigma = 6000, 0.2
    t = np.arange(n) / RATE
    clean = sigma * rng.normal(size=(n, 2))
    y = clean.copy()
    y[:, 0] += 2.0 * np.sin(2 * np.pi * 50.0 * t) + 1.5 * np.sin(2 * np.pi * 70.0 * t)
    y[:, 1] += 5.0 * np.sign(np.sin(2 * np.pi * 0.3 * t))     # friction-like steps
    estimate = spectral_noise_std(y, 1 / RATE, RATE / 4)
    assert estimate == pytest.approx([sigma, sigma], rel=0.1)
    # a whiter, larger noise reads larger: the estimate follows the noise, not a constant
    assert spectral_noise_std(3 * clean, 1 / RATE, RATE / 4) == pytest.approx(3 * estimate,
                                                                              rel=0.2)


def test_force_noise_takes_one_value_or_six():
    assert ForceNoise.specified(0.1).std == (0.1,) * 6
    assert ForceNoise.specified([1, 2, 3, 4, 5, 6]).std[4] == 5.0
    with pytest.raises(InputError, match="one value or six"):
        ForceNoise.specified([0.1, 0.2])
    with pytest.raises(InputError, match="finite number > 0"):
        ForceNoise.specified([0.1, 0.1, -1, 0.1, 0.1, 0.1])


def test_the_column_maps_toml_carries_the_force_noise(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text('force_noise = 0.05\n[columns]\nt = "time"\n')
    assert LogFormat.from_options(str(path)).force_noise == (0.05,) * 6
    path.write_text('force_noise = [0.05, 0.05]\n')
    with pytest.raises(InputError, match="force_noise"):
        LogFormat.from_options(str(path))


def test_a_noise_record_gives_each_channels_std_in_newtons(tmp_path):
    rng = np.random.default_rng(0)
    std = np.array([0.01, 0.02, 0.03, 0.04, 0.05, 0.06])
    frame = pd.DataFrame(rng.normal(size=(4000, 6)) * std + 100.0,
                         columns=[f"load{i}" for i in range(1, 7)])
    path = tmp_path / "rest.csv"
    frame.to_csv(path, index=False)
    fmt = LogFormat(columns={f"F{i}": f"load{i}" for i in range(1, 7)},
                    units={f"F{i}": "kN" for i in range(1, 7)})
    noise = read_noise_record(path, fmt)
    assert noise.source == "noise record"
    assert np.array(noise.std) == pytest.approx(1e3 * std, rel=0.05)
    with pytest.raises(InputError, match="F1"):
        read_noise_record(path)


def test_a_noise_record_with_poses_must_be_at_rest(tmp_path):
    """Pose columns still to within their noise (10 um) pass; a drift of 2 mm or a turn of
    2 mrad is a move, not a rest (``Settings.record_travel``, ``record_turn``)."""
    rng = np.random.default_rng(1)
    n = 400
    frame = pd.DataFrame({"t": np.arange(n) / 200.0, "x": rng.normal(0, 1e-5, n),
                          "y": 0.0, "z": 0.7 + rng.normal(0, 1e-5, n), "qw": 1.0, "qx": 0.0,
                          "qy": 0.0, "qz": 0.0})
    for i in range(1, 7):
        frame[f"F{i}"] = 40.0 + rng.normal(0, 0.1, n)
    path = tmp_path / "rest.csv"
    frame.to_csv(path, index=False)
    assert np.array(read_noise_record(path).std) == pytest.approx(0.1, rel=0.2)
    moved = frame.assign(x=np.linspace(0, 2e-3, n))
    moved.to_csv(path, index=False)
    with pytest.raises(InputError, match=r"rest.csv: not at rest: the platform moves 0.002 m"):
        read_noise_record(path).check_at_rest(Settings().record_travel, Settings().record_turn)
    half = 1e-3 * np.arange(n) / n           # a turn about z of up to 2 mrad
    frame.assign(qw=np.cos(half), qz=np.sin(half)).to_csv(path, index=False)
    with pytest.raises(InputError, match=r"turns 0.002 rad"):
        read_noise_record(path).check_at_rest(Settings().record_travel, Settings().record_turn)
    # the force channels are what a noise record is for: their absence is said first
    frame.drop(columns="F1").to_csv(path, index=False)
    with pytest.raises(InputError, match=r"rest.csv: no column 'F1': a noise record needs the "
                                         r"force channels F1..F6$"):
        read_noise_record(path)


def test_a_force_noise_must_be_plausible_against_the_forces_spread():
    forces = np.random.default_rng(2).normal(40.0, 3.0, (500, 6))
    limits = Settings().noise_spread
    ForceNoise.specified(0.1).check_plausible(forces, limits)
    ForceNoise.specified(25.0).check_plausible(forces, limits)     # within 10 x the spread
    for value in (1e9, 1e-300):
        with pytest.raises(InputError, match=r"^--force-noise: F1: a force noise of .* N is "
                                             r"implausible .* spread \d\.\d+ N"):
            ForceNoise.specified(value).check_plausible(forces, limits)


def test_the_floor_adds_the_pose_part_in_quadrature():
    floor = noise_floor(ForceNoise.specified(0.3), np.zeros(6), np.full(6, 0.4), "drawn", 1.0)
    assert floor.rms == pytest.approx(0.5)
    assert floor.residual_over_floor == pytest.approx(2.0)
    assert floor.trusted
    assert not noise_floor(None, np.full(6, 0.3), np.zeros(6), "", 1.0).trusted


def test_the_pose_part_grows_with_the_pose_noise():
    """Next to nothing without pose noise, larger on every leg with more of it (over the
    pairs that slide: the adaptive filters chosen differ with the noise, so not in
    proportion), and not estimated without recorded poses."""
    parts = []
    for sigma in (0.0, 1e-5, 4e-5):
        data = synthesize(samples=2000, rate=RATE, noise=0.0, pose_noise=sigma, seed=2)
        frame = data.frame
        motion = Motion.from_samples(frame.t.values, frame[["x", "y", "z"]].values,
                                     quaternion=frame[["qw", "qx", "qy", "qz"]].values)
        rows = slice(100, len(frame) - 100)
        speed = Evaluator(data.model).evaluate(motion).D_dot[rows]
        part, how = pose_noise_forces(data.model, motion, poses_from_columns(frame), rows,
                                      np.abs(speed) > 5e-3, draws=2, n_threads=1)
        assert "draws" in how
        parts.append(part)
    assert np.all(parts[0] < 1e-3 * parts[1])
    assert np.all(parts[1] > 0) and np.all(parts[2] > 1.5 * parts[1])
    none, how = pose_noise_forces(data.model, motion, None, rows, np.abs(speed) > 0, draws=1,
                                  n_threads=1)
    assert not none.any() and "not estimated" in how


# -- the dictionary ------------------------------------------------------------------------------


def _features(n: int = 4000, seed: int = 0) -> dictionary.Features:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    f = rng.uniform(0.2, 1.0, 6)
    phase = rng.uniform(0, 2 * np.pi, 6)
    F = 200 + 50 * np.sin(2 * np.pi * f * t[:, None] + phase)
    D = 1.0 + 0.05 * np.sin(2 * np.pi * f * t[:, None] + phase + 1.0)
    speed = np.gradient(D, t, axis=0)
    position = np.stack([0.02 * np.sin(2 * np.pi * 0.3 * t)] * 3, axis=1)
    return dictionary.Features(t, F, D, speed, position, np.ones((n, 6)), 0.2)


def test_play_is_the_backlash_operator():
    rng = np.random.default_rng(0)
    F = np.cumsum(rng.normal(size=(500, 3)), axis=0)
    width = np.array([0.5, 2.0, 5.0])
    out = dictionary.play(F, width)
    y = F[0].copy()
    for k in range(len(F)):     # the reading moves only when the force leaves its band
        y = np.minimum(np.maximum(y, F[k] - width), F[k] + width)
        assert out[k] == pytest.approx(y)
    assert dictionary.play(F, np.stack([width, 2 * width]))[1] == pytest.approx(
        dictionary.play(F, 2 * width))


def test_the_dictionary_finds_nothing_in_white_noise():
    x = _features()
    residual = 0.2 * np.random.default_rng(1).normal(size=x.F.shape)
    assert dictionary.find(residual, x, Settings()) == []


def test_the_dictionary_describes_a_line_a_coupling_and_a_dead_band():
    x = _features()
    rng = np.random.default_rng(2)
    noise = 0.2 * rng.normal(size=x.F.shape)
    line = noise.copy()
    line[:, [0, 2]] += 0.5 * np.sin(2 * np.pi * 50.0 * x.t)[:, None]
    found = dictionary.find(line, x, Settings())
    assert [s.kind for s in found] == ["line"]
    assert found[0].legs == [1, 3]
    assert found[0].details["lines"][0]["frequency"] == pytest.approx(50.0, abs=0.01)
    assert "50 Hz line of 0.5 N on legs 1, 3 in phase" in found[0].description

    coupled = noise.copy()
    coupled[:, 1] += 0.04 * (x.F[:, 2] - x.F[:, 2].mean())
    found = dictionary.find(coupled, x, Settings())
    assert "coupling" in [s.kind for s in found]
    coupling = next(s for s in found if s.kind == "coupling")
    assert coupling.legs == [2]
    assert "leg 2 reads 4 % of leg 3's force" in coupling.description

    band = noise.copy()
    band[:, 4] += dictionary.play(x.F, 0.8)[:, 4] - x.F[:, 4]
    found = dictionary.find(band, x, Settings())
    memory = next(s for s in found if s.kind == "sensor memory")
    assert memory.legs == [5]
    assert memory.details["memory"][0]["half_width"] == pytest.approx(0.8, rel=0.25)


# -- the decision --------------------------------------------------------------------------------


def _floor(ratio: float, force: ForceNoise | None = None):
    return noise_floor(force, np.full(6, 0.1), np.zeros(6), "", 0.1 * ratio)


def _decide(floor, structures=(), named=()):
    return decide(structures=list(structures), structure_found=False, structure_text="",
                  floor=floor, ratio_limit=Settings().floor_ratio, named=list(named),
                  refit_closes=False, noise=NoiseModel([3] * 6, [0.5] * 6, [0.1] * 6,
                                                       [0.2] * 6))


def test_a_residual_above_a_floor_the_user_gave_is_a_discrepancy():
    spec = ForceNoise.specified(0.1)
    assert _decide(_floor(3.0, spec), named=["stribeck"]).verdict == "unexplained_discrepancy"
    assert _decide(_floor(1.2, spec), named=["stribeck"]).verdict == "explained"


def test_no_discrepancy_above_an_estimated_floor_states_why():
    decision = _decide(_floor(3.0))
    assert decision.verdict == "no_discrepancy"
    assert "3 x the noise floor" in decision.reason and "--force-noise" in decision.reason
    assert "--force-noise" not in _decide(_floor(1.0)).reason


def test_structure_makes_a_named_effect_partial():
    s = dictionary.Unexplained("drift", [2], 0.3, [0, 0.7, 0, 0, 0, 0], 1.5, 1e-9, 0.002, 0.3,
                               "a drift over the record of 0.9 N on leg 2")
    decision = _decide(_floor(1.0), [s], named=["seal_friction"])
    assert decision.verdict == "unexplained_discrepancy"
    assert "a drift over the record of 0.9 N on leg 2" in decision.reason


# -- end to end ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def mains_record():
    """A short record at 200 Hz with 0.1 N of white force noise, 2 um of pose noise and a
    50 Hz line of 0.3 N on load cells 1 and 4."""
    data = synthesize(samples=3000, rate=RATE, noise=0.1, pose_noise=2e-6, seed=5)
    frame = data.frame.copy()
    for leg in (1, 4):
        frame[f"F{leg}"] += 0.3 * np.sin(2 * np.pi * 50.0 * frame.t + 0.4)
    return frame


def _run(frame, **options):
    motion = Motion.from_samples(frame.t.values, frame[["x", "y", "z"]].values,
                                 quaternion=frame[["qw", "qx", "qy", "qz"]].values)
    forces = frame[[f"F{i}" for i in range(1, 7)]].values
    return discover(motion, forces, poses=poses_from_columns(frame), n_bootstrap=10,
                    **options)


def test_a_mains_line_is_unexplained_and_described(mains_record):
    result = _run(mains_record)
    assert result.verdict == "unexplained_discrepancy"
    lines = [s for s in result.structures if s.kind == "line"]
    assert lines and lines[0].legs == [1, 4]
    assert lines[0].details["lines"][0]["frequency"] == pytest.approx(50.0, abs=0.05)
    floor = result.noise.floor
    assert floor.force_source == "estimated"
    # the line does not inflate the floor: it reads the 0.1 N of the load cells
    assert np.sqrt(np.mean(np.square(floor.force))) == pytest.approx(0.1, rel=0.15)


def test_discover_takes_the_force_noise_from_the_command_line(tmp_path, mains_record):
    frame = mains_record.copy()
    for leg in (1, 4):
        frame[f"F{leg}"] -= 0.3 * np.sin(2 * np.pi * 50.0 * frame.t + 0.4)
    path = tmp_path / "measured.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / "out"
    out.mkdir()
    for stale in ("residuals_time.png", "report.html"):     # an earlier run's, of another record
        (out / stale).write_text("old")
    run = CliRunner().invoke(main, ["discover", "--measured", str(path), "--out", str(out),
                                    "--quiet", "--no-plots", "--force-noise", "0.03"])
    assert run.exit_code == 0, run.output
    # --no-plots: the files of the answer, no figure and no 3-D view, nor an earlier run's
    assert sorted(p.name for p in out.iterdir()) == ["platform.toml", "report.md",
                                                     "summary.json"]
    assert "## Plots" not in (out / "report.md").read_text()
    summary = json.loads((out / "summary.json").read_text())
    floor = summary["noise"]["floor"]
    assert floor["force_source"] == "specified" and floor["force"] == [0.03] * 6
    # the residual (0.1 N of noise) is over three times a floor of 0.03 N: a discrepancy
    assert summary["verdict"] == "unexplained_discrepancy"
    assert summary["verdict_decided_by"] == "floor"
    assert "x the noise floor" in summary["verdict_reason"]
    bad = CliRunner().invoke(main, ["discover", "--measured", str(path), "--out", str(out),
                                    "--force-noise", "0.1,x"])
    assert bad.exit_code == 2 and "--force-noise" in bad.output



def test_the_command_line_wins_over_the_record_and_the_column_map(tmp_path):
    from gsfric.discovery.api import _force_noise

    path = tmp_path / "rest.csv"
    rng = np.random.default_rng(1)
    pd.DataFrame(0.07 * rng.normal(size=(2000, 6)),
                 columns=[f"F{i}" for i in range(1, 7)]).to_csv(path, index=False)
    fmt = LogFormat(force_noise=0.5)
    assert _force_noise(0.2, path, fmt).std == (0.2,) * 6
    recorded = _force_noise(None, path, fmt)
    assert recorded.source == "noise record"
    assert np.array(recorded.std) == pytest.approx(np.full(6, 0.07), rel=0.1)
    assert _force_noise(None, None, fmt).std == (0.5,) * 6
    assert _force_noise(None, None, None) is None


def test_forces_of_the_opposite_sign_are_refused_before_any_fit():
    """Load cells read with the opposite sign convention: one line naming the cause, not a
    model that fits them with negative gains and offsets."""
    data = synthesize(samples=1200, noise=0.1, seed=5)
    forces = -data.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()
    with pytest.raises(InputError, match=r"forces: F1..F6 sum to -\d.* the load cells' sign "
                                         r"is the opposite of gsfric's .* negate F1..F6"):
        discover(data.motion, forces)


def test_the_sign_check_leaves_legs_that_carry_no_net_load_alone():
    """Legs that pull against each other (a summed force near zero against their sizes): a
    small summed force of either sign says nothing of the load cells' convention."""
    rng = np.random.default_rng(0)
    carried = 40.0 + rng.normal(0.0, 5.0, (500, 6))
    with pytest.raises(InputError, match="negate F1..F6"):
        check_force_sign(-carried, carried)
    balanced = np.tile([30.0, -30.0, 30.0, -30.0, 30.0, -29.0], (500, 1))
    check_force_sign(-balanced + rng.normal(0.0, 1.0, (500, 6)), balanced)
