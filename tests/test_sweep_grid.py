"""gsfric sweep on an even grid of variants, the labelled envelope lines, and the explicit
note when the platform gives no limits."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from gsfric import io, models
from gsfric.cli import main
from gsfric.errors import InputError
from gsfric.sweep import load
from gsfric.sweep.plot import case_labels
from gsfric.sweep.variants import make_variants

RANGES = {"platform.payload_mass": (0.0, 8.0), "friction.joint_coulomb": (0.02, 0.1)}


def test_grid_is_every_combination_of_even_values_ends_included():
    platforms, table = make_variants(models.reference_platform(), RANGES, grid=3)
    assert len(platforms) == 1 + 9 and [row["variant"] for row in table] == list(range(10))
    pairs = {(row["platform.payload_mass"], row["friction.joint_coulomb"]) for row in table[1:]}
    assert pairs == {(m, c) for m in (0.0, 4.0, 8.0) for c in (0.02, 0.06, 0.1)}
    for platform, row in zip(platforms[1:], table[1:]):
        assert platform.platform.payload_mass == row["platform.payload_mass"]
        assert platform.friction.joint_coulomb == pytest.approx(row["friction.joint_coulomb"])
    # random draws stay the default: the same count gives other, uneven values
    _, drawn = make_variants(models.reference_platform(), RANGES, samples=9, seed=0)
    assert {(r["platform.payload_mass"], r["friction.joint_coulomb"]) for r in drawn[1:]} != pairs


@pytest.mark.parametrize("kwargs, words", [
    (dict(vary=RANGES, grid=0), "grid: expected an integer >= 1"),
    (dict(vary={}, grid=3), "grid: give the ranges"),
    (dict(vary=RANGES, tolerances={"platform.mass": 0.1}, grid=3), "grid: not with tolerances"),
    (dict(vary=RANGES, grid=1000), "grid: 1000 values of 2 parameters make 1000000 variants"),
])
def test_grid_errors_are_one_line(kwargs, words):
    with pytest.raises(InputError) as error:
        make_variants(models.reference_platform(), **kwargs)
    assert words in str(error.value) and "\n" not in str(error.value)


def test_case_labels_name_the_varied_values():
    envelopes = pd.DataFrame({"motion": ["a.csv"] * 2, "variant": [0, 1]})
    variants = pd.DataFrame([{"variant": 0, "platform.payload_mass": 3.0},
                             {"variant": 1, "platform.payload_mass": 8.0}])
    labels = case_labels(envelopes, variants)
    assert labels == {("a.csv", 0): "payload_mass=3 (nominal)", ("a.csv", 1): "payload_mass=8"}


@pytest.fixture(scope="module")
def trajectory(tmp_path_factory):
    folder = tmp_path_factory.mktemp("grid")
    motion = models.random_motion(np.random.default_rng(0), np.linspace(0, 1, 101))
    path = folder / "motion.csv"
    io.write_table(motion.to_frame(), path)
    return path


def test_cli_grid_and_no_limits_note(trajectory, tmp_path):
    runner = CliRunner()
    out = tmp_path / "sweep"
    result = runner.invoke(main, ["sweep", "--out", str(out), "--trajectories", str(trajectory),
                                  "--vary", "platform.payload_mass=0:8", "--grid", "3",
                                  "--scheduler", "serial", "--no-progress", "--no-plots"])
    assert result.exit_code == 0, result.output
    info = json.loads((out / "sweep.json").read_text())
    assert info["limits"] == {} and info["limits_check"] == "no limits given: nothing checked"
    assert info["variants_drawn"].startswith("3 on an even grid")
    assert "limits: no limits given" in result.output and "nothing checked" in result.output
    assert "variants: 3 on an even grid" in result.output
    text = repr(load(out))
    assert len(text) < 300 and "4 cases" in text and "nothing checked" in text
    both = runner.invoke(main, ["sweep", "--out", str(tmp_path / "x"), "--trajectories",
                                str(trajectory), "--vary", "platform.payload_mass=0:8",
                                "--grid", "3", "--variants", "4"])
    assert both.exit_code == 2 and "--grid" in both.output and "--variants" in both.output
