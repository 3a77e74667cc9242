"""The throughput table of ``gsfric bench``: the compiled actuator map in steps per second.

The compiled map ``Evaluator.actuator_forces`` (actuator forces with friction of the reference
platform, its default friction model; preallocated output) over a smooth random motion sampled
at ``RATE``, at each size: the build this CPU runs (SIMD over steps) on one thread and on two,
and the baseline build, which evaluates one step per call (``per step``), on one thread. Each
figure is from the fastest of repeated calls after a warm-up call, within a time budget per
case; the wall clock counts, so other load on the machine lowers the figures (the load
average is printed with them).

The NumPy reference engine, memory, the paths around the hot path and every user path
against its goal are measured by the benchmarks of a source checkout (``benchmarks/``:
``python -m benchmarks.throughput``, ``make bench-all``).
"""

from __future__ import annotations

import functools
import os
import platform as _platform
import statistics
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from gsfric._checks import as_flag
from gsfric.compiled import native
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.parameters import model_function
from gsfric.models import random_motion, reference_platform
from gsfric.trajectory import TIME_UNITS

SIZES = (40, 1_000, 100_000, 1_000_000)
"""Steps per call of the full table."""
QUICK_SIZES = (40, 1_000)
"""Steps per call with ``--quick``."""
BUDGET = 1.0
"""Seconds of calls per case (at least ``MIN_CALLS``): enough for a stable fastest call."""
QUICK_BUDGET = 0.2
"""Seconds of calls per case with ``--quick``."""
MIN_CALLS = 3
"""Timed calls per case at least, however long one takes (a median of three)."""
RATE = 1000.0
"""Sampling rate of the benchmark's motion, Hz."""
SEED = 20261122
"""Seed of the benchmark's motion."""


@dataclass(frozen=True)
class Case:
    """One timed case.

    Attributes
    ----------
    implementation : str
        ``"simd"``: the build this CPU runs, SIMD over steps; ``"per step"``: the baseline
        build, one step per call.
    threads : int
    steps : int
        Steps per call.
    calls : int
        Timed calls.
    best_s, median_s : float
        Wall-clock seconds per call: the fastest and the median.
    """

    implementation: str
    threads: int
    steps: int
    calls: int
    best_s: float
    median_s: float

    @property
    def steps_per_second(self) -> float:
        """Steps per second of the fastest call; NaN when it took no measurable time."""
        return self.steps / self.best_s if self.best_s > 0 else float("nan")


@dataclass(frozen=True)
class Machine:
    """What the figures were measured on.

    Attributes
    ----------
    cpu : str
        The CPU's model name.
    cores : int or None
        Logical cores (``os.cpu_count``).
    python, numpy : str
        Versions.
    build : str
        The compiled build loaded (``native.chosen_build``).
    lanes : int
        Steps per vector of that build (0: one step per call).
    load_average : tuple of float, or None
        1, 5 and 15 minutes, before the cases.
    """

    cpu: str
    cores: int | None
    python: str
    numpy: str
    build: str
    lanes: int
    load_average: tuple[float, ...] | None


@dataclass(frozen=True)
class Throughput:
    """One run of ``gsfric bench``: the machine and the cases, by size then row."""

    machine: Machine
    cases: tuple[Case, ...]

    def as_dict(self) -> dict:
        """The run as JSON-ready data, with each case's steps per second."""
        return {"machine": asdict(self.machine),
                "cases": [{**asdict(c), "steps_per_second": c.steps_per_second}
                          for c in self.cases]}


def _cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return _platform.processor() or _platform.machine()


def machine() -> Machine:
    """The machine, the build loaded and the load average now."""
    try:
        load = tuple(round(v, 2) for v in os.getloadavg())
    except OSError:
        load = None
    return Machine(cpu=_cpu_name(), cores=os.cpu_count(), python=_platform.python_version(),
                   numpy=np.__version__, build=native.chosen_build(),
                   lanes=native.lanes(native.library()), load_average=load)


