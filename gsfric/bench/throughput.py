"""Throughput of the compiled combined map against two NumPy implementations (``gsfric bench``).

The compiled map ``Evaluator.actuator_forces`` (actuator forces with friction, NumPy in to NumPy
out, preallocated output) is timed on one and on two threads against the same physics written
in NumPy (``gsfric.numpy_model``): vectorised over steps, and a per-step loop that solves the
dense 42x42 system of (2)-(16) at every step. Every case runs on the reference platform over a
smooth random motion.

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

import json
import os
import platform as _platform
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

import gsfric
from gsfric import models
from gsfric.bench import numpy_engine as numpy_model
from gsfric.compiled import native
from gsfric.compiled.manifest import function, manifest
from gsfric.evaluation.evaluator import (
    Evaluator,
    model_function,
    release_memory,
    state_array,
)

SIZES = (40, 1_000, 100_000, 1_000_000)
QUICK_SIZES = (40, 1_000)
LOOP_MAX_STEPS = 1_000
SIMULATE_STEPS = 1_000_000   # benchmarks/memory_10M.py runs the same at 10 million
RATE = 1000.0
"""Sampling rate of the benchmark's motions, Hz."""
DT = 1 / RATE
SEED = 20261122

IMPLEMENTATIONS = {
    "compiled": "compiled C (Evaluator.actuator_forces), coupled friction model",
    "compiled_paper": "compiled C, the paper's post-hoc friction model",
    "numpy": "vectorised NumPy (numpy_model.actuator_forces_numpy)",
    "loop": "per-step loop, 42x42 solve (numpy_model.actuator_forces_loop)",
}

TARGETS = {
    "compiled_1e5_steps_per_s": ("compiled map, one core, N = 1e5", ">=", 1e6, "steps/s"),
    "speedup_vs_numpy": ("compiled (one core) / vectorised NumPy, N = 1e5", ">=", 10.0, "x"),
    "speedup_vs_loop": ("compiled (one core) / per-step loop, N = 1e5", ">=", 500.0, "x"),
    "latency_40_us": ("one call of 40 steps (median)", "<=", 50.0, "us"),
    "two_core_speedup_1e6": ("two cores / one core, N = 1e6", ">=", 1.7, "x"),
    "import_s": ("import gsfric, fresh interpreter (median)", "<=", 0.3, "s"),
    "evaluate_1e5_steps_per_s": ("gsfric.evaluate (kept outputs + flags), one core, N = 1e5",
                                 ">=", 2e6, "steps/s"),
    "evaluate_vs_numpy": ("gsfric.evaluate / vectorised NumPy actuator map, N = 1e5", ">=",
                          6.0, "x"),
    "control_loop_40_us": ("README control loop: new Evaluator + forces(), 40 steps (median)",
                           "<=", 20.0, "us"),
    "busy_two_vs_one": ("two threads / one thread with the other core busy, N = 1e3 and 1e5 "
                        "(worst)", ">=", 1.0, "x"),
    "evaluate_memory_1e6_gib": ("gsfric.evaluate at N = 1e6, peak memory added", "<=", 2.3,
                                "GiB"),
    "simulate_steps_per_s": (f"gsfric simulate to Parquet, default columns, N = "
                             f"{SIMULATE_STEPS:.0e} (wall clock, end to end)", ">=", 5e5,
                             "steps/s"),
    "simulate_peak_gb": (f"gsfric simulate, N = {SIMULATE_STEPS:.0e}, peak RSS", "<=", 1.0,
                         "GB"),
}


def _ratio(a: float | None, b: float | None) -> float:
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
        return _ratio(self.steps, self.best)

    @property
    def steps_per_cpu_second(self) -> float | None:
        """Steps per second of CPU time (one-thread cases only)."""
        return None if self.cpu_best is None else _ratio(self.steps, self.cpu_best)

    def as_dict(self) -> dict:
        out = asdict(self)
        out["steps_per_second"] = self.steps_per_second
        out["steps_per_cpu_second"] = self.steps_per_cpu_second
        return out


