"""What the benchmarks time and how: the inputs, the implementations and the timed calls.

Every case runs on the reference platform over a smooth random motion sampled every ``DT``
seconds; an implementation is the compiled map ``Evaluator.actuator_forces`` (coupled or the
paper's friction model) or one of the NumPy reference engines
(``tests/engines/numpy_reference.py``). A case's times are the wall-clock seconds of successive
calls after a warm-up call, and for one thread also the calling thread's CPU seconds.

Run from the root of a source checkout (``python -m benchmarks.throughput``): the benchmarks
import ``benchmarks`` and ``tests.engines`` from it, and so do their child processes.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from gsfric import models
from gsfric.evaluation.evaluator import Evaluator, state_array
from tests.engines import numpy_reference as numpy_model

CHECKOUT = Path(__file__).resolve().parents[1]
"""The source checkout: the working directory of the benchmarks' child processes."""
RATE = 1000.0
"""Sampling rate of the benchmark's motions, Hz."""
DT = 1 / RATE
SEED = 20261122


def ratio(a: float | None, b: float | None) -> float:
    """a / b, NaN when b is zero or unknown (a time below the clock's resolution)."""
    if a is None or b is None or not b > 0:
        return float("nan")
    return a / b


@dataclass
class Case:
    """One timed case: an implementation on ``threads`` threads over ``steps`` steps.

    Times are seconds per call; ``extrapolated`` marks a per-step loop case computed from its
    per-step time at a smaller size rather than run.
    """

    implementation: str
    threads: int
    steps: int
    calls: int = 0
    best: float = float("nan")
    median: float = float("nan")
    cpu_best: float | None = None
    extrapolated: bool = False
    memory_rss_mib: float | None = None
    memory_tracemalloc_mib: float | None = None

    @property
    def steps_per_second(self) -> float:
        return ratio(self.steps, self.best)

    @property
    def steps_per_cpu_second(self) -> float | None:
        """Steps per second of CPU time (one-thread cases only)."""
        return None if self.cpu_best is None else ratio(self.steps, self.cpu_best)

    def as_dict(self) -> dict:
        out = asdict(self)
        out["steps_per_second"] = self.steps_per_second
        out["steps_per_cpu_second"] = self.steps_per_cpu_second
        return out


def bench_motion(n: int):

    return models.random_motion(np.random.default_rng(SEED), DT * np.arange(n))


def states(n: int) -> np.ndarray:
    """States (n, 24) of a smooth random motion sampled every ``DT`` seconds."""

    return state_array(bench_motion(n))


def implementation_call(implementation: str, threads: int, x: np.ndarray):
    """A function of no arguments that evaluates x with one implementation."""

    platform = models.reference_platform("paper")   # the model the NumPy references implement
    if implementation in ("compiled", "compiled_paper"):
        if implementation == "compiled":
            platform = models.reference_platform("coupled")
        evaluator = Evaluator(platform, n_threads=threads)
        out = np.empty((x.shape[0], 6))
        out.fill(0.0)
        return lambda: evaluator.actuator_forces(x, out=out)
    if implementation == "numpy":
        return lambda: numpy_model.actuator_forces_numpy(platform, x)
    if implementation == "loop":
        return lambda: numpy_model.actuator_forces_loop(platform, x)
    raise ValueError(f"unknown implementation {implementation!r}")


def time_calls(fn, budget: float, min_calls: int, max_calls: int,
                cpu: list | None = None, setup=None) -> list[float]:
    """Wall-clock seconds of successive calls, until ``budget`` seconds have passed.

    With ``cpu``, the CPU seconds of the calling thread for each call are appended to it (the
    whole cost of a call that runs on one thread). ``setup()``, when given, runs before each
    call, untimed.
    """
    times: list[float] = []
    start = time.perf_counter()
    while len(times) < max_calls and (len(times) < min_calls
                                      or time.perf_counter() - start < budget):
        if setup is not None:
            setup()
        c0 = time.thread_time()
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
        if cpu is not None:
            cpu.append(time.thread_time() - c0)
    return times


def time_case(implementation: str, threads: int, x: np.ndarray, budget: float = 2.0) -> Case:
    """Time one case after a warm-up call (the loop's large cases: a single call, no warm-up)."""
    fn = implementation_call(implementation, threads, x)
    n = x.shape[0]
    slow = implementation == "loop" and n > 100
    if not slow:
        fn()
    cpu: list[float] = []
    times = time_calls(fn, budget, 1 if slow else 3, 1 if slow else 100_000, cpu)
    return Case(implementation, threads, n, calls=len(times), best=min(times),
                median=statistics.median(times), cpu_best=min(cpu) if threads == 1 else None)


def best_times(fn, budget: float, min_calls: int = 3,
                setup=None) -> tuple[float, float, float]:
    """(best wall, median wall, best CPU of the calling thread) seconds per call
    (``setup()`` before each call, untimed)."""
    fn()
    cpu: list[float] = []
    times = time_calls(fn, budget, min_calls, 100_000, cpu, setup)
    return min(times), statistics.median(times), min(cpu)
