"""The paths around the hot path: ``evaluate`` with flags, the README's control loop,
``Evaluator`` construction, two threads beside a busy core, import time, evaluate's memory."""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import gsfric
from benchmarks.cases import CHECKOUT, bench_motion, best_times
from benchmarks.simulate import SIMULATE_STEPS, simulate_case
from gsfric.compiled import native
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.memory import release_memory
from tests.engines import numpy_reference as numpy_model


def import_time(runs: int = 7) -> dict:
    """Seconds to ``import gsfric`` in fresh interpreters (and -X importtime's own figure)."""
    code = ("import time; t = time.perf_counter(); import gsfric; "
            "print(time.perf_counter() - t)")
    wall = []
    for _ in range(runs):
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             check=True)
        wall.append(float(run.stdout.strip()))
    run = subprocess.run([sys.executable, "-X", "importtime", "-c", "import gsfric"],
                         capture_output=True, text=True, check=True)
    cumulative = None
    for line in run.stderr.splitlines():
        parts = [s.strip() for s in line.split("|")]
        if len(parts) == 3 and parts[2] == "gsfric":
            cumulative = int(parts[1]) * 1e-6
    first = ("import time; t = time.perf_counter(); import numpy as np, gsfric; "
             "from gsfric.evaluation import Evaluator, state_array; "
             "ev = Evaluator(gsfric.reference_platform()); "
             "ev.actuator_forces(np.tile(np.r_[0, 0, 0.7, 1, 0, 0, 0, 1, 0, 0, 0, 1, "
             "np.zeros(12)], (40, 1))); print(time.perf_counter() - t)")
    run = subprocess.run([sys.executable, "-c", first], capture_output=True, text=True,
                         check=True)
    return {"median_s": statistics.median(wall), "best_s": min(wall), "runs": runs,
            "importtime_cumulative_s": cumulative,
            "first_call_s": float(run.stdout.strip().splitlines()[-1])}


def _busy_core():
    """A process that keeps one core busy until terminated."""
    return subprocess.Popen([sys.executable, "-c", "while True: pass"])


def measure_paths(budget: float, memory: bool, progress=print, simulate: bool = False) -> dict:
    """The paths around the hot path: ``evaluate`` with flags, the README's control loop,
    Evaluator construction, two threads against a busy core, evaluate's memory."""

    platform = gsfric.reference_platform()
    out: dict = {"friction_model": platform.friction.model}
    out["lanes"] = native.lanes(native.library())
    progress("  evaluate (kept outputs + flags) N=100,000")
    motion = bench_motion(100_000)
    out["evaluate_1e5"] = _evaluate_path(platform, motion, budget)
    progress("  README control loop, 40 steps")
    out.update(control_loop_paths(platform, budget))
    out["busy_core"] = busy_core_paths(platform, state_array(motion), budget, progress)
    if memory:
        progress("  evaluate memory, N=1,000,000 (fresh process)")
        code = ("import json; from benchmarks.memory import evaluate_memory_child; "
                "print(json.dumps(evaluate_memory_child(1_000_000)))")
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             cwd=CHECKOUT)
        if run.returncode == 0:
            out["evaluate_memory_1e6"] = json.loads(run.stdout.strip().splitlines()[-1])
    if simulate:
        progress(f"  gsfric simulate to Parquet, N={SIMULATE_STEPS:,} (fresh process)")
        with tempfile.TemporaryDirectory(prefix="gsfric-bench-") as tmp:
            result = simulate_case(SIMULATE_STEPS, Path(tmp))
        if result is not None:
            out["simulate"] = result
    return out


def _evaluate_path(platform, motion, budget: float) -> dict:
    """``gsfric.evaluate`` over ``motion`` (1e5 steps): fresh, into reused arrays, into memory
    mapped anew, with the paper's friction model; against the vectorised NumPy map."""
    best, median, cpu = best_times(lambda: gsfric.evaluate(platform, motion), budget)
    ev, buffers = Evaluator(platform), {}
    rbest, _, rcpu = best_times(lambda: ev.evaluate_quiet(motion, buffers=buffers), budget)

    # no dropped result's memory to reuse: every page mapped anew (the release untimed)
    fbest, _, fcpu = best_times(lambda: gsfric.evaluate(platform, motion), budget,
                                setup=release_memory)
    x = state_array(motion)
    nbest, _, ncpu = best_times(lambda: numpy_model.actuator_forces_numpy(platform, x), budget)
    paths = {"steps_per_s": 1e5 / best, "steps_per_cpu_s": 1e5 / cpu,
             "numpy_steps_per_s": 1e5 / nbest, "vs_numpy": nbest / best,
             "vs_numpy_cpu": ncpu / cpu, "reused_steps_per_s": 1e5 / rbest,
             "reused_steps_per_cpu_s": 1e5 / rcpu,
             "new_memory_steps_per_s": 1e5 / fbest,
             "new_memory_steps_per_cpu_s": 1e5 / fcpu}
    paper = gsfric.reference_platform("paper")
    pbest, _, pcpu = best_times(lambda: gsfric.evaluate(paper, motion), budget)
    paths.update(paper_steps_per_s=1e5 / pbest, paper_steps_per_cpu_s=1e5 / pcpu)
    return paths


def control_loop_paths(platform, budget: float) -> dict:
    """The README's control loop (a new Evaluator and ``forces`` over 40 steps) and the
    Evaluator's construction alone, in microseconds."""
    m40 = bench_motion(40)
    args = (m40.position, m40.rotation, m40.velocity, m40.omega, m40.acceleration, m40.alpha)
    best, median, cpu = best_times(lambda: Evaluator(platform).forces(*args), budget)
    out = {"control_loop_40": {"best_us": best * 1e6, "median_us": median * 1e6,
                               "cpu_us": cpu * 1e6}}
    best, median, cpu = best_times(lambda: Evaluator(platform), budget)
    out["evaluator_construct"] = {"best_us": best * 1e6, "median_us": median * 1e6}
    return out


def busy_core_paths(platform, x: np.ndarray, budget: float, progress,
                    sizes=(1_000, 100_000)) -> dict:
    """One and two threads of the compiled map with another process keeping a core busy, at
    each of ``sizes`` steps (the first rows of the states x)."""
    busy = {}
    worker = _busy_core()
    try:
        for n in sizes:
            progress(f"  one and two threads, other core busy, N={n:,}")
            xs = np.ascontiguousarray(x[:n])
            row = {}
            for threads in (1, 2):
                ev, o = Evaluator(platform, n_threads=threads), np.empty((n, 6))
                row[threads] = best_times(lambda: ev.actuator_forces(xs, o), budget)[1]
            busy[str(n)] = {"one_thread_ms": row[1] * 1e3, "two_threads_ms": row[2] * 1e3,
                            "two_vs_one": row[1] / row[2]}
    finally:
        worker.terminate()
        worker.wait()
    return busy
