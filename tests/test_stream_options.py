"""``simulate``'s output options: column groups, float32, plain Parquet encoding, overlap."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

import gsfric
from gsfric import models
from gsfric.cli import main
from gsfric.evaluation.columns import DEFAULT_GROUPS, GROUPS
from gsfric.evaluation.evaluator import Evaluator, evaluate_outputs
from gsfric.io.readers import read_trajectory
from gsfric.io.tables import write_table
from gsfric.platform.catalog import apply_sensor
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.signal.savgol import savgol_core, savgol_filter
from gsfric.simulate import writer
from gsfric.simulate.differentiate import iter_motions
from gsfric.simulate.outputs import FLOAT32_RTOL
from gsfric.simulate.run import simulate_file
from gsfric.trajectory import Motion


def _trajectory(path, n=700, rate=200.0):
    t = np.arange(n) / rate
    motion = models.sinusoidal(t)
    q = quaternion_from_rotation(motion.rotation)
    frame = pd.DataFrame({"t": t, "x": motion.position[:, 0], "y": motion.position[:, 1],
                          "z": motion.position[:, 2], "qw": q[:, 0], "qx": q[:, 1],
                          "qy": q[:, 2], "qz": q[:, 3]})
    write_table(frame, path)
    return path


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    folder = tmp_path_factory.mktemp("full")
    path = _trajectory(folder / "t.csv")
    out = folder / "all.parquet"
    simulate_file(path, out, chunk=200, window=9, columns=("all",))
    return path, pd.read_parquet(out), out


def test_column_groups_select_columns_with_the_same_values(full, tmp_path):
    path, every, _ = full
    out = tmp_path / "some.parquet"
    result = _run("simulate", "--trajectory", path, "--out", out, "--chunk", 200, "--window",
                  9, "--columns", "lengths,forces")
    assert result.exit_code == 0, result.output
    some = pd.read_parquet(out)
    expected = ["t"] + [f"F{i}" for i in range(1, 7)] + [f"D{i}" for i in range(1, 7)] + \
        ["flag"]
    assert list(some.columns) == expected
    pd.testing.assert_frame_equal(some, every[expected])


def test_all_columns_are_every_group_in_the_result_frame_order(full):
    _, every, _ = full
    truth = models.sinusoidal(np.linspace(0, 1, 50))
    motion = Motion.from_samples(truth.t, truth.position, quaternion=truth.quaternion())
    frame_columns = list(gsfric.evaluate(models.reference_platform(), motion).to_frame())
    assert list(every.columns) == frame_columns
    # a motion given with its rates has no differentiation uncertainty: no such columns
    given = list(gsfric.evaluate(models.reference_platform(), truth).to_frame())
    assert given == [c for c in frame_columns if not c.startswith("sigma_F") and c != "rest"]


CONTRACT = (["t"] + [f"F{i}" for i in range(1, 7)] + [f"sigma_F{i}" for i in range(1, 7)]
            + ["rest"]
            + [f"{name}{i}" for name in ("Ffr", "MfrE_s", "MfrC_s", "Ffr_s") for i in range(1, 7)]
            + [f"{name}{a}{i}" for name in ("RE", "RC") for i in range(1, 7) for a in "xyz"]
            + [f"MC{i}" for i in range(1, 7)] + ["flag"])
"""The columns a default simulate output promises: 81 values a step."""


def test_default_columns_hold_the_documented_set_with_the_same_values(full, tmp_path):
    path, every, _ = full
    out = tmp_path / "default.parquet"
    result = _run("simulate", "--trajectory", path, "--out", out, "--chunk", 200, "--window", 9,
                  "--quiet")
    assert result.exit_code == 0, result.output
    default = pd.read_parquet(out)
    assert len(CONTRACT) == 81 and sorted(default.columns) == sorted(CONTRACT)
    assert list(default.columns) == [c for c in every.columns if c in CONTRACT]
    pd.testing.assert_frame_equal(default, every[list(default.columns)])


def test_every_group_but_the_defaults_is_named_in_the_help():
    result = _run("simulate", "--help")
    text = " ".join(result.output.split())
    for group in GROUPS:
        assert group in text, group
    assert "[default: " + ",".join(DEFAULT_GROUPS) + "]" in text


def test_float32_within_its_documented_error(full, tmp_path):
    path, every, _ = full
    out = tmp_path / "f32.parquet"
    simulate_file(path, out, chunk=200, window=9, float32=True)
    small = pd.read_parquet(out)
    assert small["t"].dtype == np.float64 and small["flag"].dtype == np.int64
    values = [c for c in small.columns if c not in ("t", "flag")]
    assert all(small[c].dtype == np.float32 for c in values)
    a, b = small[values].to_numpy(np.float64), every[values].to_numpy()
    assert np.all(np.abs(a - b) <= FLOAT32_RTOL * np.abs(b))
    np.testing.assert_array_equal(small["t"], every["t"])


def test_parquet_floats_are_written_without_dictionary_encoding(full):
    _, _, out = full
    meta = pq.ParquetFile(out).metadata
    assert meta.num_row_groups == 4                   # one per chunk of 200 steps
    for g in range(meta.num_row_groups):
        for c in range(meta.num_columns):
            column = meta.row_group(g).column(c)
            if column.path_in_schema == "flag":
                continue
            assert column.physical_type == "DOUBLE"
            assert not any("DICTIONARY" in e for e in column.encodings), column.encodings


def test_unknown_column_group_is_one_line_exit_2(tmp_path):
    path = _trajectory(tmp_path / "t.csv", n=100)
    result = _run("simulate", "--trajectory", path, "--out", tmp_path / "o.csv", "--columns",
                  "forces,torques")
    assert result.exit_code == 2
    assert result.output.strip().splitlines() == [
        "gsfric: error: --columns: unknown group 'torques'; choose from forces, uncertainty, "
        "friction, reactions, friction_detail, frictionless, lengths (comma-separated) or all"]
    assert not (tmp_path / "o.csv").exists()


def test_streamed_chunks_are_written_in_order(full):
    """The worker thread writes chunks in order: the rows are the file's steps in order."""
    path, every, _ = full
    assert np.all(np.diff(every["t"].to_numpy()) > 0)
    assert len(every) == 700


