"""The Python API as a user meets it: names, help, DataFrame input, repr, per-leg frames,
and the units that travel with the outputs (DataFrame.attrs, Parquet field metadata, the
`gsfric columns` listing and the README's table, all from gsfric.columns)."""

from __future__ import annotations

import gc
import re
import subprocess
import sys
from pathlib import Path

import click
import numpy as np
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

import gsfric
from gsfric import models
from gsfric.cli import main
from gsfric.errors import InputError
from gsfric.evaluation import columns
from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.memory import _POOL, POOL_MIN_BYTES, release_memory
from gsfric.platform import catalog
from gsfric.platform.catalog import describe

ROOT = Path(__file__).resolve().parent.parent


def test_lazy_names_are_listed_and_documented():
    names = dir(gsfric)
    for name in gsfric.__all__:
        assert name in names
        value = getattr(gsfric, name)
        doc = value.__doc__ or ""
        assert len(doc.strip().splitlines()) >= 1, name
    assert "Parameters" in gsfric.evaluate.__doc__ and "Returns" in gsfric.evaluate.__doc__
    # a fresh interpreter: dir() shows the lazy names before any of them is loaded
    out = subprocess.run([sys.executable, "-c", "import gsfric, sys; "
                          "print('evaluate' in dir(gsfric), 'numpy' in sys.modules)"],
                         capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "False"]


def test_evaluate_takes_a_dataframe_as_read_trajectory_reads_a_file(tmp_path, platform):
    motion = models.sinusoidal(np.linspace(0.0, 2.0, 201))
    frame = motion.to_frame()
    gsfric.io.write_table(frame, tmp_path / "m.csv")
    from_frame = gsfric.evaluate(platform, frame)
    from_file = gsfric.evaluate(platform, gsfric.read_trajectory(tmp_path / "m.csv"))
    np.testing.assert_array_equal(from_frame.F, from_file.F)
    # and it is the motion: the differentiated samples agree with the exact derivatives
    exact = gsfric.evaluate(platform, motion)
    assert np.max(np.abs(from_frame.F - exact.F)[10:-10]) < 0.01


def test_evaluate_rejects_a_bad_frame_in_one_line(platform):
    frame = models.sinusoidal(np.linspace(0.0, 1.0, 50)).to_frame()
    frame.loc[7, "y"] = np.nan
    with pytest.raises(InputError, match=r"^DataFrame: row 8: column 'y' is empty or NaN$"):
        gsfric.evaluate(platform, frame)
    with pytest.raises(TypeError, match="motion must be a gsfric.Motion or a pandas DataFrame"):
        gsfric.evaluate(platform, frame.to_numpy())


def test_result_repr_is_short_and_dir_shows_the_arrays(platform):
    result = gsfric.evaluate(platform, models.sinusoidal(np.linspace(0.0, 1.0, 2001)))
    text = repr(result)
    assert len(text.splitlines()) == 1 and len(text) < 400
    assert "2001 steps" in text and "R_E" in text
    assert {"F", "R_E", "MfrC_s"} <= set(dir(result))


def test_legs_frame_is_the_arrays_by_step_and_leg(platform):
    result = gsfric.evaluate(platform, models.sinusoidal(np.linspace(0.0, 1.0, 30)))
    legs = result.to_legs_frame()
    assert legs.index.names == ["step", "leg"] and len(legs) == 6 * 30
    for step, leg in ((0, 1), (17, 4), (29, 6)):
        row = legs.loc[(step, leg)]
        assert row["F"] == result.F[step, leg - 1]
        np.testing.assert_array_equal(row[["R_E_x", "R_E_y", "R_E_z"]].to_numpy(float),
                                      result.R_E[step, leg - 1])
    assert legs.attrs["units"]["R_E_x"] == "N" and legs.attrs["units"]["M_C"] == "N m"
    # per-joint analysis: the largest spherical-joint force per leg
    peak = np.sqrt((legs[["R_E_x", "R_E_y", "R_E_z"]] ** 2).sum(axis=1)).groupby(level="leg").max()
    np.testing.assert_allclose(peak.to_numpy(), np.linalg.norm(result.R_E, axis=2).max(axis=0))


