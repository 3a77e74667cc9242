"""A real rig's log read right: dropout rows, counter resets, time units, repeated keys, the
controller's frame, jittered stamps, the log's own rates, and data that are not the platform's.

The shipped controller log (tests/data/controller_log.csv, written by
tests/data/make_controller_log.py) is read, simulated and discovered through the CLI as the
tutorial notebooks/real_log.ipynb does.
"""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from helpers import trajectory_frame

from gsfric import models
from gsfric.cli import main
from gsfric.errors import DataWarning, GsfricWarning, InputError
from gsfric.io.logs import LogFormat
from gsfric.io.readers import read_measured, read_trajectory
from gsfric.io.tables import read_table, write_table
from gsfric.signal.local import local_polynomial_derivatives
from gsfric.signal.savgol import savgol_derivatives
from gsfric.simulate.run import simulate_file
from gsfric.synth import synthesize
from gsfric.trajectory import Motion

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

DATA = Path(__file__).resolve().parent / "data"
LOG, LOG_FORMAT = DATA / "controller_log.csv", DATA / "controller_log.toml"


def _cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def _frame(n: int = 300) -> pd.DataFrame:
    return trajectory_frame(n)


def _quiet(function, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GsfricWarning)
        return function(*args, **kwargs)


# -- dropout rows and counters ------------------------------------------------------------------


def test_a_trailing_zero_row_is_left_out_and_changes_no_other_row(tmp_path):
    clean = _frame()
    counts = 2**32 - 1_000_000 + np.round(clean["t"].to_numpy() * 1e6).astype(np.int64)
    clean["t"] = (counts % 2**32).astype(np.uint32)
    bad = pd.concat([clean, pd.DataFrame({c: [0] for c in clean.columns}).astype(
        clean.dtypes.to_dict())], ignore_index=True)
    write_table(clean, tmp_path / "clean.csv")
    write_table(bad, tmp_path / "bad.csv")
    fmt = "t=us"
    outputs = {}
    for name in ("clean", "bad"):
        out = tmp_path / f"{name}_out.csv"
        result = _cli("simulate", "--trajectory", tmp_path / f"{name}.csv", "--units", fmt,
                      "--out", out)
        assert result.exit_code == 0, result.output
        outputs[name] = (read_table(out), result.stderr)
    assert "row 301: every value is 0 and the time stops (a dropout row): left out" \
        in outputs["bad"][1]
    assert "dropout" not in outputs["clean"][1]
    pd.testing.assert_frame_equal(outputs["clean"][0], outputs["bad"][0], check_exact=True)
    with pytest.warns(GsfricWarning) as caught:
        motion = read_trajectory(tmp_path / "bad.csv", log_format=LogFormat(units={"t": "us"}))
    assert len(motion) == 300
    dropouts = [w for w in caught if issubclass(w.category, DataWarning)]
    assert [str(w.message).split(": ", 1)[1] for w in dropouts] == [
        "row 301: every value is 0 and the time stops (a dropout row): left out"]
    assert any("wraps around" in str(w.message) for w in caught)      # the counter's wrap
    # zeros at an advancing time are a pose (the home pose of a controller's frame): kept
    kept = pd.DataFrame({"t": np.arange(60) / 100.0, "x": 0.0, "y": 0.0, "z": 0.0,
                         "roll": 0.0, "pitch": 0.0, "yaw": 0.0})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read = read_trajectory(_write(tmp_path, kept, "home.csv"),
                               log_format=LogFormat(offset={"z": 0.7}))
    assert len(read) == 60 and not [w for w in caught if w.category is DataWarning]


def test_a_dropout_row_inside_the_file_keeps_the_rows_of_later_messages(tmp_path):
    frame = _frame(60)
    frame.loc[20, frame.columns] = 0.0
    frame.loc[40, "t"] = frame.loc[39, "t"]
    write_table(frame, tmp_path / "log.csv")
    with pytest.warns(DataWarning, match=r"row 21: every value is 0"), \
            pytest.raises(InputError, match=r"row 41: duplicate time .* \(same as row 40\)"):
        read_trajectory(tmp_path / "log.csv")
    with pytest.warns(DataWarning), \
            pytest.raises(InputError, match=r"row 41: duplicate time .* \(same as row 40\)"):
        list(_quiet_iter(tmp_path / "log.csv"))


def _quiet_iter(path):
    from gsfric.simulate.differentiate import iter_motions
    return iter_motions(path, chunk=25, window=7)


