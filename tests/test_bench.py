"""``gsfric bench``: the throughput table of the compiled model (figures not judged)."""

import json
import math

from click.testing import CliRunner

from gsfric.cli import main
from gsfric.throughput import QUICK_SIZES, Case, Throughput, format_table, machine


def test_quick_table_has_every_case_and_writes_the_same_figures(tmp_path):
    out = tmp_path / "bench.json"
    result = CliRunner().invoke(main, ["bench", "--quick", "--out", str(out)])
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    cases = data["cases"]
    rows = {(c["implementation"], c["threads"]) for c in cases}
    per_step = {("per step", 1)} if data["machine"]["build"] != "baseline" else set()
    assert rows == {("simd" if data["machine"]["lanes"] else "per step", t)
                    for t in (1, 2)} | per_step
    assert sorted({c["steps"] for c in cases}) == list(QUICK_SIZES)
    assert len(cases) == len(rows) * len(QUICK_SIZES)
    for c in cases:
        assert c["calls"] >= 3 and 0 < c["best_s"] <= c["median_s"]
        assert math.isclose(c["steps_per_second"], c["steps"] / c["best_s"])
    text = result.stdout.splitlines()
    assert text[1].startswith("machine: ") and f"build {data['machine']['build']}" in text[1]
    table = text[text.index(next(t for t in text if t.startswith("implementation"))) + 2:]
    assert len(table) == len(cases) + 1
    for line, c in zip(table, cases):
        assert line.startswith(c["implementation"]), line
        assert line.split()[-7:-5] == [f"{c['steps']:,}", f"{c['steps_per_second']:.3g}"]
    assert text[-1] == f"wrote {out}"


def test_a_call_below_the_clock_resolution_has_no_rate():
    case = Case("simd", 1, 40, calls=3, best_s=0.0, median_s=0.0)
    assert math.isnan(case.steps_per_second)
    line = format_table(Throughput(machine(), (case,))).splitlines()[-1]
    assert line.split()[3] == "nan" and line.endswith("-")


def test_all_points_to_the_benchmarks_of_a_checkout():
    result = CliRunner().invoke(main, ["bench", "--all"])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        "gsfric: error: --all: every user path against its goal is measured from a source "
        "checkout: `make bench-all` (or `python -m benchmarks.all`)"]


def test_call_times_are_printed_in_the_unit_their_rounding_needs():
    times = (0.99996, 0.9994, 2.5e-5, 4e-9)
    cases = tuple(Case("simd", 1, 40, calls=3, best_s=t, median_s=t) for t in times)
    lines = format_table(Throughput(machine(), cases)).splitlines()[-len(times):]
    assert [line.split()[4:6] for line in lines] == [["1", "s"], ["999", "ms"], ["25", "us"],
                                                     ["4", "ns"]]
