"""Fuzzing (hypothesis): random poses, motions and platforms never crash the evaluation and never
give a non-finite value on an unflagged step; malformed CSV and TOML files never crash the
loaders (only ``InputError``, one line); the CLI answers random files with exit 0 or 2."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from gsfric import models
from gsfric.cli import main
from gsfric.errors import GsfricWarning, InputError
from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.flags import FLAG_NONFINITE
from gsfric.io.readers import read_trajectory
from gsfric.platform.catalog import EFFECTS
from gsfric.platform.description import Platform
from gsfric.signal.rotations import rotation_from_quaternion
from gsfric.simulate.differentiate import iter_motions
from gsfric.trajectory import Motion

fuzz = settings(deadline=None, max_examples=60,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])

OUTPUTS = ("F", "F0", "R_E", "R_C", "M_C", "R_3", "M_3", "MfrE", "MfrC", "Ffr", "MfrE_s",
           "MfrC_s", "Ffr_s", "D", "D_dot", "u", "omega_leg", "omega_rel", "s2")


def check_result(result, n: int) -> None:
    """No non-finite value on an unflagged step; FLAG_NONFINITE steps are NaN throughout."""
    assert result.flag.shape == (n,)
    for name in OUTPUTS:
        values = getattr(result, name).reshape(n, -1)
        finite = np.isfinite(values).all(axis=1)
        assert not (~finite & (result.flag == 0)).any(), name
        nonfinite = (result.flag & FLAG_NONFINITE) != 0
        assert np.isnan(values[nonfinite]).all(), name
    frame = result.to_frame()
    assert len(frame) == n
    unflagged = frame["flag"].to_numpy() == 0
    assert np.isfinite(frame.to_numpy()[unflagged]).all()


def checked_warnings(function):
    """``function()``, its warnings checked instead of printed: each one a ``GsfricWarning``
    of one line (random platforms often have implausible inertias, far centres of mass)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            return function()
        finally:
            for w in caught:
                assert issubclass(w.category, GsfricWarning), (w.category, str(w.message))
                assert "\n" not in str(w.message)


def evaluate_quietly(evaluator, motion):
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"[0-9]+ of [0-9]+ steps flagged")
        return evaluator.evaluate(motion)


# -- random poses and motions --------------------------------------------------------------------


def magnitudes(limit: float) -> st.SearchStrategy[float]:
    return st.one_of(st.floats(-limit, limit, allow_nan=False),
                     st.sampled_from([0.0, 5e-324, -1e-300, 1e-12, -1e-9, 1e-5, 1e150, -1e200]))


vectors = st.lists(magnitudes(1e3), min_size=3, max_size=3)
quaternions = st.lists(st.floats(-1, 1, allow_nan=False), min_size=4, max_size=4).filter(
    lambda q: np.linalg.norm(q) > 1e-3)
positions = st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-1, 3)).map(list)


@st.composite
def motions(draw, max_steps: int = 6):
    n = draw(st.integers(1, max_steps))
    steps = [draw(st.tuples(st.one_of(positions, vectors), quaternions, vectors, vectors,
                            vectors, vectors)) for _ in range(n)]
    position, q, velocity, omega, acceleration, alpha = (np.array(c, float)
                                                         for c in zip(*steps))
    return Motion(np.arange(n, dtype=float), position, rotation_from_quaternion(q), velocity,
                  omega, acceleration, alpha)


@pytest.fixture(scope="module")
def reference_evaluators():
    platform = models.reference_platform()
    return {mode: Evaluator(platform, mode=mode) for mode in ("kinematic", "paper")}


@fuzz
@given(motion=motions(), mode=st.sampled_from(["kinematic", "paper"]))
def test_random_motions_never_crash_nor_hide_non_finite_values(reference_evaluators, motion,
                                                                mode):
    result = evaluate_quietly(reference_evaluators[mode], motion)
    check_result(result, len(motion))


@fuzz
@given(scale=st.sampled_from([1e-300, 1e-12, 1.0, 1e6, 1e100, 1e160, 1e300]),
       motion=motions(max_steps=3))
def test_huge_and_tiny_rates_are_finite_or_flagged(reference_evaluators, scale, motion):
    with np.errstate(over="ignore"):
        rates = [np.clip(r * scale, -1e300, 1e300) for r in (motion.velocity, motion.omega,
                                                             motion.acceleration, motion.alpha)]
    scaled = Motion(motion.t, motion.position, motion.rotation, *rates)
    check_result(evaluate_quietly(reference_evaluators["kinematic"], scaled), len(motion))


# -- random platforms ----------------------------------------------------------------------------


def inertias(limit: float = 10.0):
    return st.lists(st.floats(0, limit), min_size=3, max_size=3).map(
        lambda d: np.diag(d).tolist())


