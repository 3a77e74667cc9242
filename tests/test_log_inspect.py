"""`gsfric log inspect`: the proposed log format reads a controller's log as the same motion
given in SI (the forces agree), what it assumes is named with its evidence, and bad input
gets one line naming the column or row.

The log is made like a real controller's: 100 Hz, a uint32 microsecond counter that wraps,
stamps jittering by 1.1 % of the step, rests, a z-down frame whose heave is zero at home,
its own names and units (mm, degrees, mm/s, mm/s^2, deg/s), its own velocity, acceleration
and angular rate columns, and columns gsfric does not read.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from gsfric import models
from gsfric.cli import main
from gsfric.errors import InputError
from gsfric.io.logs import LogFormat
from gsfric.io.tables import read_table
from gsfric.loginspect import inspect_log
from gsfric.loginspect.names import role
from gsfric.platform.rig import Rig
from gsfric.platform.usable import home_height
from gsfric.signal.rotations import rpy_from_rotation
from gsfric.trajectory import Motion

RATE, JITTER = 100.0, 0.011
FLIP = np.diag([1.0, -1.0, -1.0])           # the controller's axes (z down) in the platform's
SCHEDULE = (("rest", 1.5), ("up", 0.8), ("move", 4.0), ("down", 0.8), ("rest", 2.0),
            ("up", 0.8), ("move", 3.0), ("down", 0.8), ("rest", 1.0))
"""The motion's phases and their lengths, s: the sinusoidal motion's clock runs at speed 0 in
a rest, 1 in a move, and speeds up and slows down smoothly (minimum-jerk) in between."""


def _clock(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The motion's clock tau(t) and its first two derivatives, in closed form."""
    tau, rate, change = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
    start, before = 0.0, 0.0
    for kind, length in SCHEDULE:
        inside = (t >= start) & (t < start + length)
        u = (t[inside] - start) / length
        if kind == "move":
            tau[inside], rate[inside] = before + (t[inside] - start), 1.0
        elif kind in ("up", "down"):
            ramp = 10 * u**3 - 15 * u**4 + 6 * u**5
            area = length * (2.5 * u**4 - 3 * u**5 + u**6)
            slope = (30 * u**2 - 60 * u**3 + 30 * u**4) / length
            up = kind == "up"
            tau[inside] = before + (area if up else length * u - area)
            rate[inside] = ramp if up else 1 - ramp
            change[inside] = slope if up else -slope
        else:
            tau[inside] = before
        before += {"move": length, "up": length / 2, "down": length / 2}.get(kind, 0.0)
        start += length
    return tau, rate, change


def _motion(t: np.ndarray) -> Motion:
    """The sinusoidal reference motion around the platform's home, run on ``_clock``."""
    tau, rate, change = _clock(t)
    home = home_height(models.reference_platform())
    s = models.sinusoidal(tau, centre=(0.0, 0.0, home))
    r, c = rate[:, None], change[:, None]
    return Motion.from_arrays(t, s.position, s.rotation, s.velocity * r, s.omega * r,
                              s.acceleration * r**2 + s.velocity * c,
                              s.alpha * r**2 + s.omega * c)


