"""Every path a user takes around the compiled core, each against its goal, measured in one run.

Usage, from the root of a source checkout (or ``make bench-all``)::

    python -m benchmarks.all [--quick] [--out all.json]

Rows (``ROWS``, in this order):

* ``evaluate``: ``gsfric.evaluate`` (kept outputs + flags) of N steps on one core, steps per
  second, and its ratio to the hot path (``Evaluator.actuator_forces`` into a preallocated
  array, one thread) timed in the same run on the same motion;
* ``simulate``: ``gsfric simulate`` of a Parquet trajectory to Parquet, default columns, end to
  end in a child process: steps per wall second and the child's peak resident set size;
* ``threads``: the hot path on two threads over one thread while another process keeps a core
  busy, at each N (the worst counts);
* ``discover_long`` and ``discover_short``: ``gsfric discover`` of a ``gsfric synth`` record
  (one hidden Stribeck effect, seed 1) in a child process: wall and CPU seconds, peak RSS;
* ``control_loop``: the README's control loop, a new ``Evaluator`` and ``forces()`` over 40
  steps (median of many calls);
* ``dask``: a workspace sweep on a Dask cluster of two worker processes against one (cluster
  start-up excluded); measured by a function the caller passes (``benchmarks.dask_scaling``,
  which ``main`` passes).

``quick=True`` runs every row at small sizes (``QUICK``) and judges no goal: for a test of the
table, not for figures.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

import gsfric
from benchmarks.cases import bench_motion, best_times
from benchmarks.dask_scaling import dask_scaling
from benchmarks.machine import describe_machine, load_average, parallel_capacity, publish
from benchmarks.paths import busy_core_paths, control_loop_paths
from benchmarks.simulate import run_gsfric, simulate_case
from gsfric.evaluation.evaluator import Evaluator, state_array


@dataclass(frozen=True)
class Sizes:
    """The sizes of one run: steps of ``evaluate``, ``simulate``, each N of ``threads``,
    (samples, rate in Hz) of the two discover records, steps of the Dask sweep and its runs
    on each cluster (the fastest kept, as every in-process row keeps its best call), and the
    timing budget of one in-process measurement, s."""

    evaluate: int
    simulate: int
    threads: tuple[int, ...]
    discover_long: tuple[int, float]
    discover_short: tuple[int, float]
    sweep: int
    sweep_runs: int
    budget: float


FULL = Sizes(100_000, 1_000_000, (1_000, 100_000), (100_000, 500.0), (6_000, 200.0),
             2_000_000, 3, 2.0)
QUICK = Sizes(2_000, 20_000, (1_000,), (1_500, 500.0), (1_000, 200.0), 16_000, 1, 0.2)

ROWS = ("evaluate", "simulate", "threads", "discover_long", "discover_short", "control_loop",
        "dask")
"""The rows of the table, in order."""

TIMING_RESOLUTION = 0.005
"""Relative difference of two best-of-many timings that counts as none (``threads``): a
two-thread Evaluator runs one thread below two blocks of 2048 steps, so at N = 1,000 both
timings are of the same call, and their ratio is 1 within this."""

DISCOVER_EFFECT = "stribeck:static=2,velocity=0.01"
"""The hidden effect of the discover records."""


@dataclass
class Row:
    """One path: what it is (``path``), its goal, what was measured (``measured``, text;
    ``values``, the numbers, seconds, steps/s, MB), and whether the goal is met (None: not
    judged, in a quick run or when the measurement failed)."""

    key: str
    path: str
    goal: str
    measured: str = "failed"
    met: bool | None = None
    values: dict = field(default_factory=dict)


@dataclass
class AllReport:
    """The rows of one run, with its machine (CPU, load, free cores) and whether it was quick."""

    rows: list[Row]
    machine: dict
    quick: bool

    def as_dict(self) -> dict:
        return {"quick": self.quick, "machine": self.machine,
                "rows": [asdict(r) for r in self.rows]}


def _evaluate_row(sizes: Sizes, row: Row) -> None:
    platform = gsfric.reference_platform()
    motion = bench_motion(sizes.evaluate)
    x = np.ascontiguousarray(state_array(motion))
    hot, out = Evaluator(platform, n_threads=1), np.empty((len(x), 6))
    n = len(x)
    # the hot path timed before and after the path, its best kept (wall, and CPU seconds of
    # the calling thread, which other load on the machine disturbs less)
    first = best_times(lambda: hot.actuator_forces(x, out), sizes.budget)
    best = best_times(lambda: gsfric.evaluate(platform, motion), sizes.budget)
    second = best_times(lambda: hot.actuator_forces(x, out), sizes.budget)
    rate, hot_rate = n / best[0], n / min(first[0], second[0])
    cpu_rate, hot_cpu_rate = n / best[2], n / min(first[2], second[2])
    row.values = {"steps": n, "steps_per_s": rate, "hot_path_steps_per_s": hot_rate,
                  "vs_hot_path": rate / hot_rate, "steps_per_cpu_s": cpu_rate,
                  "hot_path_steps_per_cpu_s": hot_cpu_rate,
                  "vs_hot_path_cpu": cpu_rate / hot_cpu_rate}
    row.measured = f"{rate / 1e6:.2f} M steps/s, {rate / hot_rate:.2f}x the hot path " \
                   f"({hot_rate / 1e6:.2f} M steps/s); per CPU second " \
                   f"{cpu_rate / 1e6:.2f} M, {cpu_rate / hot_cpu_rate:.2f}x"
    row.met = rate >= 2.5e6 and rate / hot_rate >= 0.6


def _simulate_row(sizes: Sizes, row: Row) -> None:
    with tempfile.TemporaryDirectory(prefix="gsfric-bench-") as tmp:
        result = simulate_case(sizes.simulate, Path(tmp))
    if result is None:
        return
    rss_gb = result["peak_rss_gb"]
    row.values = result
    row.measured = f"{result['steps_per_s'] / 1e3:.0f} k steps/s ({result['wall_s']:.2f} s " \
                   f"wall, {result['cpu_s']:.2f} s CPU), {rss_gb:.2f} GB peak RSS"
    row.met = result["steps_per_s"] >= 6e5 and rss_gb <= 0.5


def _threads_row(sizes: Sizes, row: Row, progress) -> None:
    platform = gsfric.reference_platform()
    x = state_array(bench_motion(max(sizes.threads)))
    busy = busy_core_paths(platform, x, sizes.budget, progress, sizes=sizes.threads)
    ratios = {int(n): v["two_vs_one"] for n, v in busy.items()}
    row.values = busy
    row.measured = ", ".join(f"{r:.2f} at N = {n:,}" for n, r in ratios.items())
    row.met = min(ratios.values()) >= 1.0 - TIMING_RESOLUTION


def _discover_row(samples: int, rate: float, row: Row, goal_s: float,
                  goal_mb: float | None) -> None:
    with tempfile.TemporaryDirectory(prefix="gsfric-bench-") as tmp:
        record = Path(tmp) / "record.parquet"
        made = run_gsfric(["synth", "--out", str(record), "--samples", str(samples),
                           "--rate", f"{rate:g}", "--effect", DISCOVER_EFFECT, "--seed", "1"])
        if made["returncode"] != 0:
            return
        run = run_gsfric(["discover", "--measured", str(record), "--out",
                          str(Path(tmp) / "out"), "--quiet"])
    if run["returncode"] != 0:
        return
    row.values = {k: run[k] for k in ("wall_s", "cpu_s", "peak_rss_mb")}
    row.values.update(samples=samples, rate_hz=rate)
    row.measured = f"{run['wall_s']:.1f} s wall, {run['cpu_s']:.1f} s CPU, " \
                   f"{run['peak_rss_mb']:.0f} MB peak RSS"
    row.met = run["wall_s"] <= goal_s and (goal_mb is None or run["peak_rss_mb"] <= goal_mb)


def _control_loop_row(sizes: Sizes, row: Row) -> None:
    loop = control_loop_paths(gsfric.reference_platform(), sizes.budget)["control_loop_40"]
    row.values = loop
    row.measured = f"{loop['median_us']:.1f} us median ({loop['best_us']:.1f} us best)"
    row.met = loop["median_us"] <= 15.0


def _dask_row(sizes: Sizes, row: Row, dask: Callable[[int, int], dict]) -> None:
    scaling = dask(sizes.sweep, sizes.sweep_runs)
    row.values = scaling
    row.measured = f"{scaling['two_vs_one']:.2f} ({scaling['one_worker_s']:.2f} s on one " \
                   f"worker, {scaling['two_workers_s']:.2f} s on two, " \
                   f"{scaling['steps']:,} steps)"
    row.met = scaling["two_vs_one"] >= 1.8


def _rows(sizes: Sizes) -> dict[str, Row]:
    long_n, long_rate = sizes.discover_long
    short_n, short_rate = sizes.discover_short
    rows = [
        Row("evaluate", f"gsfric.evaluate (kept outputs + flags), N = {sizes.evaluate:,}, "
                        "one core", ">= 2.5 M steps/s and >= 0.6x the hot path"),
        Row("simulate", f"gsfric simulate to Parquet, default columns, {sizes.simulate:,} "
                        "steps, end to end", ">= 600 k steps/s, peak RSS <= 0.5 GB"),
        Row("threads", "two threads / one thread, the other core busy", ">= 1.0 at every N"),
        Row("discover_long", f"gsfric discover, {long_n:,} samples at {long_rate:g} Hz",
            "<= 25 s wall, <= 400 MB"),
        Row("discover_short", f"gsfric discover, {short_n:,} samples at {short_rate:g} Hz",
            "<= 3 s wall"),
        Row("control_loop", "README control loop: new Evaluator + forces(), 40 steps",
            "<= 15 us"),
        Row("dask", f"Dask sweep, {sizes.sweep:,} steps, 2 workers / 1 worker", ">= 1.8"),
    ]
    return {r.key: r for r in rows}


def measure_all(quick: bool = False, dask: Callable[[int, int], dict] | None = None,
                progress=print) -> AllReport:
    """Measure every row of ``ROWS`` (``dask``: the function that times the sweep on one and
    two workers, ``dask(steps, runs)``, ``benchmarks.dask_scaling.dask_scaling``; without it
    that row is "not run").

    Returns
    -------
    AllReport
        Every row in ``ROWS`` order; ``met`` is None throughout when ``quick``.
    """
    sizes = QUICK if quick else FULL
    rows = _rows(sizes)
    machine = describe_machine()
    if not quick:
        machine["parallel_capacity_start"] = parallel_capacity()
    steps = [("evaluate", lambda: _evaluate_row(sizes, rows["evaluate"])),
             ("simulate", lambda: _simulate_row(sizes, rows["simulate"])),
             ("threads", lambda: _threads_row(sizes, rows["threads"], progress)),
             ("discover_long", lambda: _discover_row(*sizes.discover_long,
                                                     rows["discover_long"], 25.0, 400.0)),
             ("discover_short", lambda: _discover_row(*sizes.discover_short,
                                                      rows["discover_short"], 3.0, None)),
             ("control_loop", lambda: _control_loop_row(sizes, rows["control_loop"]))]
    if dask is not None:
        steps.append(("dask", lambda: _dask_row(sizes, rows["dask"], dask)))
    else:
        rows["dask"].measured = "not run"
    for key, run in steps:
        progress(f"  {rows[key].path}")
        run()
    machine["load_average_end"] = load_average()
    if quick:
        for row in rows.values():
            row.met = None
    else:
        machine["parallel_capacity_end"] = parallel_capacity()
    return AllReport([rows[k] for k in ROWS], machine, quick)


def format_all(report: AllReport) -> str:
    """The table: path, goal, measured, met (yes / NO / -), with the machine above it."""
    m = report.machine
    quick = " --quick (sizes too small to judge the goals)" if report.quick else ""
    head = [f"python -m benchmarks.all{quick}",
            f"machine: {m.get('cpu')}, {m.get('cores')} cores, Python {m.get('python')}, "
            f"NumPy {m.get('numpy')}; source {m.get('source')}",
            f"load average {m.get('load_average_start')} -> {m.get('load_average_end')}; "
            f"free cores for two processes {m.get('parallel_capacity_start', float('nan')):.2f}"
            f" -> {m.get('parallel_capacity_end', float('nan')):.2f} (2.00 when idle)", ""]
    table = [("path", "goal", "measured", "met")]
    for r in report.rows:
        table.append((r.path, r.goal, r.measured,
                      "-" if r.met is None else "yes" if r.met else "NO"))
    widths = [max(len(line[i]) for line in table) for i in range(3)]
    lines = [" | ".join(c.ljust(w) for c, w in zip(line[:3], widths)) + " | " + line[3]
             for line in table]
    lines.insert(1, "-+-".join("-" * w for w in widths) + "-+-----")
    return "\n".join(head + lines)


def run_all(quick: bool = False, out: Path | None = None,
            dask: Callable[[int, int], dict] | None = None) -> AllReport:
    """``measure_all``, the table printed, and with ``out`` the report written as JSON."""
    report = measure_all(quick, dask, progress=lambda s: print(s, file=sys.stderr, flush=True))
    publish(format_all(report), report.as_dict(), out)
    return report


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="every path at a small size, goals not judged")
    parser.add_argument("--out", type=Path, help="also write the table as JSON")
    args = parser.parse_args(argv)
    run_all(quick=args.quick, out=args.out, dask=dask_scaling)


if __name__ == "__main__":
    main()