points = st.lists(st.lists(st.floats(-1, 1), min_size=3, max_size=3), min_size=6, max_size=6)


@st.composite
def platform_dicts(draw):
    data = models.reference_platform().to_dict()
    if draw(st.booleans()):
        data["geometry"]["base_joints"] = draw(points)
        data["geometry"].pop("universal_axes")
    if draw(st.booleans()):
        data["geometry"]["platform_joints"] = draw(points)
    if draw(st.booleans()):
        data["geometry"]["universal_axes"] = draw(points)
    if draw(st.booleans()):
        data["geometry"].pop("stroke")
    data["gravity"] = draw(st.floats(0, 30))
    body = data["platform"]
    body["mass"] = draw(st.floats(0, 1e3))
    body["inertia"] = draw(inertias())
    body["com"] = draw(st.lists(st.floats(-0.5, 0.5), min_size=3, max_size=3))
    body["payload_mass"] = draw(st.floats(0, 1e3))
    legs = data["legs"]
    legs["model"] = draw(st.sampled_from(["rigid", "paper"]))
    legs["weight"] = draw(st.booleans())
    for part in ("lower", "upper"):
        legs[f"{part}_mass"] = draw(st.floats(0, 50))
        legs[f"{part}_com"] = draw(st.floats(-1, 1))
        legs[f"{part}_inertia"] = draw(inertias(1.0))
    for key in data["friction"]:
        data["friction"][key] = draw(st.floats(0, 10))
    names = draw(st.lists(st.sampled_from(sorted(EFFECTS)), max_size=3, unique=True))
    data["effects"] = {name: {p: draw(st.floats(-10, 10)) for p in EFFECTS[name]
                              if draw(st.booleans())} for name in names}
    return data


@fuzz
@given(data=platform_dicts(), motion=motions(max_steps=4),
       mode=st.sampled_from(["kinematic", "paper"]))
def test_random_platforms_never_crash_nor_hide_non_finite_values(data, motion, mode):
    try:
        platform = checked_warnings(lambda: Platform.from_dict(data, source="fuzz.toml"))
    except InputError as error:           # e.g. a base joint on the z axis with no axes given
        assert "\n" not in str(error) and str(error).startswith("fuzz.toml: ")
        return
    check_result(evaluate_quietly(Evaluator(platform, mode=mode), motion), len(motion))


# -- malformed CSV files through both readers ----------------------------------------------------


def _valid_lines(n: int = 30) -> list[str]:
    t = np.arange(n) * 0.01
    motion = models.sinusoidal(t)
    q = motion.quaternion()
    rows = [",".join(repr(float(v)) for v in (t[i], *motion.position[i], *q[i]))
            for i in range(n)]
    return ["t,x,y,z,qw,qx,qy,qz"] + rows


garbage = st.one_of(st.sampled_from(["", "nan", "inf", "-", "1e999", "abc", '"', ",", ",,",
                                     "\t", "NULL", "1,5", "0x1p3", "\x00", "é", "#", "\r"]),
                    st.text(max_size=5), st.floats().map(repr))


@st.composite
def mutated_csv(draw) -> str:
    lines = _valid_lines()
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(lines) - 1))
        kind = draw(st.sampled_from(["cell", "delete", "duplicate", "insert", "truncate",
                                     "header", "swap"]))
        if kind == "cell":
            cells = lines[i].split(",")
            cells[draw(st.integers(0, len(cells) - 1))] = draw(garbage)
            lines[i] = ",".join(cells)
        elif kind == "delete" and len(lines) > 1:
            del lines[i]
        elif kind == "duplicate":
            lines.insert(i, lines[i])
        elif kind == "insert":
            lines.insert(i, draw(garbage))
        elif kind == "truncate":
            lines[i] = lines[i][:draw(st.integers(0, len(lines[i])))]
            lines = lines[:i + 1]
        elif kind == "header":
            names = lines[0].split(",")
            names[draw(st.integers(0, len(names) - 1))] = draw(
                st.sampled_from(["", "gama", "alpha", "T", "x", "F1", "qw "]))
            lines[0] = ",".join(names)
        elif kind == "swap" and i > 1:
            lines[i], lines[i - 1] = lines[i - 1], lines[i]
    return "\n".join(lines) + draw(st.sampled_from(["", "\n", "\n\n"]))


def _outcome(function):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GsfricWarning)
        try:
            return function(), None
        except InputError as error:
            message = str(error)
            assert "\n" not in message
            return None, message