def test_a_counter_reset_is_told_apart_from_a_wrap(tmp_path):
    frame = _frame(100)
    counts = 3_000_000_000 + np.arange(100) * 10_000
    counts[60:] = 40 + np.arange(40) * 10_000             # a reboot: restarts near zero
    frame["t"] = counts.astype(np.uint32)
    write_table(frame, tmp_path / "log.csv")
    with pytest.raises(InputError) as caught:
        read_trajectory(tmp_path / "log.csv", log_format=LogFormat(units={"t": "us"}))
    message = str(caught.value)
    assert "row 61:" in message and "drops from 3000590000 to 40, a reset" in message
    assert "not a wrap at 4294967296" in message and "split the log at row 61" in message


def test_time_in_microseconds_declared_as_seconds_names_us(tmp_path):
    frame = _frame()
    frame["t"] = np.round(frame["t"] * 1e6).astype(np.int64)
    write_table(frame, tmp_path / "log.csv")
    with pytest.raises(InputError, match=r"time column 't': median time step 1e\+04 s, a "
                                         r"sampling rate of 0.0001 Hz, .* -> looks like us; "
                                         r"declare t=us"):
        read_trajectory(tmp_path / "log.csv")
    result = _cli("simulate", "--trajectory", tmp_path / "log.csv", "--out", tmp_path / "o.csv")
    assert result.exit_code == 2 and "looks like us" in result.stderr
    assert not (tmp_path / "o.csv").exists()


# -- repeated keys ----------------------------------------------------------------------------


def test_a_repeated_key_is_an_error_naming_it(tmp_path):
    with pytest.raises(InputError, match=r"--units: 'x' given twice \('mm' and 'm'\)"):
        LogFormat.from_options(units="x=mm,y=mm,x=m")
    with pytest.raises(InputError, match=r"--column-map: 't' given twice"):
        LogFormat.from_options(column_map="t=a,t=b")
    toml = tmp_path / "f.toml"
    toml.write_text('[units]\nx = "mm"\ny = "mm"\nx = "m"\n')
    with pytest.raises(InputError, match=r"f.toml: line 4: key 'x' given twice"):
        LogFormat.from_toml(toml)
    toml.write_text('[units]\nx = "mm"\n')
    with pytest.raises(InputError, match=r"--units: 'x' given twice \(also in .*f.toml\)"):
        LogFormat.from_options(column_map=str(toml), units="x=m")
    write_table(_frame(), tmp_path / "log.csv")
    result = _cli("simulate", "--trajectory", tmp_path / "log.csv", "--units", "x=mm,x=m",
                  "--out", tmp_path / "o.csv")
    assert result.exit_code == 2 and "'x' given twice" in result.stderr


# -- the controller's frame -------------------------------------------------------------------


def test_axes_and_offset_map_the_controllers_frame_onto_the_platforms(tmp_path):
    frame = _frame()
    motion = _quiet(read_trajectory, _write(tmp_path, frame, "platform.csv"))
    flip = np.diag([1.0, -1.0, -1.0])
    rotation = models.sinusoidal(frame["t"].to_numpy()).rotation
    log = frame[["t"]].copy()
    log[["x", "y", "z"]] = (frame[["x", "y", "z"]].to_numpy() - [0.01, 0.0, 0.7]) @ flip
    from gsfric.signal.rotations import quaternion_from_rotation
    log[["qw", "qx", "qy", "qz"]] = quaternion_from_rotation(flip @ rotation @ flip)
    fmt = LogFormat(axes="x,-y,-z", offset={"x": 0.01, "z": 0.7})
    mapped = _quiet(read_trajectory, _write(tmp_path, log, "log.csv"), log_format=fmt)
    np.testing.assert_allclose(mapped.position, motion.position, atol=1e-12)
    np.testing.assert_allclose(mapped.rotation, motion.rotation, atol=1e-12)
    np.testing.assert_allclose(mapped.omega, motion.omega, atol=1e-9)
    # a yaw offset turns the positions and the orientation about z
    turned = _quiet(read_trajectory, _write(tmp_path, frame, "p.csv"),
                    log_format=LogFormat(offset={"yaw": np.pi / 2}))
    np.testing.assert_allclose(turned.position[:, 0], -motion.position[:, 1], atol=1e-12)
    np.testing.assert_allclose(turned.rotation[:, 0], -motion.rotation[:, 1], atol=1e-12)


