"""Platform: TOML reading and writing, defaults, validation messages, variants."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gsfric.platform.description as platform_module
from gsfric.errors import InputError
from gsfric.models import reference_platform
from gsfric.platform.description import (
    Body,
    Friction,
    Geometry,
    Legs,
    Platform,
)
from gsfric.platform.values import default_universal_axes
from gsfric.signal.rotations import rotation_from_rpy

EFFECTS = {
    "stribeck": {"static": 0.0, "velocity": 0.01},
    "seal_friction": {"force": 0.0},
    "quadratic_drag": {"coefficient": 0.0},
    "stroke_friction": {"slope": 0.0, "reference": 0.0},
    "payload_offset": {"x": 0.0, "y": 0.0, "z": 0.0},
    "sensor_bias": {f"b{i}": 0.0 for i in range(1, 7)},
    "joint_friction_coupling": {"scale": 0.0},
    "leg_weight": {"lower_mass": 0.0, "upper_mass": 0.0},
    "bushing_friction": {"coefficient": 0.0, "spacing": 0.1},
}

fixture_settings = settings(suppress_health_check=[HealthCheck.function_scoped_fixture],
                            deadline=None)


@pytest.fixture(autouse=True)
def effect_catalog(monkeypatch):
    monkeypatch.setattr(platform_module, "_effects_catalog", lambda: EFFECTS)


def hexagon(radius: float, half_angle_deg: float, z: float) -> list[list[float]]:
    points = []
    for k in range(3):
        for sign in (-1, 1):
            angle = math.radians(120 * k + sign * half_angle_deg)
            points.append([radius * math.cos(angle), radius * math.sin(angle), z])
    return points


def platform_dict() -> dict:
    return {
        "gravity": 9.81,
        "geometry": {
            "base_joints": hexagon(0.5, 10, 0.0),
            "platform_joints": hexagon(0.3, 50, -0.05),
        },
        "platform": {
            "mass": 10.0,
            "inertia": [[0.07, 0.0, 0.0], [0.0, 0.07, 0.0], [0.0, 0.0, 0.07]],
            "payload_mass": 3.0,
        },
    }


def write(tmp_path, data, name="platform.toml"):
    path = tmp_path / name
    path.write_text(tomli_w.dumps(data))
    return path


def error_of(tmp_path, data) -> str:
    path = write(tmp_path, data)
    with pytest.raises(InputError) as info:
        Platform.from_toml(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    return message[len(f"{path}: "):]


# -- reading, defaults, round trip ---------------------------------------------------------


def test_defaults(tmp_path):
    p = Platform.from_toml(write(tmp_path, platform_dict()))
    assert p.gravity == 9.81
    assert p.legs == Legs()
    assert p.friction == Friction()
    assert (p.legs.model, p.legs.weight, p.legs.lower_mass, p.legs.upper_com) == \
        ("rigid", True, 0.5, 0.2)
    np.testing.assert_array_equal(p.legs.upper_inertia, 0.035 * np.eye(3))
    assert dataclasses.astuple(p.friction) == (0.02, 0.04, 0.05, 0.02, 0.04, "paper", 0.25,
                                               0.1, 0.0)
    np.testing.assert_array_equal(p.platform.com, np.zeros(3))
    np.testing.assert_array_equal(p.platform.payload_inertia, np.zeros((3, 3)))
    np.testing.assert_array_equal(p.platform.payload_com, np.zeros(3))
    assert p.geometry.stroke is None
    assert p.effects == {}


def test_default_universal_axes_are_horizontal_tangents():
    base = np.array(hexagon(0.5, 10, 0.1))
    axes = Geometry(base, hexagon(0.3, 50, 0.0)).universal_axes
    np.testing.assert_allclose(np.linalg.norm(axes, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(axes[:, 2], 0.0, atol=0)
    np.testing.assert_allclose(np.einsum("ij,ij->i", axes, base), 0.0, atol=1e-15)
    expected = np.cross([0.0, 0.0, 1.0], base)
    np.testing.assert_allclose(axes, expected / np.linalg.norm(expected, axis=1)[:, None])
    np.testing.assert_array_equal(axes, default_universal_axes(base))


def test_given_universal_axes_are_normalized(tmp_path):
    data = platform_dict()
    data["geometry"]["universal_axes"] = [[2.0, 0.0, 0.0]] * 3 + [[0.0, 3.0, 4.0]] * 3
    p = Platform.from_toml(write(tmp_path, data))
    np.testing.assert_allclose(p.geometry.universal_axes[0], [1.0, 0.0, 0.0])
    np.testing.assert_allclose(p.geometry.universal_axes[5], [0.0, 0.6, 0.8])


def full_platform() -> Platform:
    rng = np.random.default_rng(7)
    a = rng.standard_normal((3, 3))
    data = platform_dict()
    data["gravity"] = 9.80665
    data["geometry"]["platform_joints"][0][0] = 0.1 + 0.2
    data["geometry"]["universal_axes"] = rng.standard_normal((6, 3)).tolist()
    data["geometry"]["stroke"] = [0.45, 0.95]
    spd = a @ a.T / 3
    data["platform"]["inertia"] = (spd + np.trace(spd) * np.eye(3)).tolist()   # a rigid body's
    data["platform"]["com"] = [1e-17, -2.5e-3, 1 / 3]
    data["platform"]["payload_inertia"] = (np.eye(3) / 7).tolist()
    data["platform"]["payload_com"] = [0.01, 0.0, 0.02]
    data["legs"] = {"model": "paper", "weight": False, "lower_mass": 0.7, "upper_com": 0.15}
    data["friction"] = {"joint_radius": 0.03, "prismatic_coulomb": 0.1}
    data["effects"] = {"stribeck": {"static": 2.0, "velocity": 0.01},
                       "sensor_bias": {"b3": -0.5}}
    return Platform.from_dict(data)


def test_toml_round_trip_is_exact(tmp_path):
    original = full_platform()
    path = tmp_path / "out.toml"
    original.to_toml(path)
    again = Platform.from_toml(path)
    assert again == original
    assert again.to_dict() == original.to_dict()
    again.to_toml(tmp_path / "again.toml")
    assert (tmp_path / "again.toml").read_text() == path.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["again.toml", "out.toml"]


def test_round_trip_with_defaults(tmp_path):
    original = Platform.from_dict(platform_dict())
    original.to_toml(tmp_path / "p.toml")
    assert Platform.from_toml(tmp_path / "p.toml") == original


def test_effect_parameters_take_catalog_defaults(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(tomli_w.dumps(platform_dict())
                    + "\n[effects]\nstribeck = { static = 2.0 }\nleg_weight = {}\n")
    p = Platform.from_toml(path)
    assert p.effects == {"stribeck": {"static": 2.0, "velocity": 0.01},
                         "leg_weight": {"lower_mass": 0.0, "upper_mass": 0.0}}


def test_arrays_are_read_only_and_platform_is_frozen():
    p = full_platform()
    for array in (p.geometry.base_joints, p.geometry.universal_axes, p.platform.inertia,
                  p.legs.lower_inertia, p.platform.com):
        assert array.dtype == np.float64
        with pytest.raises(ValueError):
            array[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.gravity = 1.0  # type: ignore[misc]


def test_variants():
    p = Platform.from_dict(platform_dict())
    q = p.with_friction(joint_coulomb=0.1)
    assert q.friction.joint_coulomb == 0.1 and p.friction.joint_coulomb == 0.04
    assert p.with_legs(weight=False).legs.weight is False
    assert p.with_body(payload_mass=5).platform.payload_mass == 5.0
    assert p.with_geometry(stroke=(0.5, 0.9)).geometry.stroke == (0.5, 0.9)
    assert p.replace(gravity=0).gravity == 0.0
    r = p.with_effect("stribeck", static=1.5).with_effect("seal_friction", force=3)
    assert r.effects == {"stribeck": {"static": 1.5, "velocity": 0.01},
                         "seal_friction": {"force": 3.0}}
    assert r.with_effect("stribeck", velocity=0.02).effects["stribeck"] == \
        {"static": 1.5, "velocity": 0.02}
    assert r.without_effects("stribeck").effects == {"seal_friction": {"force": 3.0}}
    assert r.without_effects().effects == {}
    drag = p.with_effects({"quadratic_drag": {}})
    assert drag.effects == {"quadratic_drag": {"coefficient": 0.0}}
    with pytest.raises(InputError, match="friction.joint_coulomb: must be >= 0"):
        p.with_friction(joint_coulomb=-1)
    with pytest.raises(InputError, match="effects.stribek: unknown effect"):
        p.with_effect("stribek")
    with pytest.raises(InputError, match="legs.model"):
        dataclasses.replace(p.legs, model="other")


def test_leg_com_placement():
    assert Legs().com_placement() == (0.2, 0.0, 0.2, 0.0)
    assert Legs(model="paper").com_placement() == (0.0, 0.25, 0.0, 0.25)


def test_constructors_validate_without_a_file():
    with pytest.raises(InputError, match=r"^geometry.base_joints: expected an array of shape "
                                         r"\(6, 3\), got \(3,\)$"):
        Geometry([0.0, 0.0, 0.0], np.zeros((6, 3)))
    with pytest.raises(InputError, match="platform.mass: must be >= 0"):
        Body(mass=-1.0, inertia=np.eye(3))
    with pytest.raises(InputError, match="geometry: expected a Geometry"):
        Platform(geometry={}, platform=Body(1.0, np.eye(3)))  # type: ignore[arg-type]


def test_base_joint_on_axis_has_no_default_axis():
    base = np.array(hexagon(0.5, 10, 0.0))
    base[2] = [0.0, 0.0, 0.0]
    with pytest.raises(InputError, match="base joint 3 lies on the z axis"):
        Geometry(base, hexagon(0.3, 50, 0.0))
    Geometry(base, hexagon(0.3, 50, 0.0), universal_axes=np.ones((6, 3)))


def test_catalog_contract():
    catalog = pytest.importorskip("gsfric.platform.catalog")
    for name, params in EFFECTS.items():
        assert name in catalog.EFFECTS
        assert set(params) <= set(catalog.EFFECTS[name])
    for params in catalog.EFFECTS.values():
        assert all(isinstance(v, (int, float)) for v in params.values())


# -- bad input: one-line messages naming the key ---------------------------------------------


def change(section, key, value):
    def apply(d):
        (d if section is None else d.setdefault(section, {}))[key] = value
    return apply


def delete(section, key=None):
    def apply(d):
        if key is None:
            del d[section]
        else:
            del d[section][key]
    return apply


BAD = [
    (change(None, "frction", {}), "frction: unknown key (did you mean 'friction'?)"),
    (change("geometry", "base_joint", []),
     "geometry.base_joint: unknown key (did you mean 'base_joints'?)"),
    (change("legs", "lower_mas", 1.0),
     "legs.lower_mas: unknown key (did you mean 'lower_mass'?)"),
    (change("geometry", "base_joints", [[0.0, 0.0, 0.0]] * 5),
     "geometry.base_joints: expected an array of shape (6, 3), got (5, 3)"),
    (change("geometry", "platform_joints", [[0.0, 0.0]] + [[0.0, 0.0, 0.0]] * 5),
     "geometry.platform_joints: expected an array of shape (6, 3), got rows of different lengths"),
    (change("geometry", "platform_joints", [[0.0, 0.0, "a"]] * 6),
     "geometry.platform_joints: expected an array of shape (6, 3) of numbers, found 'a'"),
    (change("platform", "mass", math.nan), "platform.mass: must be finite, got nan"),
    (change("platform", "mass", True), "platform.mass: expected a number, got True"),
    (change("platform", "mass", -1.0), "platform.mass: must be >= 0, got -1"),
    (change("platform", "com", [0.0, math.inf, 0.0]), "platform.com[1]: must be finite, got inf"),
    (change("legs", "upper_mass", -0.5), "legs.upper_mass: must be >= 0, got -0.5"),
    (change("platform", "inertia", [[1.0, 0.1, 0.0], [0.2, 1.0, 0.0], [0.0, 0.0, 1.0]]),
     "platform.inertia: not symmetric ([0][1] = 0.1 but [1][0] = 0.2)"),
    (change("platform", "payload_inertia", [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]),
     "platform.payload_inertia: not positive semi-definite (smallest eigenvalue -1)"),
    (change("legs", "lower_inertia", [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
     "legs.lower_inertia: not positive semi-definite (smallest eigenvalue -1)"),
    (change("geometry", "universal_axes", [[1.0, 0.0, 0.0]] * 2 + [[0.0, 0.0, 0.0]] * 4),
     "geometry.universal_axes[2]: axis of zero length"),
    (change("geometry", "stroke", [0.9, 0.5]),
     "geometry.stroke: d_min = 0.9 must be less than d_max = 0.5"),
    (change("geometry", "stroke", [0.9, 0.9]),
     "geometry.stroke: d_min = 0.9 must be less than d_max = 0.9"),
    (change("geometry", "stroke", [0.9]), "geometry.stroke: expected [d_min, d_max], got [0.9]"),
    (change("legs", "model", "rgid"),
     "legs.model: unknown leg model 'rgid' (did you mean 'rigid'?); expected 'rigid' or 'paper'"),
    (change("legs", "weight", 1), "legs.weight: expected true or false, got 1"),
    (change("friction", "joint_radius", -0.05), "friction.joint_radius: must be >= 0, got -0.05"),
    (change(None, "gravity", "9.81"), "gravity: expected a number, got '9.81'"),
    (change(None, "geometry", [1, 2]), "geometry: expected a table [geometry], got [1, 2]"),
    (delete("geometry"), "geometry: missing section [geometry]"),
    (delete("platform", "mass"), "platform.mass: missing"),
    (change("effects", "stribek", {}),
     "effects.stribek: unknown effect (did you mean 'stribeck'?)"),
    (change("effects", "stribeck", {"statik": 1.0}),
     "effects.stribeck.statik: unknown parameter (did you mean 'static'?)"),
    (change("effects", "stribeck", {"static": "big"}),
     "effects.stribeck.static: expected a number, got 'big'"),
    (change("effects", "seal_friction", 2.0),
     "effects.seal_friction: expected a table of parameters, e.g. seal_friction = {}, got 2.0"),
]


@pytest.mark.parametrize(("mutate", "expected"), BAD, ids=[e for _, e in BAD])
def test_bad_toml_names_the_key(tmp_path, mutate, expected):
    data = platform_dict()
    mutate(data)
    assert error_of(tmp_path, data) == expected


def test_bad_files(tmp_path):
    with pytest.raises(InputError, match=r"missing.toml: file not found$"):
        Platform.from_toml(tmp_path / "missing.toml")
    (tmp_path / "bin.toml").write_bytes(b"gravity = 9.81\n\xff\xfe")
    with pytest.raises(InputError, match=r"bin.toml: not UTF-8 text \(line 2, byte 15 of the file\)$"):
        Platform.from_toml(tmp_path / "bin.toml")
    (tmp_path / "syntax.toml").write_text("gravity = = 9.81\n[geometry\n")
    with pytest.raises(InputError, match=r"syntax.toml: invalid TOML: .*line 1"):
        Platform.from_toml(tmp_path / "syntax.toml")
    with pytest.raises(InputError, match="is a directory"):
        Platform.from_toml(tmp_path)
    with pytest.raises(InputError, match=r"^<dict>: expected a table of keys"):
        Platform.from_dict([1, 2])  # type: ignore[arg-type]


# -- fuzzing: garbage never raises anything but InputError -----------------------------------

toml_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=5),
    lambda children: st.lists(children, max_size=7)
    | st.dictionaries(st.text(max_size=5), children, max_size=4),
    max_leaves=30,
)
locations = st.sampled_from(
    [(None, k) for k in ("gravity", "geometry", "platform", "legs", "friction", "effects", "x")]
    + [("geometry", k) for k in ("base_joints", "platform_joints", "universal_axes", "stroke")]
    + [("platform", k) for k in ("mass", "inertia", "com", "payload_inertia", "payload_com")]
    + [("legs", k) for k in ("model", "weight", "lower_com", "upper_inertia")]
    + [("friction", k) for k in ("joint_viscous", "prismatic_coulomb")]
    + [("effects", k) for k in ("stribeck", "sensor_bias", "nothing")]
)


@fixture_settings
@given(changes=st.lists(st.tuples(locations, toml_values), max_size=3))
def test_random_values_raise_only_input_error(changes):
    data = platform_dict()
    for (section, key), value in changes:
        if section is not None and not isinstance(data.get(section, {}), dict):
            continue
        change(section, key, value)(data)
    try:
        Platform.from_dict(data)
    except InputError as error:
        assert "\n" not in str(error)


@fixture_settings
@given(text=st.text(max_size=300))
def test_random_toml_text_raises_only_input_error(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("fuzz") / "p.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        Platform.from_toml(path)
    except InputError as error:
        assert "\n" not in str(error)


@fixture_settings
@given(raw=st.binary(max_size=300))
def test_random_bytes_raise_only_input_error(tmp_path_factory, raw):
    path = tmp_path_factory.mktemp("fuzz") / "p.toml"
    path.write_bytes(raw)
    with pytest.raises(InputError):
        Platform.from_toml(path)


toml_lines = st.lists(st.sampled_from([
    "gravity = 9.81", "[geometry]", "[platform]", "[legs]", "[friction]", "[effects]",
    "base_joints = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [-0.5, 0.0, 0.0], [0.0, -0.5, 0.0],"
    " [0.3, 0.3, 0.0], [-0.3, 0.3, 0.0]]",
    "platform_joints = [[0.3, 0.0, 0.0]]", "mass = 10", "mass = -1", "inertia = 0.07",
    "inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]", "model = 'paper'", "weight = 'yes'",
    "stribeck = { static = 2.0 }", "stribeck = 3", "stroke = [1, 0]", "com = nan",
    "x = 1979-05-27", "universal_axes = [[0, 0, 0]]",
]), max_size=12)


@fixture_settings
@given(lines=toml_lines)
def test_random_toml_documents_raise_only_input_error(tmp_path_factory, lines):
    path = tmp_path_factory.mktemp("fuzz") / "p.toml"
    path.write_text("\n".join(lines))
    try:
        Platform.from_toml(path)
    except InputError as error:
        assert "\n" not in str(error)


@given(st.integers(1, 40), st.integers(0, 2**32 - 1))
def test_leg_lengths_are_the_joint_distances(n, seed):
    """|p + R e_i - c_i| for every pose and leg, against a loop over the legs with matmul."""
    rng = np.random.default_rng(seed)
    platform = reference_platform()
    position = rng.normal([0, 0, 0.7], 0.1, (n, 3))
    rotation = rotation_from_rpy(rng.uniform(-0.5, 0.5, (n, 3)))
    e = np.asarray(platform.geometry.platform_joints)
    c = np.asarray(platform.geometry.base_joints)
    expected = np.stack([np.linalg.norm(position + rotation @ e[i] - c[i], axis=1)
                         for i in range(6)], axis=1)
    np.testing.assert_allclose(platform.leg_lengths(position, rotation), expected,
                               rtol=1e-14)