def test_units_travel_with_frames_and_parquet(tmp_path, platform):
    result = gsfric.evaluate(platform, models.sinusoidal(np.linspace(0.0, 1.0, 30)))
    frame = result.to_frame()
    assert set(frame.attrs["units"]) == set(frame.columns)
    assert frame.attrs["units"]["REz3"] == "N" and frame.attrs["units"]["MfrC_s2"] == "N m"
    assert frame.attrs["units"]["t"] == "s" and frame.attrs["units"]["D6"] == "m"
    # the paper's friction scalars are never positive, as their description says
    assert "<= 0" in frame.attrs["descriptions"]["Ffr_s1"]
    assert (frame[[f"Ffr_s{i}" for i in range(1, 7)]].to_numpy() <= 0).all()
    gsfric.io.write_table(models.sinusoidal(np.linspace(0, 1, 60)).to_frame(), tmp_path / "m.csv")
    out = tmp_path / "o.parquet"
    assert CliRunner().invoke(main, ["simulate", "--trajectory", str(tmp_path / "m.csv"),
                                     "--out", str(out), "--quiet"]).exit_code == 0
    schema = pq.read_schema(out)
    for name in ("F1", "REx2", "MfrE_s6", "flag"):
        meta = schema.field(name).metadata
        assert meta[b"unit"].decode() == columns.units()[name]
        assert meta[b"description"]


def test_columns_listing_and_reference_table_come_from_one_source():
    listing = CliRunner().invoke(main, ["columns"]).output
    for column in columns.all_columns():
        assert column.label in listing
    table = CliRunner().invoke(main, ["columns", "--markdown"]).output.strip()
    assert table == columns.markdown_table()
    page = (ROOT / "docs" / "reference" / "columns.md").read_text()
    block = re.search(r"<!-- columns: begin.*?-->\n(.*?)\n<!-- columns: end -->", page, re.S)
    assert block, "docs/reference/columns.md has no generated output table"
    assert block.group(1).strip() == table, (
        "docs/reference/columns.md's table is stale: paste `gsfric columns --markdown`")


def test_effects_reference_table_comes_from_the_catalog():
    table = CliRunner().invoke(main, ["effects", "--markdown"]).output.strip()
    assert table == catalog.markdown_table()
    rows = table.splitlines()[2:]
    assert [row.split("`")[1] for row in rows] == [e["name"] for e in catalog.describe()]
    page = (ROOT / "docs" / "reference" / "effects.md").read_text()
    block = re.search(r"<!-- effects: begin.*?-->\n(.*?)\n<!-- effects: end -->", page, re.S)
    assert block, "docs/reference/effects.md has no generated table"
    assert block.group(1).strip() == table, (
        "docs/reference/effects.md's table is stale: paste `gsfric effects --markdown`")


def test_effects_listing_names_every_parameter_with_its_unit():

    out = CliRunner().invoke(main, ["effects"]).output
    for effect in describe():
        assert f"{effect['name']}: " in out
        for p in effect["parameters"]:
            assert re.search(rf"\n    {re.escape(p['name'])} = \S+ {re.escape(p['unit'] or '1')} ",
                             out)


