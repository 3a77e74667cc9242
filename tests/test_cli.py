"""The command line on bad input and failure modes: exit codes and one-line messages.

Exit codes (gsfric.cli): 0 success, 1 a check failed (``simulate --strict`` with flagged steps),
2 bad input (one line ``gsfric: error: ...`` naming the file, field or row), 3 an internal or
build failure (a stale or altered generated/).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import click
import numpy as np
import pandas as pd
import pytest
import tomli_w
from click.testing import CliRunner
from scipy.spatial.transform import Rotation

from gsfric import models
from gsfric.cli import COMMANDS, main
from gsfric.io.tables import read_table, write_table
from gsfric.signal.rotations import euler_from_rotation, quaternion_from_rotation
from gsfric.simulate import run as simulate_run

ROOT = Path(__file__).resolve().parent.parent
STALE = "gsfric: warning: generated/ is stale"     # may appear while derive/ is being edited


def run(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line and not line.startswith(STALE)]


def error_of(result, code: int = 2) -> str:
    """The one-line reason of a failed command (without the ``gsfric: error: `` prefix)."""
    assert result.exit_code == code, (result.exit_code, result.output)
    got = lines(result.stderr)
    assert len(got) == 1, result.stderr
    assert got[0].startswith("gsfric: error: "), got[0]
    assert "Traceback" not in result.output
    return got[0][len("gsfric: error: "):]


def warnings_of(result) -> list[str]:
    got = lines(result.stderr)
    assert all(line.startswith("gsfric: warning: ") for line in got), result.stderr
    return [line[len("gsfric: warning: "):] for line in got]


def trajectory(n: int = 60, orientation: str = "quaternion", rate: float = 50.0
               ) -> pd.DataFrame:
    t = np.arange(n) / rate
    motion = models.sinusoidal(t)
    frame = pd.DataFrame({"t": t})
    frame[["x", "y", "z"]] = motion.position
    if orientation == "quaternion":
        frame[["qw", "qx", "qy", "qz"]] = motion.quaternion()
    else:
        frame[["alpha", "beta", "gamma"]] = motion.euler()
    return frame


@pytest.fixture
def good(tmp_path) -> Path:
    path = tmp_path / "trajectory.csv"
    write_table(trajectory(), path)
    return path


def write_text(tmp_path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def no_leftovers(folder: Path) -> bool:
    return not [p for p in folder.iterdir() if p.name.startswith(".")]


# -- success ----------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_simulate_writes_every_column(tmp_path, good, suffix):
    out = tmp_path / f"forces{suffix}"
    result = run("simulate", "--trajectory", good, "--out", out)
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith(f"wrote {out} (60 steps, 0 flagged; differentiated by "
                                    "savgol, per-sample filters (order 4))\npeaks per leg ")
    assert warnings_of(result) == []
    frame = read_table(out)
    assert len(frame) == 60
    for name in (["t", "flag"] + [f"F{i}" for i in range(1, 7)]
                 + [f"{k}{i}" for k in ("Ffr", "MfrE_s", "MfrC_s", "Ffr_s", "MC") for i in range(1, 7)]
                 + [f"{k}{a}{i}" for k in ("RE", "RC") for a in "xyz" for i in range(1, 7)]):
        assert name in frame.columns, name
    assert np.isfinite(frame.drop(columns="flag").to_numpy()).all()
    assert no_leftovers(tmp_path)


def test_streamed_and_whole_cli_runs_agree(tmp_path):
    path = tmp_path / "t.csv"
    write_table(trajectory(500), path)
    a, b = tmp_path / "a.parquet", tmp_path / "b.parquet"
    assert run("simulate", "--trajectory", path, "--out", a, "--window", "9").exit_code == 0
    assert run("simulate", "--trajectory", path, "--out", b, "--window", "9",
               "--chunk", "64").exit_code == 0
    streamed, whole = pd.read_parquet(b), pd.read_parquet(a)
    # sigma_F of a streamed file takes the pose noise of its first rows, not of the whole
    sigma = [f"sigma_F{i}" for i in range(1, 7)]
    np.testing.assert_allclose(streamed[sigma], whole[sigma], rtol=0.5, atol=1e-3)
    np.testing.assert_allclose(streamed.drop(columns=sigma).to_numpy(),
                               whole.drop(columns=sigma).to_numpy(), rtol=1e-9, atol=1e-9)


def test_progress_is_shown_on_request(tmp_path, good):
    shown = run("simulate", "--trajectory", good, "--out", tmp_path / "a.csv", "--progress")
    assert shown.exit_code == 0 and "simulate" in shown.stderr and "step" in shown.stderr
    hidden = run("simulate", "--trajectory", good, "--out", tmp_path / "b.csv")
    assert hidden.exit_code == 0 and lines(hidden.stderr) == []


# -- bad trajectory files ------------------------------------------------------------------------


def _frame_text(frame: pd.DataFrame) -> str:
    return frame.to_csv(index=False)


def _set(frame, row, column, value):
    frame = frame.astype(object)
    frame.loc[row - 1, column] = value
    return _frame_text(frame)


T = trajectory()
BAD_FILES = [
    ("empty.csv", "", "file is empty"),
    ("header.csv", "t,x,y,z,qw,qx,qy,qz\n", "no data rows"),
    ("nozcol.csv", _frame_text(T.drop(columns="z")), "missing column 'z'"),
    ("noorient.csv", _frame_text(T.drop(columns=["qw", "qx", "qy", "qz"])),
     "missing orientation: give columns alpha, beta, gamma, qw, qx, qy, qz or roll, pitch, yaw"),
    ("typo.csv", _frame_text(T.rename(columns={"qx": "q_x"})),
     "missing column 'qx' (is it 'q_x'? map it with --column-map qx=q_x)"),
    ("nan.csv", _set(T, 17, "x", np.nan), "row 17: column 'x' is empty or NaN"),
    ("inf.csv", _set(T, 9, "qw", np.inf), "row 9: column 'qw' is infinite"),
    ("comma.csv", _set(T, 30, "y", "12,5"), "row 30: column 'y' is not a number: '12,5'"),
    ("fields.csv", _frame_text(T).replace("\n", ",7\n", 31).replace(",7\n", "\n", 30),
     "cannot parse as CSV: row 30 has 9 fields but the header has 8"),
    ("text.csv", _set(T, 30, "y", "twelve"), "row 30: column 'y' is not a number: 'twelve'"),
    ("back.csv", _set(T, 5, "t", 0.01), "row 5: t = 0.01 is less than t = 0.06 in row 4; "
                                        "t must increase"),
    ("zeroq.csv", _frame_text(T.assign(**{c: np.where(np.arange(60) == 2, 0.0, T[c])
                                          for c in ("qw", "qx", "qy", "qz")})),
     "row 3: quaternion of zero length"),
    ("short.csv", _frame_text(T.head(4)), "4 data rows; at least 7 are needed to differentiate "
                                          "the motion"),
    ("measured.csv", _frame_text(T.assign(F1=1.0)),
     "missing column 'F2' (measured data need F1..F6)"),
    ("bad.parquet", "this is not parquet", "cannot read as Parquet"),
    ("data.txt", "t,x\n", "unknown extension '.txt'; use .csv, .parquet or .pq"),
]


@pytest.mark.parametrize(("name", "text", "expected"), BAD_FILES,
                         ids=[name for name, _, _ in BAD_FILES])
def test_bad_trajectory_file_one_line_exit_2(tmp_path, name, text, expected):
    path = write_text(tmp_path, name, text)
    out = tmp_path / "forces.csv"
    message = error_of(run("simulate", "--trajectory", path, "--out", out))
    assert message.startswith(f"{path}: ")
    assert expected in message
    assert not out.exists() and no_leftovers(tmp_path)


def test_missing_trajectory_file(tmp_path):
    missing = tmp_path / "nope.csv"
    assert error_of(run("simulate", "--trajectory", missing, "--out", tmp_path / "o.csv")) \
        == f"{missing}: file not found"


def test_bad_row_in_a_later_chunk_names_it_and_leaves_nothing(tmp_path):
    frame = trajectory(400).astype(object)
    frame.loc[349, "z"] = "NULL"
    path = tmp_path / "t.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / "forces.parquet"
    out.write_bytes(b"old")
    message = error_of(run("simulate", "--trajectory", path, "--out", out, "--chunk", "50"))
    assert message == f"{path}: row 350: column 'z' is not a number: 'NULL'"
    assert out.read_bytes() == b"old" and no_leftovers(tmp_path)


@pytest.mark.parametrize(("args", "expected"), [
    (("--chunk", "3"), "chunk: must be an integer >= 7, got 3"),
    (("--window", "8"), "window must be odd, got 8"),
    (("--window", "41", "--chunk", "20"), "window = 41 is longer than the chunk of 20 steps"),
])
def test_bad_options_one_line(tmp_path, good, args, expected):
    message = error_of(run("simulate", "--trajectory", good, "--out", tmp_path / "o.csv", *args))
    assert expected in message


@pytest.mark.parametrize(("out", "expected"), [
    ("forces.xlsx", "unknown extension '.xlsx'"),
    ("missing/forces.csv", "does not exist"),
])
def test_bad_output_path(tmp_path, good, out, expected):
    assert expected in error_of(run("simulate", "--trajectory", good, "--out", tmp_path / out))


def test_output_onto_the_input_is_refused(tmp_path, good):
    before = good.read_bytes()
    message = error_of(run("simulate", "--trajectory", good, "--out", good))
    assert message == f"{good}: is the trajectory file itself; choose another output"
    assert good.read_bytes() == before


# -- bad platform files --------------------------------------------------------------------------


def _platform_data() -> dict:
    return models.reference_platform().to_dict()


def _with(change) -> dict:
    data = _platform_data()
    change(data)
    return data


BAD_PLATFORMS = [
    (lambda d: d["friction"].__setitem__("joint_colomb", d["friction"].pop("joint_coulomb")),
     "friction.joint_colomb: unknown key (did you mean 'joint_coulomb'?)"),
    (lambda d: d.__setitem__("gravty", 9.81), "gravty: unknown key (did you mean 'gravity'?)"),
    (lambda d: d.__setitem__("effects", {"stribek": {"static": 1.0}}),
     "effects.stribek: unknown effect (did you mean 'stribeck'?)"),
    (lambda d: d.__setitem__("effects", {"stribeck": {"statik": 1.0}}),
     "effects.stribeck.statik: unknown parameter (did you mean 'static'?)"),
    (lambda d: d["geometry"].__setitem__("base_joints", d["geometry"]["base_joints"][:5]),
     "geometry.base_joints: expected an array of shape (6, 3), got (5, 3)"),
    (lambda d: d["platform"].__setitem__("mass", "ten"),
     "platform.mass: expected a number, got 'ten'"),
    (lambda d: d["platform"].__setitem__("mass", -1.0), "platform.mass: must be >= 0, got -1"),
    (lambda d: d["geometry"].__setitem__("stroke", [1.1, 0.5]),
     "geometry.stroke: d_min = 1.1 must be less than d_max = 0.5"),
    (lambda d: d["legs"].__setitem__("model", "papr"),
     "legs.model: unknown leg model 'papr' (did you mean 'paper'?); expected 'rigid' or "
     "'paper'"),
    (lambda d: d.pop("platform"), "platform: missing section [platform]"),
]


@pytest.mark.parametrize(("change", "expected"), BAD_PLATFORMS,
                         ids=[e.split(":")[0] for _, e in BAD_PLATFORMS])
def test_bad_platform_one_line_exit_2(tmp_path, good, change, expected):
    path = tmp_path / "platform.toml"
    path.write_text(tomli_w.dumps(_with(change)))
    out = tmp_path / "o.csv"
    message = error_of(run("simulate", "--trajectory", good, "--platform", path, "--out", out))
    assert message == f"{path}: {expected}"
    assert not out.exists()


@pytest.mark.parametrize(("text", "expected"), [
    ("", "geometry: missing section [geometry]"),
    ("gravity = \n", "invalid TOML"),
    ("[geometry\n", "invalid TOML"),
])
def test_malformed_platform_toml(tmp_path, good, text, expected):
    path = write_text(tmp_path, "platform.toml", text)
    message = error_of(run("simulate", "--trajectory", good, "--platform", path,
                           "--out", tmp_path / "o.csv"))
    assert message.startswith(f"{path}: ") and expected in message


def test_missing_platform_file(tmp_path, good):
    missing = tmp_path / "nope.toml"
    assert error_of(run("simulate", "--trajectory", good, "--platform", missing,
                        "--out", tmp_path / "o.csv")) == f"{missing}: file not found"


# -- suspicious input: warnings, flags, --strict ----------------------------------------------


def test_degrees_give_a_warning_and_no_result(tmp_path):
    frame = trajectory(orientation="euler")
    frame[["alpha", "beta", "gamma"]] = np.degrees(frame[["alpha", "beta", "gamma"]]) + 40
    path = tmp_path / "deg.csv"
    write_table(frame, path)
    result = run("simulate", "--trajectory", path, "--out", tmp_path / "o.csv")
    assert result.exit_code == 2
    found = lines(result.stderr)
    assert found[0].startswith(f"gsfric: warning: {path}: angles look like degrees")
    assert "angles must be in radians" in found[0]
    # such angles turn the platform far out of its workspace: a data error, before physics
    assert found[-1].startswith(f"gsfric: error: {path}: ")
    assert "steps have a leg outside the stroke" in found[-1] and len(found) == 2
    assert not (tmp_path / "o.csv").exists()


def test_euler_jumps_at_the_level_pose_warn_and_match_the_quaternion(tmp_path):
    t = np.linspace(0.0, 2.0, 201)
    tilt = 0.05 * (t - 1.0)

    rotation = Rotation.from_rotvec(np.stack([tilt, 0 * t, 0.4 * t], axis=1)).as_matrix()
    base = pd.DataFrame({"t": t, "x": 0.01 * t, "y": 0.0, "z": models.HOME_HEIGHT})
    euler, quaternion = base.copy(), base.copy()
    euler[["alpha", "beta", "gamma"]] = euler_from_rotation(rotation)
    quaternion[["qw", "qx", "qy", "qz"]] = quaternion_from_rotation(rotation)
    write_table(euler, tmp_path / "e.csv")
    write_table(quaternion, tmp_path / "q.csv")
    a = run("simulate", "--trajectory", tmp_path / "e.csv", "--out", tmp_path / "e_out.csv")
    b = run("simulate", "--trajectory", tmp_path / "q.csv", "--out", tmp_path / "q_out.csv")
    assert a.exit_code == 0 and b.exit_code == 0
    found = warnings_of(a)
    assert len(found) == 1 and "near beta = 0" in found[0] and "at row 101" in found[0]
    assert "give the orientation as a quaternion" in found[0]
    assert warnings_of(b) == []
    np.testing.assert_allclose(read_table(tmp_path / "e_out.csv").to_numpy(),
                               read_table(tmp_path / "q_out.csv").to_numpy(), atol=1e-8)


def _outside_stroke(tmp_path, chunked: bool) -> Path:
    frame = trajectory(300 if chunked else 60)
    frame.loc[20:24, "z"] = 1.5
    path = tmp_path / "t.csv"
    write_table(frame, path)
    return path


@pytest.mark.parametrize("chunked", [False, True])
def test_flagged_steps_warn_with_indices(tmp_path, chunked):
    path = _outside_stroke(tmp_path, chunked)
    out = tmp_path / "o.csv"
    result = run("simulate", "--trajectory", path, "--out", out, "--chunk",
                 "100" if chunked else "100000")
    assert result.exit_code == 0
    found = warnings_of(result)
    assert len(found) == 1
    assert "steps flagged (leg length outside the stroke" in found[0]
    assert "steps 2" in found[0]                     # the indices, e.g. "steps 20, 21, ..."
    frame = read_table(out)
    flagged = np.flatnonzero(frame["flag"].to_numpy())
    assert {20, 21, 22, 23, 24} <= set(flagged.tolist())
    assert f"{len(flagged)} flagged" in result.stdout


@pytest.mark.parametrize("chunked", [False, True])
def test_strict_exits_1_and_writes_nothing(tmp_path, chunked):
    path = _outside_stroke(tmp_path, chunked)
    out = tmp_path / "o.csv"
    message = error_of(run("simulate", "--trajectory", path, "--out", out, "--strict",
                           "--chunk", "100" if chunked else "100000"), code=1)
    assert "steps flagged (leg length outside the stroke" in message
    assert "steps 2" in message and "--strict" in message
    assert not out.exists() and no_leftovers(tmp_path)


def test_keyboard_interrupt_exit_130_and_no_output(tmp_path, monkeypatch):
    path = tmp_path / "t.csv"
    write_table(trajectory(400), path)
    out = tmp_path / "o.parquet"
    original = simulate_run.evaluate_outputs     # what simulate evaluates each chunk with
    calls = []

    def interrupted(evaluator, motion, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(evaluator, motion, *args, **kwargs)

    monkeypatch.setattr(simulate_run, "evaluate_outputs", interrupted)
    message = error_of(run("simulate", "--trajectory", path, "--out", out, "--chunk", "100"),
                       code=130)
    assert message == "interrupted; no output was left half-written"
    assert not out.exists() and no_leftovers(tmp_path)


# -- other commands: bad input is one line too -----------------------------------------------


def test_discover_missing_force_column(tmp_path):
    frame = trajectory()
    for i in range(1, 6):
        frame[f"F{i}"] = 1.0
    path = tmp_path / "measured.csv"
    write_table(frame, path)
    message = error_of(run("discover", "--measured", path, "--out", tmp_path / "d"))
    assert message == f"{path}: missing column 'F6' (measured data need F1..F6)"


def test_paper_with_a_bad_platform(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(tomli_w.dumps(_with(lambda d: d["legs"].__setitem__("wieght", True))))
    message = error_of(run("paper", "--out", tmp_path / "paper", "--platform", path,
                           "--no-plots"))
    assert message == f"{path}: legs.wieght: unknown key (did you mean 'weight'?)"


# -- 6. stale generated/ and a failed compilation (fresh processes) -------------------------


def gsfric(*args, env: dict, cwd: Path):
    full = {**os.environ, **env}
    return subprocess.run([sys.executable, "-m", "gsfric.cli", *map(str, args)], cwd=cwd,
                          env=full, capture_output=True, text=True)


@pytest.fixture
def generated_copy(tmp_path) -> Path:
    copy = tmp_path / "generated"
    shutil.copytree(ROOT / "generated", copy)
    return copy


def _one_error(run_result, code: int) -> str:
    assert run_result.returncode == code, run_result.stderr
    got = [line for line in run_result.stderr.splitlines() if line]
    assert len(got) == 1, run_result.stderr
    assert got[0].startswith("gsfric: error: ")
    return got[0]


def test_altered_generated_c_file_says_how_to_fix(tmp_path, good, generated_copy):
    c_file = generated_copy / "gsfric_model.c"
    c_file.write_text(c_file.read_text() + "\n/* edited by hand */\n")
    result = gsfric("simulate", "--trajectory", good, "--out", tmp_path / "o.csv", cwd=tmp_path,
                    env={"GSFRIC_GENERATED": str(generated_copy)})
    line = _one_error(result, 3)
    assert "gsfric_model.c" in line and "manifest" in line and "gsfric derive" in line
    assert not (tmp_path / "o.csv").exists()


def test_altered_manifest_says_how_to_fix(tmp_path, good, generated_copy):
    manifest = generated_copy / "manifest.json"
    text = manifest.read_text()

    data = json.loads(text)
    name = next(iter(data["files"]))
    data["files"][name] = "0" * 64
    manifest.write_text(json.dumps(data))
    result = gsfric("simulate", "--trajectory", good, "--out", tmp_path / "o.csv", cwd=tmp_path,
                    env={"GSFRIC_GENERATED": str(generated_copy)})
    line = _one_error(result, 3)
    assert name in line and "gsfric derive" in line


@pytest.mark.parametrize("damage", ["invalid", "missing"])
def test_broken_manifest_says_how_to_fix(tmp_path, good, generated_copy, damage):
    manifest = generated_copy / "manifest.json"
    if damage == "missing":
        manifest.unlink()
    else:
        manifest.write_text("{ not json")
    result = gsfric("simulate", "--trajectory", good, "--out", tmp_path / "o.csv", cwd=tmp_path,
                    env={"GSFRIC_GENERATED": str(generated_copy)})
    line = _one_error(result, 3)
    assert "manifest.json" in line and "gsfric derive" in line


# -- 7. the commands, loaded when they run ---------------------------------------------------


def test_the_command_list_is_the_commands_own_help():
    """``gsfric --help`` lists each command from ``gsfric.cli.COMMANDS`` without loading it: the
    text there is the first paragraph of the command's own help."""
    with click.Context(main, info_name="gsfric") as ctx:
        assert main.list_commands(ctx) == sorted(COMMANDS)
        for name in COMMANDS:
            command = main.get_command(ctx, name)
            assert command.name == name
            assert command.help.split("\n\n")[0] == COMMANDS[name]
        assert main.get_command(ctx, "no-such-command") is None


def test_help_loads_no_command():
    code = ("import sys; from gsfric.cli import main; sys.argv = ['gsfric', '--help']\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.startswith('gsfric.commands.')), "
            "'numpy' in sys.modules, file=sys.stderr)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.stderr.split()[-2:] == ["['gsfric.commands.common']", "False"]
    assert "simulate  Evaluate a motion: actuator forces, reactions and friction at" in \
        result.stdout
