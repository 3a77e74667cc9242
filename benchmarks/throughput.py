"""Throughput of the compiled combined map against two NumPy implementations.

Usage, from the root of a source checkout::

    python -m benchmarks.throughput [--quick] [--out results.json]

``gsfric bench`` prints the compiled rows alone; this adds the NumPy engines, memory, the paths
around the hot path, import time and the targets. The compiled map
``Evaluator.actuator_forces`` (actuator forces with friction, NumPy in to NumPy out,
preallocated output) is timed on one and on two threads against the same physics written in
NumPy (``tests/engines/numpy_reference.py``): vectorised over steps, and a per-step loop that
solves the dense 42x42 system of (2)-(16) at every step. Every case runs on the reference
platform over a smooth random motion.

For each case: steps per second (from the fastest call; for one-thread cases also per second of
the calling thread's CPU time, which other load on the machine disturbs less), the latency of
one call (fastest and median), and the peak memory the call adds, measured in a fresh subprocess
per case as the rise of the peak resident set size over the call (Linux: ``/proc/self/status``
after resetting the peak; elsewhere ``resource.getrusage``), and for the NumPy implementations
also as the peak of ``tracemalloc``. The per-step loop is timed up to ``LOOP_MAX_STEPS`` steps;
above that its time is extrapolated from its per-step time (marked).

Before and after the cases, ``parallel_capacity`` checks how many cores the machine actually
gives two CPU-bound processes (2.0 when two cores are idle): on a shared machine the two-thread
figures cannot exceed it.

``run_bench`` prints the table, the ratios and the targets; with ``out`` it writes them as JSON.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from benchmarks.cases import Case, states, time_case
from benchmarks.machine import describe_machine, load_average, parallel_capacity, publish
from benchmarks.memory import memory_case
from benchmarks.paths import import_time, measure_paths
from benchmarks.report import Report, format_report, ratios, targets

SIZES = (40, 1_000, 100_000, 1_000_000)
QUICK_SIZES = (40, 1_000)
LOOP_MAX_STEPS = 1_000


def _command() -> str:
    """The command line of this run, as typed."""
    if not sys.argv or not sys.argv[0]:
        return "run_bench()"
    name = Path(sys.argv[0]).name
    prefix = ["python", sys.argv[0]] if name.endswith(".py") else [name]
    return " ".join(prefix + sys.argv[1:])


def measure(sizes=SIZES, threads=(1, 2), budget: float = 2.0, memory: bool = True,
            progress=print) -> Report:
    """Run every case and return the report (``run_bench`` prints and writes it)."""
    report = Report(command=_command(), machine=describe_machine())
    report.machine["parallel_capacity_start"] = parallel_capacity()
    x_all = states(max(sizes))
    with tempfile.TemporaryDirectory(prefix="gsfric-bench-") as tmp:
        for n in sizes:
            x = np.ascontiguousarray(x_all[:n])
            plan = [("compiled", t) for t in threads] + [("compiled_paper", 1), ("numpy", 1)]
            if n <= LOOP_MAX_STEPS:
                plan.append(("loop", 1))
            for implementation, t in plan:
                progress(f"  {implementation:8s} threads={t} N={n:,}")
                case = time_case(implementation, t, x, budget)
                if memory:
                    mem = memory_case(implementation, t, x, Path(tmp))
                    case.memory_rss_mib = mem["rss_mib"]
                    case.memory_tracemalloc_mib = mem["tracemalloc_mib"]
                report.cases.append(case)
        measured = [c for c in report.cases if c.implementation == "loop"]
        per_step = min(c.best / c.steps for c in measured) if measured else float("nan")
        for n in sizes:
            if report.case("loop", 1, n) is None:
                report.cases.append(Case("loop", 1, n, calls=0, best=per_step * n,
                                         median=per_step * n, extrapolated=True))
    full = memory and max(sizes) >= 1_000_000
    report.paths = measure_paths(budget, full, progress, simulate=full)
    progress("  import gsfric (fresh interpreters)")
    report.import_time = import_time()
    report.ratios = ratios(report, sizes)
    report.targets = targets(report)
    report.machine["load_average_end"] = load_average()
    report.machine["parallel_capacity_end"] = parallel_capacity()
    return report


def run_bench(quick: bool = False, out: Path | None = None) -> Report:
    """Measure, print the table and, with ``out``, write the report as JSON.

    Parameters
    ----------
    quick : bool
        Only N = 40 and 1e3 (and shorter timing budgets); targets at 1e5 and 1e6 are then not
        judged.
    out : Path, optional
        JSON file for the report (cases, ratios, targets, machine, command).

    Returns
    -------
    Report
    """
    sizes = QUICK_SIZES if quick else SIZES
    report = measure(sizes=sizes, budget=0.5 if quick else 2.0,
                     progress=lambda s: print(s, file=sys.stderr, flush=True))
    publish(format_report(report), report.as_dict(), out)
    return report


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only N = 40 and 1e3")
    parser.add_argument("--out", type=Path, help="also write the report as JSON")
    args = parser.parse_args(argv)
    run_bench(quick=args.quick, out=args.out)


if __name__ == "__main__":
    main()