@pytest.mark.parametrize("delay", [0.0175, -0.0175, 0.26])
def test_streamed_sensor_delay_equals_the_whole_record(tmp_path, delay):
    """time_offset reaches across chunk starts (and, at 0.26 s, over a whole chunk of 200
    steps): the streamed F is the whole record's shifted F, bit for bit, and the evaluation
    of the whole file to rounding."""
    path = _trajectory(tmp_path / "t.parquet")              # 700 steps at 200 Hz
    base = models.reference_platform()
    gains = np.array([0.01, -0.02, 0.0, 0.03, 0.0, -0.01])
    sensor = base.with_effect("time_offset", delay=delay).with_effect(
        "force_scale", **{f"g{i + 1}": g for i, g in enumerate(gains)})
    plain, shifted = tmp_path / "plain.parquet", tmp_path / "shifted.parquet"
    simulate_file(path, plain, base, chunk=200, window=9, columns=["forces"])
    summary = simulate_file(path, shifted, sensor, chunk=200, window=9,
                                   columns=["forces", "lengths"])
    assert summary.chunks == 4
    plain, shifted = pd.read_parquet(plain), pd.read_parquet(shifted)
    names = [f"F{i}" for i in range(1, 7)]
    t = plain["t"].to_numpy()
    expected = apply_sensor(t, plain[names].to_numpy(), gains, delay)
    np.testing.assert_array_equal(shifted[names].to_numpy(), expected)
    np.testing.assert_array_equal(shifted["t"].to_numpy(), t)
    whole = gsfric.evaluate(sensor, read_trajectory(path, window=9))
    np.testing.assert_allclose(shifted[names].to_numpy(), whole.F, rtol=1e-9, atol=1e-9)
    # shifted within each chunk alone, F is wrong next to the chunk boundaries
    per_chunk = np.vstack([apply_sensor(t[s:s + 200], plain[names].to_numpy()[s:s + 200],
                                        gains, delay) for s in range(0, 700, 200)])
    assert np.abs(per_chunk - expected).max() > 1e-3