def _time(fn, budget: float) -> tuple[int, float, float]:
    """(calls, fastest, median) wall seconds of ``fn()`` after a warm-up call."""
    fn()
    times: list[float] = []
    start = time.perf_counter()
    while len(times) < MIN_CALLS or time.perf_counter() - start < budget:
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return len(times), min(times), statistics.median(times)


def _calls(x: np.ndarray, lanes: int, per_step: bool) -> dict[tuple[str, int], Callable]:
    """The timed calls over states x, into one output array: (implementation, threads) -> a
    function of no arguments. ``lanes``: of the build loaded; ``per_step``: add the baseline
    build."""
    platform = reference_platform()
    out = np.empty((len(x), 6))
    evaluators = {threads: Evaluator(platform, n_threads=threads) for threads in (1, 2)}
    name = "simd" if lanes else "per step"
    calls = {(name, threads): functools.partial(ev.actuator_forces, x, out)
             for threads, ev in evaluators.items()}
    if per_step:
        f = native.get(model_function("actuator", platform.friction.model), "baseline")
        calls["per step", 1] = functools.partial(
            f.bound([evaluators[1].P, evaluators[1].Q], "F"), x, out)
    return calls


def measure(quick: bool = False, progress=None) -> Throughput:
    """Time every case (``progress(text)`` before each, when given)."""
    quick = as_flag(quick, "quick")
    sizes, budget = (QUICK_SIZES, QUICK_BUDGET) if quick else (SIZES, BUDGET)
    where = machine()
    x_all = state_array(random_motion(np.random.default_rng(SEED),
                                      np.arange(max(sizes)) / RATE))
    cases = []
    for n in sizes:
        x = np.ascontiguousarray(x_all[:n])
        calls = _calls(x, where.lanes, per_step=where.build != "baseline")
        for (implementation, threads), fn in calls.items():
            if progress is not None:
                progress(f"  {implementation}, {threads} thread(s), N = {n:,}")
            cases.append(Case(implementation, threads, n, *_time(fn, budget)))
    return Throughput(where, tuple(cases))


def _seconds(t: float) -> str:
    """``t`` seconds in s, ms, us or ns, three significant digits (999.96 ms is 1 s)."""
    for unit in ("s", "ms", "us", "ns"):
        scale = TIME_UNITS[unit]
        if t >= scale * (1 - 5e-4) or unit == "ns":
            return f"{t / scale:.3g} {unit}"


def format_table(run: Throughput) -> str:
    """The machine line and one line per case: steps/s, fastest and median call, and the
    ratio to the per-step build at the same size (``-`` without one)."""
    m = run.machine
    lanes = f"{m.lanes} steps per vector" if m.lanes else "one step per call"
    load = "unknown" if m.load_average is None else ", ".join(map(str, m.load_average))
    lines = ["gsfric bench: compiled actuator forces with friction, reference platform",
             f"machine: {m.cpu}, {m.cores} cores; Python {m.python}, NumPy {m.numpy}; "
             f"build {m.build} ({lanes}); load average {load} (1, 5, 15 min)", ""]
    head = (f"{'implementation':<14} {'threads':>7} {'N':>9} {'steps/s':>10} "
            f"{'best call':>10} {'median':>10} {'vs per step':>12}")
    lines += [head, "-" * len(head)]
    per_step = {c.steps: c.best_s for c in run.cases
                if c.implementation == "per step" and c.threads == 1}
    for c in run.cases:
        ratio = f"{per_step[c.steps] / c.best_s:.1f}x" if c.steps in per_step and c.best_s > 0 \
            else "-"
        lines.append(f"{c.implementation:<14} {c.threads:>7} {c.steps:>9,} "
                     f"{c.steps_per_second:>10.3g} {_seconds(c.best_s):>10} "
                     f"{_seconds(c.median_s):>10} {ratio:>12}")
    return "\n".join(lines)
