"""The paper's 40-step evaluation: tables, platform, report, misprints, implied reactions, CLI."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from helpers import PAPER_MISPRINTS

from gsfric import models
from gsfric.cli import main
from gsfric.errors import InputError
from gsfric.evaluation.paper_constants import PAPER_JOINT_SPEED
from gsfric.paper import tables as paper
from gsfric.paper.report import run_paper
from gsfric.platform.description import Platform

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

SHARED_PAPER = Path(__file__).resolve().parents[1].parent / "shared" / "paper"
SHARED_CSV = {1: "table1_friction_moments_moving_platform_joints.csv",
              2: "table2_friction_moments_fixed_platform_joints.csv",
              3: "table3_friction_forces_prismatic_joints.csv"}



@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """One ``run_paper`` with plots, shared by the tests that read its files."""
    out = tmp_path_factory.mktemp("paper") / "out"
    return out, run_paper(out, mode="paper", plots=True)


@pytest.fixture(scope="module")
def run():
    return paper.evaluate_paper(mode="paper")


def test_run_paper_writes_every_file(written):
    out, paths = written
    names = [p.name for p in paths]
    assert names == ["table1.csv", "table2.csv", "table3.csv", "platform.toml", "table1.png",
                     "table2.png", "table3.png", "breakdown.png", "report.md"]
    assert all(p.parent == out and p.stat().st_size > 0 for p in paths)
    assert not list(out.glob(".*.tmp")), "a temporary file of an atomic write was left behind"
    for name in ("table1.png", "table2.png", "table3.png", "breakdown.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("number", [1, 2, 3])
def test_tables_have_the_papers_columns_and_40_negative_rows(written, number):
    out, _ = written
    ours = pd.read_csv(out / f"table{number}.csv")
    assert list(ours.columns) == list(paper.paper_table(number).columns)
    assert list(ours.columns) == paper.TABLES[number].columns
    assert len(ours) == models.PAPER_STEPS == 40
    assert ours["pos"].tolist() == list(range(1, 41))
    values = ours.iloc[:, 1:].to_numpy()
    assert np.isfinite(values).all()
    assert (values < 0).all(), "friction opposes the motion: every value is negative"


@pytest.mark.parametrize("number", [1, 2, 3])
def test_table_columns_match_the_shared_transcription(number):
    path = SHARED_PAPER / SHARED_CSV[number]
    if not path.exists():
        pytest.skip(f"{path} not present")
    shared = pd.read_csv(path, dtype=str)
    embedded = paper.paper_table(number, printed=True)
    assert list(shared.columns) == list(embedded.columns)
    assert shared.drop(columns="pos").equals(embedded.drop(columns="pos"))
    assert shared["pos"].astype(int).tolist() == embedded["pos"].tolist()


def test_tables_are_the_evaluation_rounded_to_four_significant_digits(written, run):
    out, _ = written
    ours = pd.read_csv(out / "table1.csv")
    exact = run.result.MfrE_s
    np.testing.assert_allclose(ours.iloc[:, 1:].to_numpy(), exact, rtol=5e-4)
    pd.testing.assert_frame_equal(ours, run.ours[1], check_dtype=False)


def test_significant_digits_print_like_the_paper():
    assert paper.format_significant(-0.045529999) == "-0.04553"
    assert paper.format_significant(-1.69) == "-1.690"
    assert paper.format_significant(-2.0078e-5) == "-0.00002008"
    np.testing.assert_array_equal(paper.round_significant([-0.045529999, -1.69]),
                                  [-0.04553, -1.69])


def test_platform_toml_reads_back_equal(written):
    out, _ = written
    assert Platform.from_toml(out / "platform.toml") == models.paper_platform()


def test_run_paper_uses_a_given_platform_file(tmp_path):
    platform = models.paper_platform().with_body(payload_mass=5.0)
    source = tmp_path / "heavy.toml"
    platform.to_toml(source)
    paths = run_paper(tmp_path / "out", platform_file=source, plots=False)
    assert [p.name for p in paths] == ["table1.csv", "table2.csv", "table3.csv",
                                       "platform.toml", "report.md"]
    assert Platform.from_toml(tmp_path / "out" / "platform.toml") == platform
    assert "heavy.toml" in (tmp_path / "out" / "report.md").read_text()


def test_implied_joint_reaction_inverts_the_friction_law_closed_form():
    reaction = np.array([0.0, 1.0, 21.3, 64.0])
    fr = paper.PAPER_FRICTION
    omega = PAPER_JOINT_SPEED
    moment = -(fr.joint_viscous * omega + fr.joint_coulomb * fr.joint_radius * reaction)
    np.testing.assert_allclose(paper.implied_joint_reaction(moment), reaction, atol=1e-12)
    # the paper's own constants: |R| = (|M| - 0.0004 N m) / 0.002 m
    assert paper.implied_joint_reaction(-0.0444) == pytest.approx(22.0)


def test_implied_prismatic_reaction_inverts_the_friction_law_closed_form():
    reaction = np.array([0.0, 0.5, 20.0])
    speed = np.array([0.01, -0.1, 0.15])
    fr = paper.PAPER_FRICTION
    force = -(fr.prismatic_viscous * np.abs(speed) + fr.prismatic_coulomb * reaction)
    np.testing.assert_allclose(paper.implied_prismatic_reaction(force, speed), reaction,
                               atol=1e-12)


def test_implied_reaction_of_our_own_moments_is_our_reaction(run):
    # paper mode: joint speed 0.02 rad/s, so inverting (33)-(34) recovers |R_E| and |R_C|
    # up to the sign regularisation, 1 - 0.02 / sqrt(0.02^2 + 1e-4^2) ~ 1.2e-5
    np.testing.assert_allclose(paper.implied_joint_reaction(run.result.MfrE_s),
                               run.reaction("R_E"), rtol=1e-4)
    np.testing.assert_allclose(paper.implied_joint_reaction(run.result.MfrC_s),
                               run.reaction("R_C"), rtol=1e-4)


def test_misprints_of_an_order_of_magnitude_are_left_out(run):
    table1 = {(m.pos, m.column): m for m in run.misprints[1]}
    assert table1[(10, "MfrE5")].excluded and table1[(10, "MfrE5")].likely == "-0.133"
    assert not table1[(19, "MfrE2")].excluded
    values = run.paper_values(1)
    assert np.isnan(values[9, 4]) and np.isnan(values[11, 0])
    assert values[18, 1] == pytest.approx(-0.143)


def test_misprint_detector_on_a_made_up_table():
    printed = paper.paper_table(3, printed=True)
    printed.loc[4, "Ffr2"] = "-0.113"     # -1.129 with its digit lost
    printed.loc[9, "Ffr6"] = "-2.509"     # far above the rest
    found = {(m.pos, m.column): m.kinds for m in paper.find_misprints(3, printed)}
    assert found[(5, "Ffr2")] == ("small",)
    assert found[(10, "Ffr6")] == ("large",)


def test_summary_ratio_is_ours_over_the_papers_median(run):
    summary = run.summary(1)
    assert list(summary.index) == [f"MfrE{i}" for i in range(1, 7)] + ["all"]
    row = summary.loc["MfrE1"]
    ours = np.abs(run.ours[1]["MfrE1"].to_numpy())
    theirs = np.abs(run.paper_values(1)[:, 0])
    assert row.ours_median == pytest.approx(np.median(ours))
    assert row.paper_median == pytest.approx(np.nanmedian(theirs))
    assert row.ratio == pytest.approx(np.median(ours) / np.nanmedian(theirs))


def test_report_sets_our_tables_beside_the_papers(written):
    out, _ = written
    text = (out / "report.md").read_text()
    header = ("| column | ours min | ours median | ours max | paper min | paper median | "
              "paper max | ratio of medians |")
    assert text.count(header) == 3
    for number, spec in paper.TABLES.items():
        assert f"## Table {number}" in text
        for column in spec.columns[1:]:
            assert f"\n| {column} | " in text
        assert f"![Table {number}: ours against the paper's](table{number}.png)" in text
    for m in PAPER_MISPRINTS:
        assert f"| {m[1]} | {m[2]} | {m[3]} |" in text
    assert "## What the paper's values imply" in text
    assert "## Why our values differ" in text
    assert "## Actuator forces (not in the paper)" in text
    for leg in range(1, 7):
        assert f"| leg {leg} | " in text


def test_cli_paper_writes_the_tables(tmp_path):
    out = tmp_path / "cli"
    result = CliRunner().invoke(main, ["paper", "--out", str(out), "--no-plots"])
    assert result.exit_code == 0, result.output
    assert f"wrote {out / 'table1.csv'}" in result.output
    assert all((out / f"table{n}.csv").exists() for n in (1, 2, 3))


def test_cli_paper_help():
    result = CliRunner().invoke(main, ["paper", "--help"])
    assert result.exit_code == 0
    assert "--out" in result.output and "--mode" in result.output


def test_a_file_is_refused_as_the_output_directory(tmp_path):
    target = tmp_path / "a_file"
    target.write_text("")
    with pytest.raises(InputError, match="not a directory"):
        run_paper(target, plots=False)
    result = CliRunner().invoke(main, ["paper", "--out", str(target), "--no-plots"])
    assert result.exit_code == 2