def test_platform_template_reads_back_as_the_reference_platform(tmp_path):
    out = tmp_path / "p.toml"
    result = CliRunner().invoke(main, ["platform", "--template", "--out", str(out)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert "# kg" in text.replace("  ", " ") or "kg," in text
    assert gsfric.Platform.from_toml(out) == gsfric.reference_platform()


def test_every_option_has_help():
    ctx = click.Context(main)
    names = main.list_commands(ctx)
    assert len(names) >= 10

    def check(command, path):
        for param in command.params:
            if isinstance(param, click.Option) and not param.hidden:
                assert param.help, f"{path} {param.opts[0]} has no help"

    check(main, "gsfric")
    for name in names:
        command = main.get_command(ctx, name)
        assert command is not None and command.name == name
        check(command, f"gsfric {name}")


def test_a_dropped_result_memory_is_reused_for_the_next_with_the_same_values(platform):
    """Large result arrays live on blocks that come back when the caller drops them: the next
    evaluation of that size writes into the same memory (no new pages), with the values and
    flags of an evaluation into NumPy's own buffers, and a block in use is never handed out."""


    n = POOL_MIN_BYTES // (18 * 8) + 500
    rng = np.random.default_rng(5)
    first, second = (models.random_motion(rng, np.linspace(0, 4, n)) for _ in range(2))
    evaluator = Evaluator(platform)
    expected = evaluator.evaluate_quiet(second, buffers={})   # NumPy-owned arrays
    def blocks(result):
        return {a.ctypes.data for a in result.arrays.kept().values()
                if a.nbytes >= POOL_MIN_BYTES}

    result = evaluator.evaluate_quiet(first)
    where = blocks(result)
    assert where and all(a % 64 == 0 for a in where)
    assert result.R_E.flags.c_contiguous and result.R_E.flags.writeable
    kept = evaluator.evaluate_quiet(first)
    assert not blocks(kept) & where
    del result
    gc.collect()
    again = evaluator.evaluate_quiet(second)
    assert blocks(again) == where
    for name, values in expected.arrays.kept().items():
        assert again.arrays[name].tobytes() == values.tobytes(), name
    assert again.flag.tobytes() == expected.flag.tobytes()
    assert np.array_equal(kept.R_E, evaluator.evaluate_quiet(first, buffers={}).R_E)
    del again, kept
    gc.collect()
    assert 0 < _POOL._kept <= _POOL.keep
    release_memory()
    assert _POOL._kept == 0


def test_the_memory_kept_for_reuse_is_bounded(platform):


    evaluator = Evaluator(platform)
    rng = np.random.default_rng(6)
    base = POOL_MIN_BYTES // (6 * 8)
    old = _POOL.keep
    release_memory()
    _POOL.keep = 8 * POOL_MIN_BYTES
    try:
        for n in (base + 11, 2 * base + 3, 3 * base + 1):
            evaluator.evaluate_quiet(models.random_motion(rng, np.linspace(0, 4, n)))
            gc.collect()
            assert 0 < _POOL._kept <= _POOL.keep
    finally:
        _POOL.keep = old
        release_memory()


def test_dir_of_gsfric_lists_only_public_names():
    out = subprocess.run([sys.executable, "-c", "import gsfric; gsfric.evaluate; "
                          "gsfric.discover; print(' '.join(dir(gsfric)))"],
                         capture_output=True, text=True, check=True).stdout.split()
    assert {"evaluate", "discover", "Discovery", "Platform", "Result"} <= set(out)
    leftovers = [n for n in out if n in ("annotations", "importlib", "_importlib")
                 or (n.startswith("_") and n != "__version__")]
    assert not leftovers
    assert set(gsfric.__all__) <= set(out)


def test_result_summary_is_the_long_form_with_the_peaks_per_leg(platform):
    result = gsfric.evaluate(platform, models.sinusoidal(np.linspace(0.0, 1.0, 201)))
    lines = result.summary().splitlines()
    assert lines[0] == repr(result) and lines[-1] == "flags: none"
    head = lines.index(next(line for line in lines if line.startswith("leg ")))
    assert "|F| (N)" in lines[head] and "|Ffr| (N)" in lines[head]
    table = np.array([[float(v) for v in line.split()] for line in lines[head + 1:head + 7]])
    assert table[:, 0].tolist() == [1, 2, 3, 4, 5, 6]
    assert table[:, 1] == pytest.approx(np.abs(result.F).max(axis=0), rel=1e-3)
    # each peak's time is the step where it is reached, from the first step
    at = np.abs(result.F).argmax(axis=0)
    assert table[:, 2] == pytest.approx(result.t[at] - result.t[0], abs=1e-3)
    # the friction is the one of the file's Ffr1..Ffr6 (to_frame)
    frame = result.to_frame()
    ffr = np.abs(frame[[f"Ffr{i}" for i in range(1, 7)]].to_numpy()).max(axis=0)
    assert table[:, 3] == pytest.approx(ffr, rel=1e-3)