@dataclass
class Report:
    """Everything one run measured, with the machine and the command."""

    command: str
    machine: dict
    cases: list[Case] = field(default_factory=list)
    import_time: dict = field(default_factory=dict)
    paths: dict = field(default_factory=dict)
    ratios: dict = field(default_factory=dict)
    targets: dict = field(default_factory=dict)

    def case(self, implementation: str, threads: int, steps: int) -> Case | None:
        for c in self.cases:
            if (c.implementation, c.threads, c.steps) == (implementation, threads, steps):
                return c
        return None

    def as_dict(self) -> dict:
        return dict(command=self.command, machine=self.machine,
                    cases=[c.as_dict() for c in self.cases], import_time=self.import_time,
                    paths=self.paths,
                    ratios=self.ratios, targets=self.targets)


# --------------------------------------------------------------------------------- inputs
def states(n: int) -> np.ndarray:
    """States (n, 24) of a smooth random motion sampled every ``DT`` seconds."""

    return state_array(_motion(n))


def _callable(implementation: str, threads: int, x: np.ndarray):
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


def _time_calls(fn, budget: float, min_calls: int, max_calls: int,
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
    fn = _callable(implementation, threads, x)
    n = x.shape[0]
    slow = implementation == "loop" and n > 100
    if not slow:
        fn()
    cpu: list[float] = []
    times = _time_calls(fn, budget, 1 if slow else 3, 1 if slow else 100_000, cpu)
    return Case(implementation, threads, n, calls=len(times), best=min(times),
                median=statistics.median(times), cpu_best=min(cpu) if threads == 1 else None)


# --------------------------------------------------------------------------------- memory
def _status_kib(key: str) -> int | None:
    """A ``/proc/self/status`` figure in KiB (VmRSS, VmHWM), None where there is none."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def _reset_peak_rss() -> bool:
    """Reset this process's peak resident set size to the current one (Linux); True if done."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        return False
    return _status_kib("VmHWM") is not None


def _max_rss_kib() -> int:
    import resource

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return rss // 1024 if sys.platform == "darwin" else rss


def memory_child(implementation: str, threads: int, path: str) -> dict:
    """In a fresh process: the memory one call adds, in MiB (run by ``memory_case``).

    The states are read from ``path``; the evaluator, its output buffer and the compiled library
    are set up before the baseline. On Linux the peak resident set size is reset to the current
    one first, so the figure is the call's own peak above what was resident before it;
    elsewhere it is the rise of ``getrusage``'s maximum resident set size (a lower bound).
    """

    x = np.load(path)
    fn = _callable(implementation, threads, x)
    _callable(implementation, threads, x[:2])()
    if _reset_peak_rss():
        before = _status_kib("VmRSS")
        fn()
        rise = _status_kib("VmHWM") - before
    else:
        before = _max_rss_kib()
        fn()
        rise = _max_rss_kib() - before
    result = {"rss_mib": rise / 1024, "tracemalloc_mib": None}
    if not implementation.startswith("compiled"):
        tracemalloc.start()
        fn()
        result["tracemalloc_mib"] = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
    return result


def memory_case(implementation: str, threads: int, x: np.ndarray, folder: Path) -> dict:
    """Run ``memory_child`` for one case in a subprocess; returns its result."""
    path = folder / f"x{x.shape[0]}.npy"
    if not path.exists():
        np.save(path, x)
    code = ("import json, sys; from gsfric.bench import memory_child; "
            f"print(json.dumps(memory_child({implementation!r}, {threads}, {str(path)!r})))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    if run.returncode != 0:
        raise RuntimeError(f"memory case {implementation} N={x.shape[0]} failed: "
                           f"{run.stderr.strip().splitlines()[-1:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


# ---------------------------------------------------------------------------------- import
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


# ------------------------------------------------------------------- the other paths
def _motion(n: int):

    return models.random_motion(np.random.default_rng(SEED), DT * np.arange(n))


def _best_times(fn, budget: float, min_calls: int = 3,
                setup=None) -> tuple[float, float, float]:
    """(best wall, median wall, best CPU of the calling thread) seconds per call
    (``setup()`` before each call, untimed)."""
    fn()
    cpu: list[float] = []
    times = _time_calls(fn, budget, min_calls, 100_000, cpu, setup)
    return min(times), statistics.median(times), min(cpu)


def _busy_core():
    """A process that keeps one core busy until terminated."""
    return subprocess.Popen([sys.executable, "-c", "while True: pass"])


def evaluate_memory_child(n: int) -> dict:
    """In a fresh process: the peak memory ``gsfric.evaluate`` adds at n steps, in GiB."""

    motion = _motion(n)
    platform = gsfric.reference_platform()
    gsfric.evaluate(platform, _motion(50))
    if _reset_peak_rss():
        before = _status_kib("VmRSS")
        result = gsfric.evaluate(platform, motion)
        rise = _status_kib("VmHWM") - before
    else:
        before = _max_rss_kib()
        result = gsfric.evaluate(platform, motion)
        rise = _max_rss_kib() - before
    kept = result.arrays.kept()      # the detail outputs are computed only when read
    size = sum(v.nbytes for v in kept.values()) + result.flag.nbytes
    return {"peak_gib": rise / 2**20, "results_gib": size / 2**30, "arrays": len(kept),
            "values_per_step": sum(v[0].size for v in kept.values())}


def write_trajectory(path: Path, steps: int, group: int = 250_000) -> None:
    """A ``models.sinusoidal`` motion sampled every ``DT`` as a Parquet trajectory file
    (``t, x, y, z, qw, qx, qy, qz``), written in row groups of ``group`` rows."""
    import pyarrow as pa
    import pyarrow.parquet as pq


    writer = None
    try:
        for start in range(0, steps, group):
            t = np.arange(start, min(steps, start + group)) / RATE
            motion = models.sinusoidal(t)
            q = motion.quaternion()
            table = pa.table({"t": t, "x": motion.position[:, 0], "y": motion.position[:, 1],
                              "z": motion.position[:, 2], "qw": q[:, 0], "qx": q[:, 1],
                              "qy": q[:, 2], "qz": q[:, 3]})
            if writer is None:
                writer = pq.ParquetWriter(path, table.schema)
            writer.write_table(table)
    finally:
        if writer is not None:
            writer.close()


def run_simulate(trajectory, out, chunk: int | None = None, threads: int | None = None,
                 extra: tuple[str, ...] = ()) -> dict:
    """Run ``gsfric simulate`` of ``trajectory`` to ``out`` in a child process (default chunk
    and threads unless given): its exit code, output, wall and CPU seconds (``cpu_s``, the sum
    of ``user_s`` and ``system_s``) and peak resident set size.

    ``peak_rss_mb`` is the child's own ``ru_maxrss`` (``os.wait4``); ``children_max_rss_mb`` is
    ``getrusage(RUSAGE_CHILDREN).ru_maxrss`` of this process afterwards, the largest of all its
    waited-for children. Run it from a small process: a child's peak RSS counts the copy of its
    parent's memory it starts as. ``benchmarks/memory_10M.py`` runs it at 10 million steps.
    """
    import resource

    cmd = [sys.executable, "-m", "gsfric.cli", "simulate", "--trajectory", str(trajectory),
           "--out", str(out), "--no-progress", *extra]
    if chunk is not None:
        cmd += ["--chunk", str(chunk)]
    if threads is not None:
        cmd += ["--threads", str(threads)]
    start = time.perf_counter()
    with tempfile.TemporaryFile("w+") as stdout, tempfile.TemporaryFile("w+") as stderr:
        child = subprocess.Popen(cmd, stdout=stdout, stderr=stderr, text=True)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        stdout.seek(0)
        stderr.seek(0)
        out_text, err_text = stdout.read(), stderr.read()
    scale = 1 if sys.platform == "darwin" else 1024          # ru_maxrss: bytes or kB
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * scale
    return {"command": " ".join(["gsfric", *cmd[3:]]),
            "returncode": os.waitstatus_to_exitcode(status), "stdout": out_text.strip(),
            "stderr": err_text.strip(), "wall_s": wall,
            "cpu_s": usage.ru_utime + usage.ru_stime, "user_s": usage.ru_utime,
            "system_s": usage.ru_stime,
            "peak_rss_mb": usage.ru_maxrss * scale / 2**20,
            "children_max_rss_mb": children / 2**20}


def simulate_child(steps: int, trajectory: str, out: str) -> dict | None:
    """``run_simulate`` with the default columns and chunk: wall and CPU seconds, steps per
    second, peak RSS, the output's size; None when it failed."""
    run = run_simulate(trajectory, out, extra=("--quiet",))
    if run["returncode"] != 0:
        return None
    wall, cpu = run["wall_s"], run["cpu_s"]
    return {"steps": steps, "wall_s": wall, "cpu_s": cpu, "user_s": run["user_s"],
            "system_s": run["system_s"], "steps_per_s": steps / wall,
            "steps_per_cpu_s": steps / max(cpu, 1e-9),
            "peak_rss_gb": run["peak_rss_mb"] * 2**20 / 1e9,
            "output_gb": Path(out).stat().st_size / 1e9}


def simulate_case(steps: int, folder: Path) -> dict | None:
    """The trajectory written, then ``simulate_child`` run, each in a fresh process (this one
    is large by now); the files are removed."""
    trajectory, out = folder / "trajectory.parquet", folder / "forces.parquet"
    try:
        subprocess.run([sys.executable, "-c", "import sys; from pathlib import Path; "
                        "from gsfric.bench import write_trajectory; "
                        "write_trajectory(Path(sys.argv[1]), int(sys.argv[2]))",
                        str(trajectory), str(steps)], check=True)
        run = subprocess.run([sys.executable, "-c", "import json, sys; "
                              "from gsfric.bench import simulate_child; print(json.dumps("
                              "simulate_child(int(sys.argv[1]), sys.argv[2], sys.argv[3])))",
                              str(steps), str(trajectory), str(out)],
                             capture_output=True, text=True)
        if run.returncode != 0:
            return None
        return json.loads(run.stdout.strip().splitlines()[-1])
    finally:
        trajectory.unlink(missing_ok=True)
        out.unlink(missing_ok=True)


def measure_paths(budget: float, memory: bool, progress=print, simulate: bool = False) -> dict:
    """The paths around the hot path: ``evaluate`` with flags, the README's control loop,
    Evaluator construction, two threads against a busy core, evaluate's memory."""

    platform = gsfric.reference_platform()
    out: dict = {"friction_model": platform.friction.model}
    lib = native._library()
    out["lanes"] = lib.gsfric_simd_lanes() if lib is not None else None
    progress("  evaluate (kept outputs + flags) N=100,000")
    motion = _motion(100_000)
    best, median, cpu = _best_times(lambda: gsfric.evaluate(platform, motion), budget)
    ev, buffers = Evaluator(platform), {}
    rbest, _, rcpu = _best_times(lambda: ev.evaluate_quiet(motion, buffers=buffers), budget)

    # no dropped result's memory to reuse: every page mapped anew (the release untimed)
    fbest, _, fcpu = _best_times(lambda: gsfric.evaluate(platform, motion), budget,
                                 setup=release_memory)
    x = state_array(motion)
    nbest, _, ncpu = _best_times(lambda: numpy_model.actuator_forces_numpy(platform, x), budget)
    out["evaluate_1e5"] = {"steps_per_s": 1e5 / best, "steps_per_cpu_s": 1e5 / cpu,
                           "numpy_steps_per_s": 1e5 / nbest, "vs_numpy": nbest / best,
                           "vs_numpy_cpu": ncpu / cpu, "reused_steps_per_s": 1e5 / rbest,
                           "reused_steps_per_cpu_s": 1e5 / rcpu,
                           "new_memory_steps_per_s": 1e5 / fbest,
                           "new_memory_steps_per_cpu_s": 1e5 / fcpu}
    paper = gsfric.reference_platform("paper")
    pbest, _, pcpu = _best_times(lambda: gsfric.evaluate(paper, motion), budget)
    out["evaluate_1e5"].update(paper_steps_per_s=1e5 / pbest, paper_steps_per_cpu_s=1e5 / pcpu)
    progress("  README control loop, 40 steps")
    m40 = _motion(40)
    args = (m40.position, m40.rotation, m40.velocity, m40.omega, m40.acceleration, m40.alpha)
    best, median, cpu = _best_times(lambda: Evaluator(platform).forces(*args), budget)
    out["control_loop_40"] = {"best_us": best * 1e6, "median_us": median * 1e6,
                              "cpu_us": cpu * 1e6}
    best, median, cpu = _best_times(lambda: Evaluator(platform), budget)
    out["evaluator_construct"] = {"best_us": best * 1e6, "median_us": median * 1e6}
    busy = {}
    worker = _busy_core()
    try:
        for n in (1_000, 100_000):
            progress(f"  one and two threads, other core busy, N={n:,}")
            xs = np.ascontiguousarray(x[:n])
            row = {}
            for threads in (1, 2):
                ev, o = Evaluator(platform, n_threads=threads), np.empty((n, 6))
                row[threads] = _best_times(lambda: ev.actuator_forces(xs, o), budget)[1]
            busy[str(n)] = {"one_thread_ms": row[1] * 1e3, "two_threads_ms": row[2] * 1e3,
                            "two_vs_one": row[1] / row[2]}
    finally:
        worker.terminate()
        worker.wait()
    out["busy_core"] = busy
    if memory:
        progress("  evaluate memory, N=1,000,000 (fresh process)")
        code = ("import json; from gsfric.bench import evaluate_memory_child; "
                "print(json.dumps(evaluate_memory_child(1_000_000)))")
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        if run.returncode == 0:
            out["evaluate_memory_1e6"] = json.loads(run.stdout.strip().splitlines()[-1])
    if simulate:
        progress(f"  gsfric simulate to Parquet, N={SIMULATE_STEPS:,} (fresh process)")
        with tempfile.TemporaryDirectory(prefix="gsfric-bench-") as tmp:
            result = simulate_case(SIMULATE_STEPS, Path(tmp))
        if result is not None:
            out["simulate"] = result
    return out


# ------------------------------------------------------------------------- machine check
def parallel_capacity(iterations: int = 3_000_000) -> float:
    """How many cores two CPU-bound processes get together: 2.0 with two idle cores.

    The wall time of one pure-Python loop alone, over that of two copies started together,
    times two. Other load on the machine lowers it; two-thread figures are bounded by it.
    """
    code = f"s = 0\nfor i in range({iterations}): s += i"

    def wall(copies: int) -> float:
        start = time.perf_counter()
        procs = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(copies)]
        for proc in procs:
            proc.wait()
        return time.perf_counter() - start

    wall(1)
    return 2 * wall(1) / wall(2)


# ------------------------------------------------------------------------------------ run
def _machine() -> dict:

    model = _platform.processor() or _platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass

    compiled = native.is_compiled()

    # the actuator map the reference platform runs (its friction model's, derive/build.py)
    simd = bool(function(model_function("actuator", "coupled")).get("simd", False))
    return {"cpu": model, "cores": os.cpu_count(), "python": _platform.python_version(),
            "numpy": np.__version__, "os": _platform.platform(),
            "compiled": compiled,
            "compiler": " ".join(native._compiler() + list(native.CFLAGS))
                        + f" (SIMD source: {' '.join(native.SIMD_CFLAGS)})" if compiled
            else "none (CasADi fallback)",
            "actuator_entry": (f"SIMD over steps, {_lanes()} lanes" if simd
                               else "one step per call"),
            "source": _source_version(),
            "instructions": {f["name"].removeprefix("gsfric_model_"): f.get("n_instructions")
                             for f in manifest()["functions"]},
            "load_average_start": _load_average()}


def _lanes():

    lib = native._library()
    return lib.gsfric_simd_lanes() if lib is not None else None


def _source_version() -> str | None:
    """``git describe`` of the source tree (``-dirty`` with uncommitted changes), if any."""
    try:
        run = subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True,
                             text=True, cwd=Path(__file__).resolve().parent, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return run.stdout.strip() or None if run.returncode == 0 else None


def _load_average() -> list[float] | None:
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return None


def _ratios(report: Report, sizes) -> dict:
    out = {}
    for n in sizes:
        c1 = report.case("compiled", 1, n)
        c2 = report.case("compiled", 2, n)
        npy = report.case("numpy", 1, n)
        loop = report.case("loop", 1, n)
        out[str(n)] = {
            "compiled_vs_numpy": _ratio(npy.best, c1.best),
            "compiled_vs_loop": _ratio(loop.best, c1.best),
            "two_vs_one_core": _ratio(c1.best, c2.best),
            "compiled_vs_numpy_cpu": _ratio(npy.cpu_best, c1.cpu_best),
        }
    return out


def _targets(report: Report) -> dict:
    values = {}
    big = report.case("compiled", 1, 100_000)
    notes = {}
    if big is not None:
        values["compiled_1e5_steps_per_s"] = big.steps_per_second
        notes["compiled_1e5_steps_per_s"] = (f"{big.steps_per_cpu_second:.3g} per CPU "
                                             "second")
        notes["speedup_vs_numpy"] = (f"{report.ratios['100000']['compiled_vs_numpy_cpu']:.3g}"
                                     " in CPU time")
        values["speedup_vs_numpy"] = report.ratios["100000"]["compiled_vs_numpy"]
        values["speedup_vs_loop"] = report.ratios["100000"]["compiled_vs_loop"]
    small = report.case("compiled", 1, 40)
    if small is not None:
        values["latency_40_us"] = small.median * 1e6
    if "1000000" in report.ratios:
        values["two_core_speedup_1e6"] = report.ratios["1000000"]["two_vs_one_core"]
        free = min(report.machine.get("parallel_capacity_start", float("nan")),
                   report.machine.get("parallel_capacity_end", float("nan")))
        notes["two_core_speedup_1e6"] = f"cores free for the run: {free:.2f} of 2"
    values["import_s"] = report.import_time["median_s"]
    paths = report.paths
    if "evaluate_1e5" in paths:
        e = paths["evaluate_1e5"]
        values["evaluate_1e5_steps_per_s"] = e["steps_per_s"]
        notes["evaluate_1e5_steps_per_s"] = f"{e['steps_per_cpu_s']:.3g} per CPU second"
        values["evaluate_vs_numpy"] = e["vs_numpy"]
        notes["evaluate_vs_numpy"] = f"{e['vs_numpy_cpu']:.3g} in CPU time"
    if "control_loop_40" in paths:
        values["control_loop_40_us"] = paths["control_loop_40"]["median_us"]
        notes["control_loop_40_us"] = (f"best {paths['control_loop_40']['best_us']:.3g} us, "
                                       f"CPU {paths['control_loop_40']['cpu_us']:.3g} us")
    if paths.get("busy_core"):
        values["busy_two_vs_one"] = min(r["two_vs_one"] for r in paths["busy_core"].values())
    if "evaluate_memory_1e6" in paths:
        mem = paths["evaluate_memory_1e6"]
        values["evaluate_memory_1e6_gib"] = mem["peak_gib"]
        notes["evaluate_memory_1e6_gib"] = f"results {mem['results_gib']:.3g} GiB"
    if "simulate" in paths:
        sim = paths["simulate"]
        values["simulate_steps_per_s"] = sim["steps_per_s"]
        notes["simulate_steps_per_s"] = f"{sim['steps_per_cpu_s']:.3g} per CPU second"
        values["simulate_peak_gb"] = sim["peak_rss_gb"]
    out = {}
    for key, value in values.items():
        label, op, target, unit = TARGETS[key]
        met = value >= target if op == ">=" else value <= target
        out[key] = {"label": label, "value": value, "target": f"{op} {target:g} {unit}",
                    "met": bool(met), "note": notes.get(key, "")}
    return out


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
    report = Report(command=_command(), machine=_machine())
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
    report.ratios = _ratios(report, sizes)
    report.targets = _targets(report)
    report.machine["load_average_end"] = _load_average()
    report.machine["parallel_capacity_end"] = parallel_capacity()
    return report


# ---------------------------------------------------------------------------------- table
def _seconds(t: float) -> str:
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if t >= scale:
            return f"{t / scale:.3g} {unit}"
    return f"{t * 1e9:.3g} ns"


def _mib(value: float | None) -> str:
    return "-" if value is None else f"{max(value, 0.0):.1f}"


def format_report(report: Report) -> str:
    """The report as a plain-text table, ratios and targets."""
    m = report.machine
    lines = ["gsfric bench: actuator forces with friction, reference platform "
             "(NumPy in, NumPy out)",
             f"machine: {m['cpu']}, {m['cores']} cores; Python {m['python']}, "
             f"NumPy {m['numpy']}; compiled with: {m['compiler']}; actuator map: "
             f"{m['actuator_entry']}",
             "CasADi instructions per step (generated/manifest.json): " + ", ".join(
                 f"{name} {n}" for name, n in m.get("instructions", {}).items()),
             f"source: {m.get('source')}; load average (1, 5, 15 min): start "
             f"{m['load_average_start']}, end {m.get('load_average_end')}",
             f"cores free for this run (two CPU-bound processes together, 2.0 = two idle "
             f"cores): start {m.get('parallel_capacity_start', float('nan')):.2f}, end "
             f"{m.get('parallel_capacity_end', float('nan')):.2f}", ""]
    head = (f"{'implementation':<14} {'threads':>7} {'N':>9} {'steps/s':>10} "
            f"{'(CPU time)':>10} {'latency best':>13} {'median':>10} {'calls':>6} "
            f"{'mem RSS MiB':>12} {'tracemalloc':>12}")
    lines += [head, "-" * len(head)]
    order = {"compiled": 0, "compiled_paper": 1, "numpy": 2, "loop": 3}
    for c in sorted(report.cases, key=lambda c: (c.steps, order[c.implementation],
                                                  c.threads)):
        mark = " (extrapolated)" if c.extrapolated else ""
        cpu = "-" if c.steps_per_cpu_second is None else f"{c.steps_per_cpu_second:.3g}"
        lines.append(f"{c.implementation:<14} {c.threads:>7} {c.steps:>9,} "
                     f"{c.steps_per_second:>10.3g} {cpu:>10} {_seconds(c.best):>13} "
                     f"{_seconds(c.median):>10} {c.calls:>6} {_mib(c.memory_rss_mib):>12} "
                     f"{_mib(c.memory_tracemalloc_mib):>12}{mark}")
    lines += ["", "ratios of the fastest calls: compiled on one core vs vectorised NumPy (wall "
              "clock; CPU time), vs the per-step loop; compiled on two cores vs one"]
    for n, r in report.ratios.items():
        lines.append(f"  N = {int(n):>9,}: {r['compiled_vs_numpy']:6.1f}x "
                     f"({r['compiled_vs_numpy_cpu']:5.1f}x) NumPy  "
                     f"{r['compiled_vs_loop']:8.0f}x loop  {r['two_vs_one_core']:5.2f}x on two "
                     "cores")
    p = report.paths
    if p:
        lines += ["", f"SIMD lanes: {p.get('lanes')}"]
        if "evaluate_1e5" in p:
            e = p["evaluate_1e5"]
            lines.append("gsfric.evaluate (the kept outputs + flags; the detail outputs, "
                         "evaluation.DETAILS, are computed on first read), "
                         f"{p.get('friction_model')} friction model, N = 100,000: "
                         f"{e['steps_per_s']:.3g} steps/s ({e['steps_per_cpu_s']:.3g} per CPU "
                         f"second), {e['vs_numpy']:.1f}x the vectorised NumPy actuator map "
                         f"({e['vs_numpy_cpu']:.1f}x in CPU time); into reused arrays "
                         f"(evaluate_quiet(buffers=...)): {e['reused_steps_per_s']:.3g} steps/s "
                         f"({e['reused_steps_per_cpu_s']:.3g} per CPU second)")
            if "new_memory_steps_per_s" in e:
                lines.append("gsfric.evaluate into memory mapped anew (no dropped result's "
                             "memory to reuse, evaluation.release_memory() before each call): "
                             f"{e['new_memory_steps_per_s']:.3g} steps/s "
                             f"({e['new_memory_steps_per_cpu_s']:.3g} per CPU second)")
            if "paper_steps_per_s" in e:
                lines.append(f"gsfric.evaluate, paper friction model (no fixed-point "
                             f"iterations), N = 100,000: {e['paper_steps_per_s']:.3g} steps/s "
                             f"({e['paper_steps_per_cpu_s']:.3g} per CPU second)")
        if "control_loop_40" in p:
            c, k = p["control_loop_40"], p["evaluator_construct"]
            lines.append(f"README control loop (new Evaluator + forces, 40 steps): median "
                         f"{c['median_us']:.3g} us, best {c['best_us']:.3g} us; Evaluator() "
                         f"alone: median {k['median_us']:.3g} us")
        for n, r in p.get("busy_core", {}).items():
            lines.append(f"other core busy, N = {int(n):,}: one thread {r['one_thread_ms']:.3g} "
                         f"ms, two threads {r['two_threads_ms']:.3g} ms (median): "
                         f"{r['two_vs_one']:.2f}x")
        if "evaluate_memory_1e6" in p:
            mem = p["evaluate_memory_1e6"]
            lines.append(f"gsfric.evaluate at N = 1e6: peak memory added {mem['peak_gib']:.3g} "
                         f"GiB (results {mem['results_gib']:.3g} GiB: "
                         f"{mem.get('values_per_step', '?')} values per step in "
                         f"{mem.get('arrays', '?')} arrays, the detail outputs not read)")
        if "simulate" in p:
            sim = p["simulate"]
            lines.append(f"gsfric simulate, {sim['steps']:,} steps Parquet to Parquet (default "
                         f"columns): {sim['wall_s']:.3g} s wall, {sim['cpu_s']:.3g} s CPU "
                         f"({sim.get('user_s', float('nan')):.3g} user, "
                         f"{sim.get('system_s', float('nan')):.3g} system), "
                         f"{sim['steps_per_s']:.3g} steps/s ({sim['steps_per_cpu_s']:.3g} per "
                         f"CPU second), peak RSS {sim['peak_rss_gb']:.3g} GB, output "
                         f"{sim['output_gb']:.3g} GB")
    it = report.import_time
    lines += ["", f"import gsfric: median {it['median_s'] * 1e3:.0f} ms, best "
              f"{it['best_s'] * 1e3:.0f} ms over {it['runs']} fresh interpreters "
              f"(-X importtime: {it['importtime_cumulative_s'] * 1e3:.0f} ms); import + "
              f"Evaluator + first 40-step call: {it['first_call_s'] * 1e3:.0f} ms", "",
              "targets:"]
    for t in report.targets.values():
        value = t["value"]
        shown = f"{value:.3g}"
        note = f"; {t['note']}" if t.get("note") else ""
        lines.append(f"  [{'met' if t['met'] else 'MISSED':>6}] {t['label']}: {shown} "
                     f"(target {t['target']}{note})")
    return "\n".join(lines)


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
    print(format_report(report))
    if out is not None:
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(report.as_dict(), indent=2) + "\n")
        print(f"wrote {out}")
    return report