@settings(fuzz, max_examples=40)
@given(text=mutated_csv())
def test_malformed_csv_never_crashes_the_readers(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("csv") / "trajectory.csv"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    whole, whole_error = _outcome(lambda: read_trajectory(path))
    parts, parts_error = _outcome(lambda: list(iter_motions(path, chunk=8)))
    one, one_error = _outcome(lambda: list(iter_motions(path, chunk=10_000)))
    for message in (whole_error, parts_error, one_error):
        assert message is None or message.startswith(str(path)) \
            or message.startswith("chunk")
    # read whole, the streaming reader is read_trajectory
    assert (one_error is None) == (whole_error is None)
    assert one_error == whole_error
    # in chunks it accepts nothing that read_trajectory refuses, and refuses a good file only
    # for a reason of its own (non-uniform sampling, a window longer than the chunk)
    if whole_error is not None:
        assert parts_error is not None
    elif parts_error is not None:
        assert "uniformly sampled" in parts_error or "window" in parts_error \
            or "polyorder" in parts_error, parts_error
    else:
        assert sum(len(p.motion) for p in parts) == len(whole)
        assert np.isfinite(np.concatenate([p.motion.alpha for p in parts])).all()


@fuzz
@given(raw=st.binary(max_size=300), suffix=st.sampled_from([".csv", ".parquet"]))
def test_random_bytes_never_crash_the_streaming_reader(tmp_path_factory, raw, suffix):
    path = tmp_path_factory.mktemp("bytes") / f"trajectory{suffix}"
    path.write_bytes(raw)
    _outcome(lambda: list(iter_motions(path, chunk=8)))


# -- malformed TOML files ------------------------------------------------------------------------


toml_values = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                        st.integers(-10**20, 10**20), st.text(max_size=5), st.booleans(),
                        st.lists(st.floats(-2, 2), max_size=7),
                        st.lists(st.lists(st.floats(-2, 2), max_size=4), max_size=7),
                        st.dictionaries(st.text(max_size=4), st.floats(), max_size=2))


@st.composite
def mutated_platform(draw) -> dict:
    data = models.reference_platform().to_dict()
    data["effects"] = {"stribeck": {"static": 1.0, "velocity": 0.01}}
    for _ in range(draw(st.integers(1, 3))):
        section = draw(st.sampled_from(sorted(data)))
        kind = draw(st.sampled_from(["value", "drop", "rename", "add"]))
        table = data[section] if isinstance(data[section], dict) else data
        key = section if table is data else draw(st.sampled_from(sorted(table) or [section]))
        if key not in table:
            continue
        if kind == "value":
            table[key] = draw(toml_values)
        elif kind == "drop":
            del table[key]
        elif kind == "rename":
            new = draw(st.sampled_from([key[:-1], key + "s", key.upper(), key.replace("_", ""),
                                        "stribek", "unknown"]))
            if new:
                table[new] = table.pop(key)
        else:
            table[draw(st.text(min_size=1, max_size=6))] = draw(toml_values)
    return data


@fuzz
@given(data=mutated_platform())
def test_malformed_platform_toml_never_crashes(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("toml") / "platform.toml"
    try:
        path.write_text(tomli_w.dumps(data))
    except (TypeError, ValueError):      # tomli_w cannot write it (NaN keys, ...)
        assume(False)
    try:
        checked_warnings(lambda: Platform.from_toml(path))
    except InputError as error:
        message = str(error)
        assert "\n" not in message and message.startswith(f"{path}: ")


@fuzz
@given(text=st.text(alphabet=st.sampled_from(list("[]=\"'.,{}# \nabcxyz0123456789_-+e")),
                    max_size=200))
def test_random_toml_text_never_crashes(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("toml") / "platform.toml"
    path.write_text(text)
    try:
        checked_warnings(lambda: Platform.from_toml(path))
    except InputError as error:
        assert "\n" not in str(error)


# -- the CLI on random files ---------------------------------------------------------------------


@settings(deadline=None, max_examples=25,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(text=mutated_csv(), chunk=st.sampled_from(["8", "100000"]))
def test_cli_answers_random_files_with_exit_0_1_or_2(tmp_path_factory, text, chunk):
    folder = tmp_path_factory.mktemp("cli")
    path = folder / "trajectory.csv"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    out = folder / "out.csv"
    result = CliRunner().invoke(main, ["simulate", "--trajectory", str(path), "--out", str(out),
                                       "--chunk", chunk], catch_exceptions=False)
    # 1: a check failed, here the share of flagged steps above its limit (a jump in a pose)
    assert result.exit_code in (0, 1, 2), result.output
    errors = [line for line in result.stderr.splitlines() if line.startswith("gsfric: error:")]
    others = [line for line in result.stderr.splitlines()
              if line and not line.startswith(("gsfric: error:", "gsfric: warning:"))]
    assert others == []
    assert len(errors) == (result.exit_code != 0)
    if result.exit_code == 1:
        assert "are flagged by the model" in errors[0] and "--keep-flagged" in errors[0]
    assert out.exists() == (result.exit_code == 0)
    assert [p.name for p in folder.iterdir() if p.name.startswith(".")] == []