def test_bad_axes_and_offsets_are_one_line_errors():
    with pytest.raises(InputError, match="axes: the log's axis 'x' is used twice"):
        LogFormat(axes="x,-x,z")
    with pytest.raises(InputError, match="axes: expected three signed axes"):
        LogFormat(axes="x,y")
    with pytest.raises(InputError, match=r"offset: unknown key 'heave'"):
        LogFormat(offset={"heave": 1.0})
    with pytest.raises(InputError, match=r"offset.z: expected a finite number"):
        LogFormat.from_mapping({"offset": {"z": "high"}})


def _write(folder, frame, name):
    write_table(frame, folder / name)
    return folder / name


# -- differentiation --------------------------------------------------------------------------


def test_jittered_stamps_honour_the_window_and_say_so():
    rng = np.random.default_rng(4)
    n, step = 400, 0.01
    t = np.arange(n) * step + rng.uniform(-0.0015, 0.0015, n) * step
    truth = models.sinusoidal(t)
    # poses with 20 um and 1e-5 of noise: the stamps' 0.3 % error moves them by less, and
    # the even grid is kept (gsfric.signal.smoothing)
    noisy = truth.position + rng.normal(0.0, 2e-5, truth.position.shape)
    q = truth.quaternion() + rng.normal(0.0, 1e-5, (n, 4))
    motion = Motion.from_samples(t, noisy, quaternion=q, window=21)
    how = motion.differentiation()
    assert how.method == "savgol" and how.window == 21 and 0.002 < how.jitter < 0.003
    assert "window 21" in how.describe() and "jitter taken as evenly spaced" in how.describe()
    inner = slice(20, -20)
    scale = np.abs(truth.acceleration[inner]).max()
    assert np.abs(motion.acceleration - truth.acceleration)[inner].max() < 0.05 * scale
    # exact poses at those stamps: the stamps are the sampling instants, and are used
    exact = Motion.from_samples(t, truth.position, quaternion=truth.quaternion(), window=21)
    assert exact.differentiation().method == "local polynomial"
    # stamps far from even: the window is honoured by local fits on the stamps themselves
    t = np.sort(rng.uniform(0.0, 4.0, n))
    truth = models.sinusoidal(t)
    motion = Motion.from_samples(t, truth.position, quaternion=truth.quaternion(), window=31)
    assert motion.differentiation().method == "local polynomial"
    assert np.abs(motion.velocity - truth.velocity)[inner].max() \
        < 0.02 * np.abs(truth.velocity).max()


def test_local_fits_on_even_stamps_are_the_savitzky_golay_filter():
    rng = np.random.default_rng(1)
    y = rng.standard_normal((200, 3)).cumsum(axis=0)
    t = 0.5 + np.arange(200) * 0.002
    for got, want in zip(local_polynomial_derivatives(t, y, 15, 4),
                         savgol_derivatives(y, 15, 4, 0.002)):
        np.testing.assert_allclose(got, want, rtol=1e-7, atol=1e-7 * np.abs(want).max())


def test_rates_from_the_logs_columns(tmp_path):
    frame = _frame()
    truth = models.sinusoidal(frame["t"].to_numpy())
    frame[["v1", "v2", "v3"]] = truth.velocity * 1e3
    path = _write(tmp_path, frame, "log.csv")
    fmt = LogFormat(columns={"vx": "v1", "vy": "v2", "vz": "v3"},
                    units={"vx": "mm/s", "vy": "mm/s", "vz": "mm/s"})
    motion = read_trajectory(path, log_format=fmt)
    np.testing.assert_allclose(motion.velocity, truth.velocity, rtol=1e-12, atol=1e-15)
    assert motion.differentiation().rates == ("velocity",)
    inner = slice(30, -30)
    assert np.abs(motion.acceleration - truth.acceleration)[inner].max() \
        < 0.01 * np.abs(truth.acceleration).max()
    with pytest.raises(InputError, match=r"'vz' missing \(columns vx, vy, vz go together\)"):
        LogFormat(columns={"vx": "v1", "vy": "v2"})
    with pytest.raises(InputError, match="read with the file whole: give a --chunk"):
        list(_chunks(path, fmt))


def _chunks(path, fmt):
    from gsfric.simulate.differentiate import iter_motions
    return iter_motions(path, chunk=100, window=11, log_format=fmt)


# -- data that are not the platform's ---------------------------------------------------------


