"""``python -m benchmarks.all --quick``: every row of the table measured and printed (not
timed); run from a source checkout, whose root is on the path."""

import json

import pytest

from benchmarks.all import ROWS, format_all, main, measure_all


def _check_table(report, measured_keys):
    assert [r.key for r in report.rows] == list(ROWS)
    for row in report.rows:
        assert row.met is None                      # a quick run judges no goal
        if row.key in measured_keys:
            assert row.measured not in ("failed", "not run"), row
            assert row.values
    text = format_all(report).splitlines()
    header = next(i for i, line in enumerate(text) if line.startswith("path "))
    body = text[header + 2:]
    assert len(body) == len(ROWS)
    for line, row in zip(body, report.rows):
        cells = [c.strip() for c in line.split(" | ")]
        assert cells == [row.path, row.goal, row.measured, "-"]


@pytest.mark.slow
def test_quick_run_measures_every_row_but_dask():
    report = measure_all(quick=True, progress=lambda s: None)
    _check_table(report, set(ROWS) - {"dask"})
    assert report.rows[-1].measured == "not run"
    values = {r.key: r.values for r in report.rows}
    assert values["simulate"]["steps"] == 20_000 and values["simulate"]["peak_rss_gb"] > 0
    assert values["discover_short"]["samples"] == 1_000
    assert values["evaluate"]["vs_hot_path"] > 0
    assert json.loads(json.dumps(report.as_dict()))["rows"][0]["key"] == "evaluate"


@pytest.mark.slow
def test_script_prints_every_row_with_dask(tmp_path):
    out = tmp_path / "all.json"
    main(["--quick", "--out", str(out)])
    rows = json.loads(out.read_text())["rows"]
    assert [r["key"] for r in rows] == list(ROWS)
    assert rows[-1]["values"]["two_vs_one"] > 0