def test_streamed_motions_are_the_validated_motions(full):
    """The reader builds its Motions without a second validation pass (``Motion._trusted``):
    each equals the Motion validated from the same arrays, read-only and C-contiguous, and
    its rotations are rotations."""
    path, _, _ = full
    chunks = list(iter_motions(path, chunk=200, window=9))
    assert sum(len(c.motion) for c in chunks) == 700
    for motion in (c.motion for c in chunks):
        fields = ("t", "position", "rotation", "velocity", "omega", "acceleration", "alpha")
        checked = Motion(*(np.array(getattr(motion, f)) for f in fields))
        assert checked == motion
        for f in fields:
            a = getattr(motion, f)
            assert a.dtype == np.float64 and a.flags.c_contiguous and not a.flags.writeable
        R = motion.rotation
        np.testing.assert_allclose(np.einsum("nji,njk->nik", R, R),
                                   np.broadcast_to(np.eye(3), R.shape), atol=1e-12)


@pytest.mark.parametrize("polyorder", [2, 3, 4])
@pytest.mark.parametrize("window", [5, 7, 9, 21])
def test_filter_on_the_core_is_the_whole_signals_to_the_bit(window, polyorder):
    """Windows and orders whose weights are even, odd and neither (scipy.ndimage sums each
    kind its own way): the streamed filter gives savgol_filter's values exactly."""
    rng = np.random.default_rng(window * 10 + polyorder)
    y = np.cumsum(rng.normal(size=(400, 4)), axis=0) * 0.01 + 0.5
    step = 0.004
    h = window // 2
    got = savgol_core(y, window, polyorder, step, h + 3, 400 - h - 5)
    for k in (0, 1, 2):
        expected = savgol_filter(y, window, polyorder, k) / step**k
        np.testing.assert_array_equal(got[k], expected[h + 3:400 - h - 5], err_msg=str(k))
        assert got[k].flags.c_contiguous


def test_selected_outputs_and_flags_equal_the_full_evaluation():
    platform = models.reference_platform()
    motion = models.sinusoidal(np.linspace(0.0, 2.0, 401))
    evaluator = Evaluator(platform)
    full = evaluator.evaluate_quiet(motion)
    buffers: dict = {}
    for _ in range(2):                                  # the second call reuses the buffers
        arrays, flag = evaluate_outputs(evaluator, motion, ["R_E", "F", "MfrC_s"],
                                        buffers=buffers)
        assert sorted(arrays) == ["F", "MfrC_s", "R_E"]
        np.testing.assert_array_equal(arrays["R_E"], full.R_E.reshape(401, 18))
        np.testing.assert_array_equal(arrays["F"], full.F)
        np.testing.assert_array_equal(arrays["MfrC_s"], full.MfrC_s)
        np.testing.assert_array_equal(flag, full.flag)


def test_default_and_all_columns_flag_the_same_steps(tmp_path):
    """Fewer outputs evaluated for the default columns: the flags are still every output's."""
    n = 600
    t = np.arange(n) / 200.0
    motion = models.sinusoidal(t)
    position = motion.position.copy()
    position[[130, 131, 450], 2] = 1.5                  # legs beyond their stroke
    q = quaternion_from_rotation(motion.rotation)
    frame = pd.DataFrame({"t": t, "x": position[:, 0], "y": position[:, 1],
                          "z": position[:, 2], "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2],
                          "qz": q[:, 3]})
    path = tmp_path / "t.parquet"
    write_table(frame, path)
    with pytest.warns(gsfric.errors.GsfricWarning):
        a = simulate_file(path, tmp_path / "default.parquet", chunk=150, window=9)
    with pytest.warns(gsfric.errors.GsfricWarning):
        b = simulate_file(path, tmp_path / "all.parquet", chunk=150, window=9,
                                 columns=("all",))
    assert a.flagged == b.flagged > 0
    np.testing.assert_array_equal(a.flagged_steps, b.flagged_steps)
    default = pd.read_parquet(tmp_path / "default.parquet")
    every = pd.read_parquet(tmp_path / "all.parquet")
    np.testing.assert_array_equal(default["flag"], every["flag"])
    pd.testing.assert_frame_equal(default, every[list(default.columns)])