def test_poses_mostly_outside_the_stroke_fail_before_any_physics(tmp_path):
    frame = _frame()
    frame["z"] -= 4.0
    path = _write(tmp_path, frame, "far.csv")
    result = _cli("simulate", "--trajectory", path, "--out", tmp_path / "o.csv")
    assert result.exit_code == 2, result.output
    message = result.stderr.strip().splitlines()[-1]
    assert "300 of 300 steps have a leg outside the stroke: leg lengths" in message
    assert "vs stroke 0.5-1.1 m; heave mean -3.3 m vs home height 0.748 m" in message
    assert "pose offset" in message and "--platform" in message
    assert not (tmp_path / "o.csv").exists()


def test_forces_in_newtons_declared_as_kilonewtons_are_an_error(tmp_path):
    measured = tmp_path / "m.csv"
    assert _cli("synth", "--out", measured, "--samples", "400", "--rate", "100").exit_code == 0
    result = _cli("discover", "--measured", measured, "--units",
                  ",".join(f"F{i}=kN" for i in range(1, 7)), "--out", tmp_path / "d")
    assert result.exit_code == 2, result.output
    assert "times the model's along the same poses" in result.stderr
    assert "forces in N declared as kN?" in result.stderr
    motion, forces, _ = read_measured(measured)
    reference = models.reference_platform()
    models.check_measured_forces(reference, motion, forces)              # in N: fine
    with pytest.raises(InputError, match="forces in kN read as N"):
        models.check_measured_forces(reference, motion, forces / 1000.0)


def test_the_unit_check_weighs_the_forces_against_the_models_own_load():
    """A light platform on heavy legs: the legs' own weight is most of what the actuators
    carry. Its model's forces pass the unit check (the platform and payload weigh a
    hundredth of that load); the same forces in kN read as N do not."""
    light = models.reference_platform().with_body(mass=0.1, payload_mass=0.0)
    data = synthesize(light, samples=1000, rate=200.0, seed=1)
    forces = data.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()
    weight = light.gravity * (light.platform.mass + light.platform.payload_mass)
    assert np.mean(np.sum(np.abs(forces), axis=1)) > 30 * weight
    models.check_measured_forces(light, data.motion, forces)
    with pytest.raises(InputError, match="forces in kN read as N"):
        models.check_measured_forces(light, data.motion, forces / 1000.0)


def test_the_unit_and_sign_checks_follow_the_records_own_poses():
    """Base joints on a plinth 0.69 m up, and a platform file without a stroke: no home pose
    is known (the reference's height would lay the legs flat), the record's poses are. Its
    forces pass; negated, they are refused as of the wrong sign."""
    reference = models.reference_platform()
    raised = reference.with_geometry(base_joints=reference.geometry.base_joints
                                     + [0.0, 0.0, 0.69])
    data = synthesize(raised, samples=600, rate=200.0, seed=2)
    forces = data.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()
    loose = raised.with_geometry(stroke=None)
    models.check_measured_forces(loose, data.motion, forces)
    with pytest.raises(InputError, match=r"negate F1\.\.F6"):
        models.check_measured_forces(loose, data.motion, -forces)


# -- the shipped controller log: the tutorial's CLI -------------------------------------------


def test_the_controller_log_reads_simulates_and_discovers(tmp_path):
    out = tmp_path / "forces.csv"
    result = _cli("simulate", "--trajectory", LOG, "--column-map", LOG_FORMAT, "--out", out)
    assert result.exit_code == 0, result.output
    assert "row 2001: every value is 0 and the time stops (a dropout row): left out" \
        in result.stderr
    assert "row 752: time counter 'Timestamp [us]' wraps around" in result.stderr
    assert "velocity from the log's columns" in result.stdout
    forces = read_table(out)
    assert len(forces) == 2000 and not forces["flag"].any()
    folder = tmp_path / "discover"
    result = _cli("discover", "--measured", LOG, "--column-map", LOG_FORMAT, "--out", folder,
                  "--quiet", "--no-plots")
    assert result.exit_code == 0, result.output
    summary = json.loads((folder / "summary.json").read_text())
    names = [e["name"] for e in summary["effects"]]
    assert names == ["seal_friction"]
    assert summary["effects"][0]["parameters"]["force"] == pytest.approx(20.0, rel=0.05)
    assert any(n.startswith("differentiation: savgol") for n in summary["notes"])


def test_discover_names_no_effect_from_poses_outside_the_stroke(tmp_path):
    measured = tmp_path / "m.csv"
    assert _cli("synth", "--out", measured, "--samples", "300", "--rate", "100").exit_code == 0
    frame = read_table(measured)
    frame["z"] += 2.0
    write_table(frame, measured)
    result = _cli("discover", "--measured", measured, "--out", tmp_path / "d")
    assert result.exit_code == 2, result.output
    assert "300 of 300 steps have a leg outside the stroke" in result.stderr
    assert f"gsfric: error: {measured}: 300 of 300 steps" in result.stderr
    assert "(a z offset of -1.9" in result.stderr
    assert not (tmp_path / "d" / "summary.json").exists()


