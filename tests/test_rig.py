"""A platform of a rig's sizes: `gsfric platform --template` with sizes or a rig TOML."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import tomllib
from click.testing import CliRunner

import gsfric
from gsfric.cli import main
from gsfric.errors import InputError
from gsfric.platform.rig import Rig, rig_platform_toml, rig_toml
from gsfric.platform.text import commented_toml

LARGE_RIG = Rig(base_radius=2.0, base_half_angle=math.radians(7.5), platform_radius=1.4,
                platform_half_angle=math.radians(20.0), stroke=(3.0, 4.6),
                platform_mass=800.0, lower_mass=60.0, upper_mass=25.0, payload_mass=200.0)


def _at_rest(position: np.ndarray, steps: int = 5) -> gsfric.Motion:
    t = np.arange(steps) * 0.01
    zero = np.zeros((steps, 3))
    return gsfric.Motion.from_arrays(t, np.tile(position, (steps, 1)),
                                     np.tile(np.eye(3), (steps, 1, 1)), zero, zero, zero, zero)


@pytest.mark.parametrize("rig", [LARGE_RIG, dataclasses.replace(LARGE_RIG, home_height=3.5)])
def test_home_pose_is_inside_the_stroke_with_no_flag(rig):
    platform = rig.platform()
    result = gsfric.evaluate(platform, _at_rest(np.array([0.0, 0.0, rig.home])))
    assert not result.flag.any()
    lo, hi = rig.stroke
    assert np.all((result.D > lo) & (result.D < hi))
    if rig.home_height is None:        # mid-stroke by default
        assert np.allclose(result.D, (lo + hi) / 2, rtol=1e-9)
    # the legs hold the weight: the actuators push, about a sixth of it each
    weight = platform.gravity * (rig.platform_mass + rig.payload_mass)
    assert np.all(result.F > 0) and weight / 6 < result.F.mean() < 2 * weight / 6


def test_sizes_round_trip_through_the_platform_file(tmp_path):
    path = tmp_path / "platform.toml"
    path.write_text(rig_platform_toml(LARGE_RIG))
    platform = gsfric.Platform.from_toml(path)
    assert platform == LARGE_RIG.platform()
    back = Rig.from_platform(platform)
    for f in dataclasses.fields(Rig):
        if f.name not in ("home_height", "friction_model") and getattr(LARGE_RIG, f.name) \
                is not None:
            assert getattr(back, f.name) == pytest.approx(getattr(LARGE_RIG, f.name),
                                                          rel=1e-12), f.name
    assert back.friction_model == LARGE_RIG.friction_model
    rig_file = tmp_path / "rig.toml"
    rig_file.write_text(rig_toml(LARGE_RIG))
    assert Rig.from_toml(rig_file) == LARGE_RIG


def test_the_reference_sizes_give_the_reference_geometry():
    reference = gsfric.reference_platform()
    rig = Rig.from_platform(reference)
    g = rig.platform().geometry
    assert np.allclose(g.base_joints, reference.geometry.base_joints, atol=1e-12)
    assert np.allclose(g.platform_joints, reference.geometry.platform_joints, atol=1e-12)


def test_derived_inertias_grow_with_mass_and_size():
    small = LARGE_RIG.platform()
    heavy = dataclasses.replace(LARGE_RIG, platform_mass=1600.0, lower_mass=120.0).platform()
    assert np.allclose(heavy.platform.inertia, 2 * small.platform.inertia)
    assert np.allclose(heavy.legs.lower_inertia, 2 * small.legs.lower_inertia)
    wide = dataclasses.replace(LARGE_RIG, platform_radius=1.6).platform()
    assert np.all(np.diag(wide.platform.inertia) > np.diag(small.platform.inertia))


@pytest.mark.parametrize("change, key", [
    ({"base_radius": -1.0}, "base_radius"),
    ({"platform_half_angle": 15.0}, "platform_half_angle"),
    ({"stroke": [4.6, 3.0]}, "stroke"),
    ({"home_height": 9.0}, "home_height"),
    ({"lower_mass": "heavy"}, "lower_mass"),
    ({"friction_model": "sticky"}, "friction_model"),
    ({"base_radiuss": 2.0}, "base_radiuss"),
])
def test_a_bad_size_names_its_key_in_one_line(tmp_path, change, key):
    data = {k: list(v) if isinstance(v, tuple) else v
            for k, v in dataclasses.asdict(LARGE_RIG).items() if v is not None}
    data.update(change)
    with pytest.raises(InputError) as error:
        Rig.from_dict(data, source="rig.toml")
    message = str(error.value)
    assert message.startswith(f"rig.toml: {key}: ") and "\n" not in message


def test_cli_template_from_sizes_and_from_a_rig_file(tmp_path):
    runner = CliRunner()
    rig_file, out = tmp_path / "rig.toml", tmp_path / "platform.toml"
    result = runner.invoke(main, ["platform", "--rig-template", "--out", str(rig_file)])
    assert result.exit_code == 0, result.output
    text = rig_file.read_text().replace("base_radius = 0.5", "base_radius = 0.6")
    rig_file.write_text(text)
    result = runner.invoke(main, ["platform", "--template", "--rig", str(rig_file),
                                  "--platform-mass", "20", "--out", str(out)])
    assert result.exit_code == 0, result.output
    platform = gsfric.Platform.from_toml(out)
    assert platform.platform.mass == 20.0
    assert np.allclose(np.linalg.norm(platform.geometry.base_joints, axis=1), 0.6)
    result = runner.invoke(main, ["platform", "--template", "--stroke", "0.1", "0.2"])
    assert result.exit_code == 2
    assert result.output.strip().splitlines()[-1].startswith("gsfric: error: --stroke: ")
    result = runner.invoke(main, ["platform", "--template", "--base-radius", "-2"])
    assert result.exit_code == 2 and "--base-radius: must be a positive" in result.output


def test_commented_toml_reads_back_with_effects_and_limits():
    platform = (gsfric.reference_platform().with_effect("stribeck", static=1.5)
                .replace(limits={"actuator_force": 500.0}))
    text = commented_toml(platform, header=["from a test"], notes={"effects.stribeck": "x"})
    assert gsfric.Platform.from_dict(tomllib.loads(text)) == platform
    line = next(x for x in text.splitlines() if x.startswith("stribeck"))
    assert "static N" in line and "velocity m/s" in line


def test_derived_values_follow_the_stroke_and_are_shown():
    values = LARGE_RIG.derived()
    d_min = LARGE_RIG.stroke[0]
    assert (values.bushing_offset, values.bushing_spacing) == pytest.approx((0.5 * d_min,
                                                                             0.2 * d_min))
    longer = dataclasses.replace(LARGE_RIG, stroke=(3.5, 4.6)).derived()
    assert longer.bushing_offset == pytest.approx(0.5 * 3.5)
    # a solid cylinder of length d_min: m (3 a^2 + l^2) / 12 across, m a^2 / 2 along
    a = d_min / 20
    assert values.lower_inertia == pytest.approx(
        (60.0 * (3 * a * a + d_min**2) / 12,) * 2 + (60.0 * a * a / 2,))
    platform = LARGE_RIG.platform()
    assert platform.friction.bushing_offset == values.bushing_offset
    assert np.array_equal(np.diag(platform.legs.upper_inertia), values.upper_inertia)
    lines = values.lines()
    assert "bushings at 1.5 m and 2.1 m from C_i" in lines[1] and "derived: 0.5 d_min" in lines[1]
    assert not values.given


def test_explicit_values_override_the_derived_ones(tmp_path):
    rig = dataclasses.replace(LARGE_RIG, bushing_offset=1.2, bushing_spacing=0.4,
                              lower_inertia=(30.0, 30.0, 0.5), upper_com=1.0,
                              platform_inertia=(500.0, 500.0, 900.0))
    platform = rig.platform()
    assert (platform.friction.bushing_offset, platform.friction.bushing_spacing) == (1.2, 0.4)
    assert np.array_equal(platform.legs.lower_inertia, np.diag([30.0, 30.0, 0.5]))
    assert np.array_equal(platform.platform.inertia, np.diag([500.0, 500.0, 900.0]))
    assert platform.legs.upper_com == 1.0
    assert platform.legs.lower_com == LARGE_RIG.platform().legs.lower_com     # still derived
    given = rig.derived().given
    assert set(given) == {"bushing_offset", "bushing_spacing", "lower_inertia", "upper_com",
                          "platform_inertia"}
    # a rig file with them reads back equal, and the CLI expands it with them
    rig_file, out = tmp_path / "rig.toml", tmp_path / "platform.toml"
    rig_file.write_text(rig_toml(rig))
    assert Rig.from_toml(rig_file) == rig
    result = CliRunner().invoke(main, ["platform", "--template", "--rig", str(rig_file),
                                       "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert gsfric.Platform.from_toml(out) == platform
    assert "bushing_offset 1.2 m (given)" in result.output
    assert "upper_inertia" in result.output and "derived: a solid cylinder" in result.output
    shown = CliRunner().invoke(main, ["platform", "--show", "--rig", str(rig_file),
                                      "--stroke", "3.2", "4.6"])
    assert shown.exit_code == 0, shown.output
    assert "bushings at 1.2 m and 1.6 m from C_i" in shown.output       # given: not moved
    assert f"lower_com {3.2 / 2:.6g} m from C_i (derived" in shown.output


@pytest.mark.parametrize("change, key", [
    ({"lower_inertia": [1.0, 2.0]}, "lower_inertia"),
    ({"platform_inertia": [1.0, -2.0, 3.0]}, "platform_inertia[1]"),
    ({"bushing_offset": 9.0}, "bushing_offset"),
    ({"upper_com": 0.0}, "upper_com"),
])
def test_a_bad_explicit_value_names_its_key(change, key):
    data = {k: list(v) if isinstance(v, tuple) else v
            for k, v in dataclasses.asdict(LARGE_RIG).items() if v is not None}
    data.update(change)
    with pytest.raises(InputError) as error:
        Rig.from_dict(data, source="rig.toml")
    message = str(error.value)
    assert message.startswith(f"rig.toml: {key}: ") and "\n" not in message


def test_show_needs_a_rig():
    result = CliRunner().invoke(main, ["platform", "--show"])
    assert result.exit_code == 2 and "--show: give the rig" in result.output