def test_flushing_while_writing_changes_nothing_in_the_file(full, tmp_path, monkeypatch):
    path, _, out = full
    monkeypatch.setattr(writer, "FLUSH_BYTES", 1)       # a request to the disk every chunk
    synced = []
    sync = getattr(os, "fdatasync", os.fsync)
    monkeypatch.setattr(os, "fdatasync" if hasattr(os, "fdatasync") else "fsync",
                        lambda fd: synced.append(fd) or sync(fd))
    again = tmp_path / "again.parquet"
    simulate_file(path, again, chunk=200, window=9, columns=("all",))
    assert 1 <= len(synced) <= 5                        # one at a time, in its own thread
    assert again.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("delay", [0.0, 0.0175])
def test_pieces_of_a_chunk_give_the_chunks_values(tmp_path, monkeypatch, delay):
    """A chunk evaluated and written in pieces (``EVALUATE_STEPS``, here 64 steps of chunks
    of 200) gives every value and flag of the chunk evaluated whole, with a sensor delay
    too; the summary counts the chunks read. sigma_F is interpolated between the same steps
    of the record but for a piece's last few steps (``force_sigma``): within a few percent."""
    path = _trajectory(tmp_path / "t.parquet")
    platform = models.reference_platform().with_effect("time_offset", delay=delay) \
        if delay else models.reference_platform()
    whole = tmp_path / "whole.parquet"
    simulate_file(path, whole, platform, chunk=200, window=9, columns=("all",))
    monkeypatch.setattr(gsfric.simulate.run, "EVALUATE_STEPS", 64)
    pieces = tmp_path / "pieces.parquet"
    summary = simulate_file(path, pieces, platform, chunk=200, window=9, columns=("all",))
    assert summary.chunks == 4 and summary.steps == 700
    assert pq.ParquetFile(pieces).metadata.num_row_groups > pq.ParquetFile(
        whole).metadata.num_row_groups
    got, want = pd.read_parquet(pieces), pd.read_parquet(whole)
    sigma = [f"sigma_F{i}" for i in range(1, 7)]
    np.testing.assert_allclose(got[sigma], want[sigma], rtol=0.05,
                               atol=0.05 * float(want[sigma].to_numpy().max()))
    pd.testing.assert_frame_equal(got.drop(columns=sigma), want.drop(columns=sigma))


def test_streamed_chunks_carry_their_rows_of_the_measured_forces(tmp_path):
    """Each chunk's carried columns are the file's F1..F6 of its own steps, and every chunk
    names the windows of the streamed file."""
    path = _trajectory(tmp_path / "t.csv", n=650)
    frame = pd.read_csv(path)
    for i in range(1, 7):
        frame[f"F{i}"] = np.arange(650) * 10.0 + i
    frame.to_csv(path, index=False)
    chunks = list(iter_motions(path, chunk=200, window=9))
    assert [c.start for c in chunks] == [0, 200, 400, 600]
    assert all(c.windows == (9, 9) for c in chunks)
    for c in chunks:
        rows = np.arange(c.start, c.start + len(c.motion))
        np.testing.assert_array_equal(c.carried["F3"], frame["F3"].to_numpy()[rows])
    whole, = iter_motions(path, chunk=1000, window=9)
    assert whole.windows == "whole" and len(whole.carried["F1"]) == 650