def test_mostly_flagged_steps_and_implausible_speeds_are_data_errors():
    from gsfric.evaluation.flags import FLAG_STROKE, check_flagged
    from gsfric.platform.usable import check_poses
    platform = models.reference_platform()
    counts = {FLAG_STROKE: 51}
    check_flagged(platform, counts, 50, 100)
    with pytest.raises(InputError, match=r"log.csv: 51 of 100 steps are flagged by the model, "
                                         r"51 of them FLAG_STROKE .*geometry.stroke = \[0.5"):
        check_flagged(platform, counts, 51, 100, "log.csv")
    t = np.arange(300) / 100.0
    motion = models.sinusoidal(t)
    check_poses(platform, motion.position, motion.rotation, t)
    with pytest.raises(InputError, match=r"the platform moves at .* m/s \(median over the "
                                         r"steps\), implausible for a stroke of 0.6 m"):
        check_poses(platform, motion.position, motion.rotation, t / 1000.0)


def test_a_gap_in_the_times_is_named_and_a_mostly_missing_record_refused(tmp_path):
    frame = _frame(400)
    late = frame.copy()
    late.loc[200:, "t"] += 1.0                       # 1 s lost after row 200 of a 4 s record
    write_table(late, tmp_path / "gap.csv")
    with pytest.warns(DataWarning, match=r"gap\.csv: t: 1 gap\(s\).*about 100 samples\), "
                                         r"the first after row 200"):
        simulate_file(tmp_path / "gap.csv", tmp_path / "gap_out.csv", progress=False)
    assert (tmp_path / "gap_out.csv").is_file()
    late.loc[200:, "t"] += 10.0                      # now 11 s lost against 4 s recorded
    write_table(late, tmp_path / "gone.csv")
    result = _cli("simulate", "--trajectory", tmp_path / "gone.csv", "--out",
                  tmp_path / "gone_out.csv")
    assert result.exit_code == 2
    assert "record is mostly missing" in result.output and "\n" not in result.output.strip()
    assert not (tmp_path / "gone_out.csv").exists()


def _platform_file(path: Path, platform) -> Path:
    platform.to_toml(path)
    return path


@pytest.mark.parametrize("case, named", [
    ("joint_coulomb", r"FLAG_COUPLING \(coupled friction solve not converged\): "
                      r"friction.joint_coulomb = 5 "),
    ("mass", r"FLAG_NONFINITE \(non-finite value\): platform key platform.mass = 1e\+200"),
    ("axes", r"FLAG_COUPLING .*geometry.universal_axes: the first axis of the universal joints "
             r"of legs 1, 2, 3, 4, 5, 6 is within 13 degrees"),
])
def test_a_platform_that_flags_every_step_names_the_flag_and_its_key(tmp_path, case, named):
    """The poses are this platform's; its own numbers make every step flagged: the message
    names the flag and the platform key, not the poses."""
    import dataclasses

    from gsfric.platform.usable import home_height
    reference = models.reference_platform()
    g = reference.geometry
    if case == "joint_coulomb":
        platform = reference.with_friction(joint_coulomb=5.0)
    elif case == "mass":
        platform = dataclasses.replace(reference, platform=dataclasses.replace(
            reference.platform, mass=1e200))
    else:
        legs = np.asarray(g.platform_joints) + [0.0, 0.0, home_height(reference)] \
            - np.asarray(g.base_joints)
        platform = dataclasses.replace(reference, geometry=dataclasses.replace(
            g, universal_axes=legs / np.linalg.norm(legs, axis=1, keepdims=True)))
    write_table(_frame(), tmp_path / "traj.csv")
    result = _cli("simulate", "--trajectory", tmp_path / "traj.csv", "--platform",
                  _platform_file(tmp_path / "p.toml", platform), "--out", tmp_path / "o.csv")
    assert result.exit_code == 2, result.output
    lines = [k for k in result.stderr.splitlines() if k.startswith("gsfric: error:")]
    assert len(lines) == 1
    assert re.search(r"traj.csv: \d+ of 300 steps are flagged by the model, \d+ of them", lines[0])
    assert re.search(named, lines[0]), lines[0]
    assert "pose offset" not in lines[0]
    assert not (tmp_path / "o.csv").exists()
