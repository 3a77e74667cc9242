"""Discover's answer as a reader meets it: the console line, units in summary.json and
report.md, the report's glossary, the commented platform.toml written back, the Python API."""

from __future__ import annotations

import json
import re

import pytest
from click.testing import CliRunner

import gsfric
from gsfric.cli import main
from gsfric.discovery.answer import GLOSSARY, gap_closed, verdict_line
from gsfric.platform import catalog
from gsfric.synth import synthesize

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out


@pytest.fixture(scope="module")
def answered(tmp_path_factory):
    """A record with a hidden seal friction and sensor bias, discovered through the CLI."""
    work = tmp_path_factory.mktemp("answer")
    data = synthesize(effects=["seal_friction:force=3", "sensor_bias:b1=1,b4=-1"],
                      samples=2000, noise=0.2, seed=3)
    measured = work / "m.parquet"
    data.frame.to_parquet(measured)
    result = CliRunner().invoke(main, ["discover", "--measured", str(measured), "--out",
                                       str(work / "out"), "--no-progress", "--no-plots"])
    assert result.exit_code == 0, result.output
    return work / "out", result.output.strip().splitlines()[-1], measured


def test_console_ends_with_the_verdict_and_the_effects_with_units(answered):
    out, line, _ = answered
    summary = json.loads((out / "summary.json").read_text())
    assert line == summary["answer"]
    assert line.startswith(summary["verdict"] + ": ")
    for effect in summary["effects"]:
        assert effect["name"] in line
    seal = next(e for e in summary["effects"] if e["name"] == "seal_friction")
    assert re.search(rf"force = {seal['parameters']['force']:.3g} N", line)
    closed = re.search(r"close\w* (\d+) % of the gap", line)
    assert closed and 80 <= int(closed.group(1)) <= 100


def test_summary_gives_a_unit_for_every_parameter(answered):
    out, _, _ = answered
    summary = json.loads((out / "summary.json").read_text())
    for effect in summary["effects"]:
        assert set(effect["units"]) == set(effect["parameters"])
        for name, unit in effect["units"].items():
            assert unit == catalog.unit(f"{effect['name']}.{name}") != ""
    for name, entry in summary["refit"]["parameters"].items():
        assert entry["unit"] == catalog.unit(name) != ""
    assert summary["refit"]["parameters"]["payload_mass"]["unit"] == "kg"


def test_report_explains_each_statistic_it_prints(answered):
    out, _, _ = answered
    report = (out / "report.md").read_text()
    body, glossary = report.split("## Glossary", 1)
    for term in ("held-out gain", "p slowest / rest", "AR orders"):
        assert term in body and f"**{term}" in glossary
    assert "**model / refit / final / unbounded**" in glossary
    assert "*final* the value in the final model" in body
    assert "| force | N |" in body


def test_written_back_platform_is_commented_compact_and_loads_as_the_final_model(answered):
    out, _, measured = answered
    text = (out / "platform.toml").read_text()
    summary = json.loads((out / "summary.json").read_text())
    platform = gsfric.Platform.from_toml(out / "platform.toml")
    for effect in summary["effects"]:
        assert platform.effects[effect["name"]] == pytest.approx(effect["parameters"],
                                                                  rel=1e-12)
    assert str(measured) in text.splitlines()[0]
    assert "effect seal_friction switched on" in text
    assert len(text.splitlines()) < 80
    assert "# kg; the moving platform" in text


@pytest.fixture(scope="module")
def again(answered, tmp_path_factory):
    """The same record through the Python API, its outputs written."""
    out = tmp_path_factory.mktemp("again")
    return gsfric.discover(answered[2], out=out, figures=False), out


def test_python_api_discover_returns_the_typed_result_with_a_short_repr(answered, again):
    _, line, measured = answered
    result, out = again
    assert isinstance(result, gsfric.Discovery)
    assert verdict_line(result) == line
    assert 0.0 <= gap_closed(result) <= 1.0
    text = repr(result)
    assert len(text) < 300 and result.verdict in text and "seal_friction" in text
    assert all(len(repr(f)) < 200 for f in result.effects)
    assert all(len(repr(r)) < 200 for r in result.rounds)
    # the commented platform file reads back as exactly the final model
    assert gsfric.Platform.from_toml(out / "platform.toml") == result.platform
    with pytest.raises(gsfric.InputError, match="forces"):
        gsfric.discover(gsfric.models.paper_motion())


def test_summary_and_report_are_what_the_files_hold(answered, again):
    """``summary()`` is summary.json's content, the answer and the file included, and
    ``report(figures=False)`` is report.md written without the figures (``report()`` lists
    them as well), the same as the command line writes."""
    cli, line, measured = answered
    result, out = again
    summary = result.summary()
    assert summary == json.loads((out / "summary.json").read_text())
    assert summary["answer"] == line == verdict_line(result)
    assert summary["data"]["file"] == str(measured)
    assert result.report(figures=False) == (out / "report.md").read_text()
    assert "## Plots" in result.report() and "## Plots" not in result.report(figures=False)
    assert result.report().splitlines()[2] == (cli / "report.md").read_text().splitlines()[2]
    assert f"`{measured}`" in result.report()


def test_glossary_terms_are_explained_in_a_sentence():
    assert all(len(text.split()) >= 8 for text in GLOSSARY.values())
