"""Real log files: column maps, units, roll/pitch/yaw, wrapping counters, extra columns.

The worked example of docs/howto/read-a-log.md is run as written (its Python and its TOML) and checked
against the motion it was made from.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from gsfric import models
from gsfric.cli import main
from gsfric.errors import GsfricWarning, IgnoredColumnsWarning, InputError
from gsfric.io.logs import ColumnReader, LogFormat
from gsfric.io.readers import read_measured, read_trajectory
from gsfric.io.tables import read_table, write_table
from gsfric.signal.rotations import rotation_from_quaternion
from gsfric.simulate.differentiate import iter_motions
from gsfric.simulate.run import simulate_file

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "howto" / "read-a-log.md"


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", DOC.read_text(), flags=re.S)


def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) about base axis 0, 1 or 2, written out by hand."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros((len(angle), 3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[:, axis, axis] = 1
    R[:, i, i] = R[:, j, j] = c
    R[:, i, j], R[:, j, i] = -s, s
    return R


@pytest.fixture
def controller(tmp_path, monkeypatch):
    """The docs' controller log and its description, written by the docs' own code."""
    monkeypatch.chdir(tmp_path)
    python, = [b for b in _blocks("python") if "controller.csv" in b and "to_csv" in b]
    namespace: dict = {}
    exec(compile(python, str(DOC), "exec"), namespace)
    toml, = [b for b in _blocks("toml") if "C2H time (us)" in b]
    (tmp_path / "controller.toml").write_text(toml)
    return tmp_path, namespace["motion"]


def test_docs_controller_log_reads_as_the_motion_it_was_made_from(controller):
    folder, motion = controller
    fmt = LogFormat.from_toml(folder / "controller.toml")
    with pytest.warns(GsfricWarning) as caught:
        read = read_trajectory(folder / "controller.csv", log_format=fmt)
    messages = [str(w.message) for w in caught]
    assert any("row 501: time counter 'C2H time (us)' wraps around" in m for m in messages)
    assert any("1 column ignored" in m for m in messages)
    assert [w.message.names for w in caught if hasattr(w.message, "names")] == [("State",)]
    assert not any("Temp (C)" in m for m in messages)        # kept, so not "ignored"
    # time: the counter unwrapped, in s, uniform at 100 Hz across the wrap
    assert read.t[0] == pytest.approx((2**32 - 5_000_000) * 1e-6)
    np.testing.assert_allclose(np.diff(read.t), 0.01, rtol=0, atol=1e-9)
    # mm and deg converted; roll/pitch/yaw "xyz" is the motion's Rz Ry Rx
    # (the motion is smoothed by the differentiation: equal to its fit, ~1e-9 at the ends)
    np.testing.assert_allclose(read.position, motion.position, atol=1e-7)
    np.testing.assert_allclose(read.rotation, motion.rotation, atol=1e-7)
    np.testing.assert_allclose(_raw_rotation(folder / "controller.csv", fmt), motion.rotation,
                               atol=1e-12)


def test_roll_pitch_yaw_conventions_against_hand_written_matrices(tmp_path):
    rng = np.random.default_rng(7)
    n = 40
    angles = rng.uniform(-0.4, 0.4, (n, 3))
    frame = pd.DataFrame({"t": np.arange(n) * 0.01, "x": 0.0, "y": 0.0, "z": 0.8})
    frame[["roll", "pitch", "yaw"]] = np.degrees(angles)
    write_table(frame, tmp_path / "rpy.csv")
    roll, pitch, yaw = angles.T
    expected = {"xyz": _rot(2, yaw) @ _rot(1, pitch) @ _rot(0, roll),
                "XYZ": _rot(0, roll) @ _rot(1, pitch) @ _rot(2, yaw)}
    for convention, R in expected.items():
        fmt = LogFormat(units={k: "deg" for k in ("roll", "pitch", "yaw")}, angles=convention)
        raw = _raw_rotation(tmp_path / "rpy.csv", fmt)
        np.testing.assert_allclose(raw, R, atol=1e-12)
    assert np.max(np.abs(expected["xyz"] - expected["XYZ"])) > 0.05


def _raw_rotation(path, fmt):
    """The rotation of every row as read (before differentiation)."""
    frame = read_table(path)
    reader = ColumnReader(path, fmt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GsfricWarning)    # checked elsewhere
        reader.check(list(frame.columns))
        columns = reader.read(frame)
    q = np.stack([columns[k] for k in ("qw", "qx", "qy", "qz")], axis=1)
    return rotation_from_quaternion(q)


def test_a_wrapping_counter_streamed_in_chunks_gives_the_whole_file(tmp_path):
    """A wrap inside the second chunk and a chunk boundary: the same times as read whole."""
    n = 500
    counts = (2**16 - 3000 + 10 * np.arange(n)) % 2**16     # a 16-bit counter, 10 us steps
    motion = models.sinusoidal(np.arange(n) * 1e-5 * 2000)
    frame = motion.to_frame()[["x", "y", "z", "qw", "qx", "qy", "qz"]]
    frame.insert(0, "tick", counts.astype(np.uint16))
    write_table(frame, tmp_path / "log.parquet")
    fmt = LogFormat(columns={"t": "tick"}, units={"t": "us"})
    with pytest.warns(GsfricWarning, match="row 301: time counter 'tick' wraps around "
                                           r"\(modulus 65536\)"):
        whole = read_trajectory(tmp_path / "log.parquet", log_format=fmt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GsfricWarning)
        parts = list(iter_motions(tmp_path / "log.parquet", chunk=120, window=15,
                                  log_format=fmt))
    t = np.concatenate([p.motion.t for p in parts])
    np.testing.assert_array_equal(t, whole.t)
    np.testing.assert_allclose(np.diff(t), 1e-5, rtol=0, atol=1e-12)


def test_a_real_decrease_of_the_counter_is_still_an_error(tmp_path):
    counts = np.arange(30) * 100
    counts[12] = 50                                     # backwards by far less than 2**16/2
    frame = models.sinusoidal(np.arange(30) * 1e-4).to_frame()
    frame["t"] = counts
    write_table(frame, tmp_path / "log.csv")
    with pytest.raises(InputError, match=r"row 13: t = 4.99+[0-9]*e-05 is less than t = 0.001[0-9]* in row 12"):
        read_trajectory(tmp_path / "log.csv", log_format=LogFormat(units={"t": "us"}))


def _cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def test_simulate_a_measured_file_writes_measured_forces_residuals_and_kept_columns(tmp_path):
    measured = tmp_path / "measured.csv"
    assert _cli("synth", "--out", measured, "--samples", "400", "--noise", "0",
                "--seed", "3").exit_code == 0
    frame = read_table(measured)
    frame["Temp (C)"] = np.linspace(30.0, 31.0, len(frame))
    frame["State"] = "run"
    write_table(frame, measured)
    out = tmp_path / "out.parquet"
    result = _cli("simulate", "--trajectory", measured, "--out", out, "--keep-columns",
                  "Temp (C)")
    assert result.exit_code == 0, result.output
    assert "1 column ignored" in result.stderr
    got = pd.read_parquet(out)
    for i in range(1, 7):
        np.testing.assert_array_equal(got[f"F{i}_measured"], frame[f"F{i}"])
        np.testing.assert_array_equal(got[f"F{i}_residual"], frame[f"F{i}"] - got[f"F{i}"])
    np.testing.assert_array_equal(got["Temp (C)"], frame["Temp (C)"])
    # synthetic data without noise or hidden effects: the model explains it
    residual = got[[f"F{i}_residual" for i in range(1, 7)]].to_numpy()[20:-20]
    forces = got[[f"F{i}" for i in range(1, 7)]].to_numpy()[20:-20]
    assert np.sqrt(np.mean(residual**2)) < 0.01 * np.sqrt(np.mean(forces**2))


def test_streamed_simulate_carries_columns_row_by_row(tmp_path):
    """Chunks and their overlaps must not shift a kept column against its rows."""
    n = 300
    frame = models.sinusoidal(np.arange(n) / 100.0).to_frame()
    frame["row"] = np.arange(n)
    write_table(frame, tmp_path / "m.csv")
    out = tmp_path / "o.csv"
    result = _cli("simulate", "--trajectory", tmp_path / "m.csv", "--out", out, "--chunk",
                  "70", "--window", "11", "--keep-columns", "row", "--quiet")
    assert result.exit_code == 0, result.output
    assert result.stdout == ""
    got = read_table(out)
    np.testing.assert_array_equal(got["row"], np.arange(n))
    np.testing.assert_allclose(got["t"], frame["t"])


@pytest.mark.parametrize(("args", "expected"), [
    (("--column-map", "x=Xpos"), "column map x = 'Xpos': no such column"),
    (("--column-map", "xx=X"), "column map: unknown gsfric column 'xx' (did you mean 'x'?)"),
    (("--units", "x=ft"), "units: 'x' in 'ft': use one of m, cm, mm, um"),
    (("--units", "t=deg"), "units: 't' in 'deg': use one of s, ms, us, ns"),
    (("--column-map", "x"), "--column-map: expected name=value, got 'x'"),
    (("--keep-columns", "Temp"), "column 'Temp' to keep: no such column"),
    (("--column-map", "x=y"), "missing column 'y' (map the log's column"),
    (("--angles", "XYZ"), "has no roll, pitch, yaw columns (its orientation is qw, qx, qy, "
                          "qz), and no offset rotation"),
])
def test_bad_descriptions_are_one_line_exit_2_and_write_nothing(tmp_path, args, expected):
    frame = models.sinusoidal(np.arange(40) / 100.0).to_frame()
    write_table(frame, tmp_path / "m.csv")
    out = tmp_path / "o.csv"
    result = _cli("simulate", "--trajectory", tmp_path / "m.csv", "--out", out, *args)
    assert result.exit_code == 2, result.output
    lines = [x for x in result.stderr.splitlines() if x and "is stale" not in x]
    assert len(lines) == 1 and lines[0].startswith("gsfric: error: "), result.stderr
    assert expected in lines[0]
    assert not out.exists()


@pytest.mark.parametrize(("text", "expected"), [
    ('keep = 5\n', "keep: expected a column name or a list of them, got 5"),
    ('[units]\nqx = "rad"\n', "units: 'qx' is a quaternion without a unit: leave it out"),
    ('[offset]\nroll = 180\n', "offset.roll: 180 rad is more than a turn: degrees? give it in "
                                "rad (3.14159)"),
])
def test_bad_log_format_files_say_which_key(tmp_path, text, expected):
    (tmp_path / "f.toml").write_text(text)
    with pytest.raises(InputError, match=re.escape(expected)):
        LogFormat.from_toml(tmp_path / "f.toml")


def test_one_kept_column_is_a_name_and_the_others_are_named_in_the_warning(tmp_path):
    """``keep = "Mode"`` keeps the column Mode (not the letters M, o, d, e); a column neither
    mapped nor kept is named in the warning that it is ignored."""
    frame = models.sinusoidal(np.arange(60) / 100.0).to_frame()
    frame["Mode"], frame["State"] = 2.0, 3.0
    write_table(frame, tmp_path / "m.csv")
    (tmp_path / "f.toml").write_text('keep = "Mode"\n')
    with pytest.warns(IgnoredColumnsWarning, match=r"1 column ignored \(not gsfric inputs: "
                                                   r"'State';") as caught:
        motion = read_trajectory(tmp_path / "m.csv",
                                 log_format=LogFormat.from_toml(tmp_path / "f.toml"))
    assert len(motion) == 60 and caught[0].message.names == ("State",)


def test_read_measured_with_units(tmp_path):
    frame = models.sinusoidal(np.arange(40) / 100.0).to_frame()
    for i in range(1, 7):
        frame[f"F{i}"] = 0.1 * i                      # kN
        frame[f"len{i}"] = 700.0 + i                  # mm
    write_table(frame, tmp_path / "m.csv")
    fmt = LogFormat(columns={f"D{i}": f"len{i}" for i in range(1, 7)},
                    units={**{f"F{i}": "kN" for i in range(1, 7)},
                           **{f"D{i}": "mm" for i in range(1, 7)}})
    _, forces, lengths = read_measured(tmp_path / "m.csv", log_format=fmt)
    np.testing.assert_allclose(forces[0], 100.0 * np.arange(1, 7))
    np.testing.assert_allclose(lengths[0], 0.701 + 0.001 * np.arange(6))


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_progress_bar_has_a_total_on_request_and_is_absent_off_a_terminal(tmp_path, capsys,
                                                                          suffix):
    path = tmp_path / f"m{suffix}"
    write_table(models.sinusoidal(np.arange(250) / 100.0).to_frame(), path)
    simulate_file(path, tmp_path / "o.csv", chunk=100, window=11, progress=True)
    shown = capsys.readouterr().err
    assert "/250 [" in shown and "%" in shown      # a total, hence a percentage and an ETA
    simulate_file(path, tmp_path / "o.csv", chunk=100, window=11, progress=None)
    assert capsys.readouterr().err == ""           # stderr is not a terminal here