def real_like_log(seed: int = 49) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The controller's log and the same motion in SI (t from the first row, base frame, with
    the exact velocity and acceleration)."""
    rng = np.random.default_rng(seed)
    n = int(sum(length for _, length in SCHEDULE) * RATE)
    t = np.arange(n) / RATE + rng.uniform(-0.5, 0.5, n) * JITTER / RATE
    micros = np.round((t - t[0]) * 1e6).astype(np.int64)
    t = micros / 1e6
    motion = _motion(t)
    home = home_height(models.reference_platform())
    log = pd.DataFrame({"Mode": np.full(n, 3),
                        "Time stamp [us]": ((2**32 - 6_000_000 + micros) % 2**32
                                            ).astype(np.uint32)})
    log_position = (motion.position - [0.0, 0.0, home]) @ FLIP
    angles = np.degrees(rpy_from_rotation(FLIP @ motion.rotation @ FLIP))
    for k, name in enumerate(("Surge", "Sway", "Heave")):
        log[f"{name} [mm]"] = np.round(1e3 * log_position[:, k], 4)
        log[f"{name} vel [mm/s]"] = np.round(1e3 * (motion.velocity @ FLIP)[:, k], 3)
        log[f"{name} acc [mm/s^2]"] = np.round(1e3 * (motion.acceleration @ FLIP)[:, k], 2)
    for k, name in enumerate(("Roll", "Pitch", "Yaw")):
        log[f"{name} [deg]"] = np.round(angles[:, k], 5)
        log[f"{name} rate [deg/s]"] = np.round(np.degrees((motion.omega @ FLIP)[:, k]), 4)
    log["Oil temp [C]"] = 41.0 + 0.01 * np.arange(n) / RATE
    log["Valve cmd"] = rng.normal(0.0, 1.0, n)
    si = pd.DataFrame({"t": t})
    si[["x", "y", "z"]] = motion.position
    si[["qw", "qx", "qy", "qz"]] = motion.quaternion()
    si[["vx", "vy", "vz"]] = motion.velocity
    si[["ax", "ay", "az"]] = motion.acceleration
    si[["omega_x", "omega_y", "omega_z"]] = motion.omega
    return log, si


def _cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def test_the_proposed_format_reads_the_log_as_the_same_motion_in_si(tmp_path):
    log, si = real_like_log()
    log.to_csv(tmp_path / "log.csv", index=False)
    si.to_csv(tmp_path / "si.csv", index=False)
    assert _cli("platform", "--template", "--out", tmp_path / "rig.toml").exit_code == 0
    result = _cli("log", "inspect", tmp_path / "log.csv", "--platform", tmp_path / "rig.toml",
                  "--out", tmp_path / "found")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert any(line.startswith("wrap: the counter wraps at 4294967296") for line in lines)
    assert any(line.startswith("frame: axes x,-y,-z") for line in lines)
    fmt = LogFormat.from_toml(tmp_path / "found" / "log_format.toml")
    assert set(fmt.rates) == {"velocity", "acceleration", "omega"}   # the log's own, checked
    outputs = {}
    rates = ",".join(f"{k}={k}" for k in ("vx", "vy", "vz", "ax", "ay", "az", "omega_x",
                                          "omega_y", "omega_z"))
    for name, options in (("log", ("--column-map", tmp_path / "found" / "log_format.toml")),
                          ("si", ("--column-map", rates))):
        out = tmp_path / f"{name}_forces.csv"
        run = _cli("simulate", "--trajectory", tmp_path / f"{name}.csv", "--platform",
                   tmp_path / "rig.toml", "--out", out, *options)
        assert run.exit_code == 0, run.output
        outputs[name] = read_table(out)[[f"F{i}" for i in range(1, 7)]].to_numpy()
    peak = np.abs(outputs["si"]).max()
    gap = np.abs(outputs["log"] - outputs["si"])
    # the angular acceleration is differentiated from the angular rates, which the log rounds
    # to 1e-4 deg/s: where a rest begins or ends that moves a few steps' forces by up to 0.5 %;
    # elsewhere they agree to rounding (XYZ angles for xyz, or the home 2 mm off, move the
    # 99th percentile above 2e-4 of the peak)
    assert np.percentile(gap, 99) < 1e-4 * peak and gap.max() < 5e-3 * peak


def test_each_assumption_names_its_evidence_and_the_rest_is_found(tmp_path):
    log, _ = real_like_log()
    log.to_csv(tmp_path / "log.csv", index=False)
    found = inspect_log(tmp_path / "log.csv", platform=models.reference_platform())
    fmt = found.log_format
    assert fmt.columns["t"] == "Time stamp [us]" and fmt.units["t"] == "us"
    assert fmt.wrap == 2**32 and fmt.axes == ("x", "-y", "-z") and fmt.angles == "xyz"
    assert fmt.units["x"] == "mm" and fmt.units["roll"] == "deg"
    assert fmt.units["vx"] == "mm/s" and fmt.units["ax"] == "mm/s^2"
    assert fmt.units["omega_x"] == "deg/s"
    assert fmt.offset["z"] == pytest.approx(home_height(models.reference_platform()), abs=1e-4)
    assert set(found.ignored) == {"Mode", "Oil temp [C]", "Valve cmd"}
    # the longest rest: the 2 s in the middle, widened by the ends of the ramps around it
    # whose speed is below REST_SHARE of the log's
    start = round(sum(length for _, length in SCHEDULE[:4]) * RATE)
    stop = start + round(SCHEDULE[4][1] * RATE)
    assert found.rest is not None
    first, last = found.rest.rows[0] - 1, found.rest.rows[1]
    assert start - 0.15 * RATE <= first <= start and stop <= last <= stop + 0.15 * RATE
    lines = found.lines()
    assert all(line.count("(") >= 1 and line.endswith(")") for line in lines)
    topics = [line.split(":")[0] for line in lines]
    for topic in ("time", "rate", "wrap", "position", "orientation", "angles", "velocity",
                  "acceleration", "omega", "frame", "rest", "home", "workspace", "stroke"):
        assert topic in topics, topic
    jitter = next(line for line in lines if line.startswith("rate:"))
    assert "jitter by up to 1.1 %" in jitter


def test_the_rig_template_holds_the_motion_on_a_rig_too_short_for_it(tmp_path):
    log, _ = real_like_log()
    log.to_csv(tmp_path / "log.csv", index=False)
    rig = Rig.from_platform(models.reference_platform())
    short = Rig(**{**rig.__dict__, "stroke": (0.7, 0.8)})
    found = inspect_log(tmp_path / "log.csv", rig=short)
    proposed = found.rig.platform()
    lo, hi = proposed.geometry.stroke
    p = found.log_format.frame.position(
        log[["Surge [mm]", "Sway [mm]", "Heave [mm]"]].to_numpy() / 1e3, "xyz")
    assert p[:, 2].min() > 0.5                      # heave put at the rig's home
    assert lo <= found.legs[0] and found.legs[1] <= hi and (lo, hi) != (0.7, 0.8)
    text = found.rig_toml()
    (tmp_path / "rig.toml").write_text(text)
    assert Rig.from_toml(tmp_path / "rig.toml").stroke == (lo, hi)


def test_rate_columns_that_are_not_the_poses_derivatives_are_left_unmapped(tmp_path):
    log, _ = real_like_log()
    log["Surge vel [mm/s]"], log["Sway vel [mm/s]"] = log["Sway vel [mm/s]"].to_numpy(), \
        log["Surge vel [mm/s]"].to_numpy()
    for name in ("Surge", "Sway", "Heave"):                   # m/s^2 under a mm/s^2 name
        log[f"{name} acc [mm/s^2]"] = log[f"{name} acc [mm/s^2]"] / 1e3
    log.to_csv(tmp_path / "log.csv", index=False)
    found = inspect_log(tmp_path / "log.csv", platform=models.reference_platform())
    assert "velocity" not in found.log_format.rates
    assert found.log_format.columns["az"] == "Heave acc [mm/s^2]"
    assert found.log_format.units.get("az", "m/s^2") == "m/s^2"         # SI: not listed
    velocity = next(line for line in found.lines() if line.startswith("velocity:"))
    assert "not mapped" in velocity and "correlation" in velocity
    acceleration = next(line for line in found.lines() if line.startswith("acceleration:"))
    assert "the names say mm/s^2" in acceleration


@pytest.mark.parametrize("scale, unit, angle_scale, angle_unit",
                         [(1e3, "mm", 180 / np.pi, "deg"), (1.0, "m", 1.0, "rad")])
def test_units_without_names_come_from_the_values(tmp_path, scale, unit, angle_scale,
                                                  angle_unit):
    _, si = real_like_log()
    turned = models.sinusoidal(si["t"].to_numpy(), amplitude=(0.05, 0.05, 0.04, 0.3, 0.2, 0.2))
    angles = rpy_from_rotation(turned.rotation)          # up to 17 deg: beyond 2 pi in deg
    frame = pd.DataFrame({"time": si["t"], "x": si["x"] * scale, "y": si["y"] * scale,
                          "z": si["z"] * scale})
    for k, name in enumerate(("roll", "pitch", "yaw")):
        frame[name] = angles[:, k] * angle_scale
    frame.to_csv(tmp_path / "log.csv", index=False)
    found = inspect_log(tmp_path / "log.csv")
    assert found.log_format.units.get("x", "m") == unit
    assert found.log_format.units.get("roll", "rad") == angle_unit
    assert found.log_format.axes == ("x", "y", "z") and not found.log_format.offset
    assert found.log_format.units.get("t", "s") == "s"


@pytest.mark.parametrize("content, message", [
    ("", "file is empty"),
    ("t,x,y,z,roll,pitch,yaw\n", "no data rows"),
    ("a,b\nfoo,bar\nbaz,qux\n", "no numeric column"),
    ("x,y,z,roll,pitch,yaw\n" + "1,2,3,0.1,0.2,0.3\n" * 30, "no time-like column"),
    ("t,x,y,z,roll,pitch,yaw\n" + "".join(f"{k},1,2,3,0,0,0\n" for k in range(5)),
     "5 data rows; at least 20"),
    ("t,x,y,z,roll,pitch,yaw\n" + "".join(f"{3_000_000_000 + 10_000 * k},1,2,3,0,0,0\n"
                                           for k in range(30))
     + "".join(f"{40 + 10_000 * k},1,2,3,0,0,0\n" for k in range(30)),
     "row 31: column 't' goes from 3000290000 to 40"),
    ("time,x,y,z,roll,pitch,yaw\n" + "".join(f"{'' if k == 4 else k / 100},1,2,3,0,0,0\n"
                                              for k in range(30)),
     "row 5: column 'time' is empty or NaN"),
    ("time,x,y,z,roll,pitch,yaw\n0,1,2,oops,0.1,0.2,0.3\n"
     + "".join(f"{k / 100},1,2,3,0.1,0.2,0.3\n" for k in range(1, 60)),
     "row 1: column 'z' holds 'oops', not a number"),
    ("time,x,y,roll,pitch,yaw\n" + "".join(f"{k / 100},1,2,0.1,0.2,0.3\n" for k in range(30)),
     "no position column for z"),
])
def test_bad_input_gets_one_line_naming_the_column_or_row_and_writes_nothing(
        tmp_path, content, message):
    (tmp_path / "log.csv").write_text(content)
    result = _cli("log", "inspect", tmp_path / "log.csv", "--out", tmp_path / "found")
    assert result.exit_code == 2
    assert message in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "found").exists()


def test_a_platform_where_a_rig_is_asked_for_and_joints_no_rig_has_say_so(tmp_path):
    """``--rig`` given a platform file says to give it with --platform; a platform whose
    joints are not three pairs on two circles names --platform, not a key it never held."""
    log, _ = real_like_log()
    log.to_csv(tmp_path / "log.csv", index=False)
    models.reference_platform().to_toml(tmp_path / "p.toml")
    result = _cli("log", "inspect", tmp_path / "log.csv", "--rig", tmp_path / "p.toml",
                  "--out", tmp_path / "found")
    assert result.exit_code == 2 and "not a rig's sizes" in result.stderr
    assert "with --platform" in result.stderr
    platform = models.reference_platform()
    g = platform.geometry
    base, top = np.array(g.base_joints, float), np.array(g.platform_joints, float)
    base[1], top[1] = base[0], top[0]
    shared = dataclasses.replace(platform, geometry=dataclasses.replace(
        g, base_joints=base, platform_joints=top))
    with pytest.raises(InputError, match=r"^--platform: its joints are not laid out as a rig"):
        inspect_log(tmp_path / "log.csv", platform=shared)


@pytest.mark.parametrize("name, kind, axis, unit", [
    ("Timestamp [us]", "time", "", "us"), ("t", "time", "", None),
    ("Surge [mm]", "position", "x", "mm"), ("pos_z_mm", "position", "z", "mm"),
    ("Sway vel [mm/s]", "velocity", "y", "mm/s"), ("vx", "velocity", "x", None),
    ("Heave acc [mm/s^2]", "acceleration", "z", "mm/s^2"), ("Roll [deg]", "angle", "roll", "deg"),
    ("Yaw rate [deg/s]", "omega", "z", "deg/s"), ("omega_y", "omega", "y", None),
    ("alpha_x", "alpha", "x", None), ("alpha", "euler", "alpha", None),
    ("Act3 [N]", "force", "3", "N"), ("F6", "force", "6", None), ("F1", "force", "1", None),
    ("load_1", "force", "1", None), ("qw [1]", "quaternion", "qw", "1"), ("Mode", "", "", None),
    ("Oil temp [C]", "", "", None),
])
def test_a_column_name_says_its_quantity_axis_and_unit(name, kind, axis, unit):
    found = role(name)
    assert (found.kind, found.axis, found.unit) == (kind, axis, unit)


def test_a_file_in_gsfrics_own_columns_is_read_as_it_is(tmp_path):
    """The columns of a measured-data file, F1..F6 among them, map to themselves."""
    _, si = real_like_log()
    names = ("t", "x", "y", "z", "qw", "qx", "qy", "qz", *(f"F{i}" for i in range(1, 7)))
    si = si.assign(**{f"F{i}": 40.0 + i for i in range(1, 7)})
    si[list(names)].to_csv(tmp_path / "log.csv", index=False)
    found = inspect_log(tmp_path / "log.csv")
    fmt = found.log_format
    assert fmt.columns == {k: k for k in names}
    assert not fmt.units and not fmt.offset and fmt.frame.identity and fmt.wrap is None
    assert not found.ignored


def test_a_usage_error_points_to_the_subcommands_help(tmp_path):
    log, _ = real_like_log()
    log.to_csv(tmp_path / "log.csv", index=False)
    result = _cli("log", "inspect", tmp_path / "log.csv", "--rig", tmp_path / "a.toml",
                  "--platform", tmp_path / "b.toml")
    assert result.exit_code == 2
    assert result.stderr.strip().endswith("(see `gsfric log inspect --help`)")


def test_positions_of_a_large_rig_are_metres_when_its_platform_is_given(tmp_path):
    """Heights of 30 m without a unit: mm for a log on its own (no hexapod of unknown size
    moves its frame 20 m out), m for the 40-times reference platform it was recorded on (its
    legs reach 44 m)."""
    g = models.reference_platform().geometry
    large = models.reference_platform().with_geometry(
        base_joints=40 * g.base_joints, platform_joints=40 * g.platform_joints,
        stroke=(40 * g.stroke[0], 40 * g.stroke[1]))
    t = np.arange(2000) / 100.0
    pd.DataFrame({"time": t, "x": 0.5 * np.sin(t), "y": 0.4 * np.sin(1.3 * t),
                  "z": home_height(large) + 0.5 * np.sin(0.7 * t), "roll": 0.02 * np.sin(t),
                  "pitch": 0.02 * np.cos(t), "yaw": 0.03 * np.sin(0.5 * t)}
                 ).to_csv(tmp_path / "large.csv", index=False)
    given = inspect_log(tmp_path / "large.csv", platform=large)
    position = next(a for a in given.assumptions if a.topic == "position")
    assert position.value.endswith(" in m") and position.evidence.endswith("below 88 m: m")
    assert given.log_format.units.get("x", "m") == "m"
    assert inspect_log(tmp_path / "large.csv").log_format.units["x"] == "mm"
    sized = inspect_log(tmp_path / "large.csv", rig=Rig.from_platform(large))
    assert sized.log_format.units.get("x", "m") == "m"
