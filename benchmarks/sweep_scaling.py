"""Throughput of ``gsfric sweep``: the model's evaluation alone, with the reduction, and on Dask.

One workspace sweep (Latin-hypercube poses x dynamic states on the reference platform) is run
in up to seven ways on the same steps, each in one thread (one core), the states built as the
sweep builds them:

* ``evaluate``: ``Evaluator.evaluate_quiet`` ``BLOCK_STEPS`` steps at a time into reused
  buffers (every output): a loop over the evaluator's public call; no reduction;
* ``eval-only``: the model's compiled ``eval`` on the outputs an envelope is made of or flagged
  by (``NEEDED``: loads, friction, rates, flags' inputs), with the step flags, block by block
  into reused buffers; no reduction: **direct evaluation**, the reference of the target;
* ``envelope-only``: the generated function the sweep evaluates (``envelope``: the 78 values
  per step an envelope maximises, with the step flags), block by block; no reduction;
* ``direct``: ``envelope-only`` and the fold of each block into the running envelope, in one
  loop in this process: the sweep's arithmetic without tasks, files or Dask;
* ``serial``: ``gsfric.sweep.sweep(scheduler="serial")``: the plan (poses, reachability), the tasks
  in this process, the task envelopes, the chunk files and the merge;
* ``dask-1`` and ``dask-2``: ``gsfric.sweep.sweep`` on the ``LocalCluster`` of
  ``scheduler="local"`` (``gsfric.sweep.run.local_cluster``) with 1 and 2 single-threaded
  worker processes, started for the run and warmed by a one-pose task (start-up timed apart:
  paid once per sweep); one cluster at a time; the workers' peak memory (resident set) is
  printed.

With ``--repeat N`` every path runs N times, interleaved (each path once, then again), and the
fastest run of each is compared, with the spread (slowest over fastest) printed: on a shared
machine the fastest run is the least disturbed. It prints wall-clock steps/s of each and the
CPU time of the process(es) doing the work (the figure to read on a shared machine), the time
per step per core against ``eval-only`` (the target: the Dask path within 1.3x on >= 1e7
steps), against ``direct`` (what tasks and Dask add) and against ``evaluate``, and the speed-up
of 2 workers over 1 (target >= 1.7x), fastest over fastest and run by run::

    .venv/bin/python benchmarks/sweep_scaling.py                    # 1e6 steps
    .venv/bin/python benchmarks/sweep_scaling.py --steps 1e7 --repeat 3   # the target's size
    .venv/bin/python benchmarks/sweep_scaling.py --steps 2e6 --paths dask-1 --json out.json

docs/howto/sizing.md has the figures of one run and the cost of a 1e10-step sweep computed from them.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import tempfile
import threading
import time
import warnings
from pathlib import Path

# one core per path, as Dask's workers have (they set these to 1): otherwise numpy's BLAS would
# use every core in this process and not in the workers
for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_name] = "1"

import numpy as np  # noqa: E402

from gsfric import models  # noqa: E402
from gsfric._optional import optional  # noqa: E402
from gsfric.compiled import native  # noqa: E402
from gsfric.compiled.state import state_layout  # noqa: E402
from gsfric.evaluation.evaluator import Evaluator  # noqa: E402
from gsfric.evaluation.parameters import model_function  # noqa: E402
from gsfric.sweep import Workspace, sweep  # noqa: E402
from gsfric.sweep.blocks import Block, Evaluation  # noqa: E402
from gsfric.sweep.envelope import Envelope  # noqa: E402
from gsfric.sweep.plan import CHUNK_STEPS  # noqa: E402
from gsfric.sweep.run import local_cluster  # noqa: E402
from gsfric.sweep.tasks import BLOCK_STEPS, Task, run_task  # noqa: E402
from gsfric.sweep.workspace import SCRATCH  # noqa: E402
from gsfric.trajectory import Motion  # noqa: E402

PATHS = ("evaluate", "eval-only", "envelope-only", "direct", "serial", "dask-1", "dask-2")


def workspace(steps: int, states: int = 8) -> Workspace:
    """The benchmark's workspace: ``steps // states`` Latin-hypercube poses."""
    return Workspace.from_dict({
        "sampling": "lhs", "samples": max(1, steps // states), "states": states, "seed": 0,
        "pose": {"x": [-0.05, 0.05], "y": [-0.05, 0.05], "z": [0.65, 0.75],
                 "roll": [-0.1, 0.1], "pitch": [-0.1, 0.1], "yaw": [-0.15, 0.15]},
        "bounds": {"velocity": 0.2, "omega": 0.5, "acceleration": 2.0, "alpha": 5.0}})


def _blocks(ws, poses):
    """(first step, states, times) of the workspace, ``BLOCK_STEPS`` states at a time, built as
    the sweep builds them (into one reused buffer)."""
    per = max(1, BLOCK_STEPS // ws.states)
    zeros = np.zeros(per * ws.states)
    buffer = np.empty(per * ws.states * (state_layout().size + SCRATCH))
    for p0 in range(0, len(poses), per):
        x = ws.states_of(poses[p0:p0 + per], p0, out=buffer)
        yield p0 * ws.states, x, zeros[:len(x)]


def cpu_seconds() -> float:
    """CPU time of this process (all its threads), s."""
    return time.process_time()


def evaluate(ws) -> tuple[int, float]:
    """``Evaluator.evaluate_quiet`` (all outputs) block by block; (steps, seconds)."""
    poses = ws.poses()
    ev = Evaluator(models.reference_platform())
    buffers: dict = {}
    steps = 0
    start = time.perf_counter()
    for _, x, t in _blocks(ws, poses):
        n = len(x)
        motion = Motion(t, *state_layout().split(x))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ev.evaluate_quiet(motion, buffers=buffers)
        steps += n
    return steps, time.perf_counter() - start


NEEDED = ("R_E", "R_C", "R_3", "M_3", "MfrE", "MfrC", "omega_rel", "omega_leg", "M_C", "F",
          "Ffr", "D_dot", "D", "s2", "h", "coupling_change", "F0")
"""The outputs of ``eval`` an envelope is made of (loads, friction, rates) or flagged by."""


def eval_only(ws) -> tuple[int, float]:
    """The model's compiled ``eval`` (derived with the platform's friction model fixed, as
    ``evaluate`` runs it) on the outputs an envelope needs (``NEEDED``), with the step flags,
    block by block into reused buffers; no reduction."""
    poses = ws.poses()
    platform = models.reference_platform()
    ev = Evaluator(platform, n_threads=1)
    fn = native.get(model_function("eval", platform.friction.model))
    spec = ev.flag_spec()
    sizes = {name: size for name, size, _ in fn.outputs}
    flat = {k: np.empty(BLOCK_STEPS * sizes[k]) for k in NEEDED}
    flag = np.empty(BLOCK_STEPS, dtype=np.int64)
    steps = 0
    start = time.perf_counter()
    for _, x, _ in _blocks(ws, poses):
        n = len(x)
        out = {k: v[:n * sizes[k]].reshape(n, sizes[k]) for k, v in flat.items()}
        fn([x, ev.P, ev.Q], out, 1, select=NEEDED, flags=spec, flag=flag[:n])
        steps += n
    return steps, time.perf_counter() - start


def direct(ws, reduce: bool) -> tuple[int, float]:
    """The sweep's block evaluation (generated ``envelope``) and, with ``reduce``, its fold
    into the running envelope, in one loop."""
    poses = ws.poses()
    block = Block(BLOCK_STEPS)
    evaluation = Evaluation(models.reference_platform())
    envelope = Envelope()
    steps = 0
    start = time.perf_counter()
    for first, x, t in _blocks(ws, poses):
        for s, e in evaluation.blocks(block, x, t):
            if reduce:
                envelope.add(block.values, block.flag, x[s:e], t[s:e], first + s, False,
                             block.pairs)
        steps += len(x)
    return steps, time.perf_counter() - start


def warm() -> None:
    """A worker's one-time cost: a task of one pose (imports: gsfric, pandas, SciPy's
    rotations; the compiled library loaded, or compiled, from the cache)."""
    run_task(Task(0, "workspace", [0], [models.reference_platform()], 8,
                  poses=np.array([[0.0, 0.0, 0.7, 0.0, 0.0, 0.0]]), workspace=workspace(8)))


def peak_rss_mb() -> float:
    """This process's peak resident set, MB: ``VmHWM`` of /proc/self/status (Linux; reset by
    exec, unlike ``ru_maxrss``, which a spawned worker inherits from its parent), else
    ``ru_maxrss``."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def worker_threads() -> dict:
    """What a worker runs with: its BLAS thread variables and its threads."""
    return {"OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS"),
            "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS"),
            "MKL_NUM_THREADS": os.environ.get("MKL_NUM_THREADS"),
            "threads": threading.active_count()}


def swept(ws, chunk: int, scheduler) -> tuple[int, float, dict]:
    """``gsfric.sweep.sweep`` of the workspace on ``scheduler``; (steps, seconds, info)."""
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        result = sweep(Path(tmp) / "out", workspace=ws, scheduler=scheduler,
                       chunk_steps=chunk, plots=False, progress=False)
        return result.info["steps"], time.perf_counter() - start, result.info


def run_path(name: str, ws, chunk: int) -> dict:
    """One run of path ``name``: steps, seconds, CPU s of the process(es) doing the work and of
    this process (the client) besides."""
    cpu0 = cpu_seconds()
    out = {"tasks": None}
    if name == "evaluate":
        steps, sec = evaluate(ws)
    elif name == "eval-only":
        steps, sec = eval_only(ws)
    elif name in ("envelope-only", "direct"):
        steps, sec = direct(ws, reduce=name == "direct")
    elif name == "serial":
        steps, sec, info = swept(ws, chunk, "serial")
        out["tasks"] = info["tasks"]
    else:
        Client = optional("distributed").Client
        n = int(name[-1])
        t0 = time.perf_counter()
        # one cluster at a time: an idle one's scheduler and nannies would run in this process
        with local_cluster(n) as cluster, Client(cluster, set_as_default=False) as client:
            client.wait_for_workers(n)
            client.run(warm)       # import gsfric and load the cached compiled library
            out["startup"] = time.perf_counter() - t0
            before = client.run(cpu_seconds)
            cpu0 = cpu_seconds()
            steps, sec, info = swept(ws, chunk, client)
            client_cpu = cpu_seconds() - cpu0
            after = client.run(cpu_seconds)
            out.update(tasks=info["tasks"], work_cpu=sum(after[w] - before[w] for w in after),
                       client_cpu=client_cpu, memory=max(client.run(peak_rss_mb).values()),
                       threads=next(iter(client.run(worker_threads).values())))
    if "work_cpu" not in out:
        out.update(work_cpu=cpu_seconds() - cpu0, client_cpu=0.0)
    out.update(steps=steps, seconds=sec, workers=int(name[-1]) if name.startswith("dask")
               else 1)
    return out


def _arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, default=1e6)
    parser.add_argument("--chunk", type=int, default=CHUNK_STEPS, help="steps per task")
    parser.add_argument("--paths", nargs="+", choices=PATHS, default=list(PATHS))
    parser.add_argument("--repeat", type=int, default=1,
                        help="runs of every path, interleaved (path after path, round after "
                        "round); the fastest run of each is compared, the spread printed")
    parser.add_argument("--json", type=Path, help="also write the figures as JSON")
    return parser.parse_args()


def _table(runs: dict[str, list[dict]], steps: int) -> tuple[dict, dict]:
    """Print each path's fastest run; (best (steps, seconds, workers), cpu (work, client))."""
    print(f"{'path':<14} {'workers':>7} {'seconds':>9} {'spread':>7} {'steps/s':>10} "
          f"{'steps/s/core':>13} {'cpu s':>8} {'steps/cpu-s':>12} {'client cpu s':>13}")
    best, cpu = {}, {}
    for name, rs in runs.items():
        sec = [r["seconds"] for r in rs]
        b = min(rs, key=lambda r: r["seconds"])
        best[name] = (b["steps"], b["seconds"], b["workers"])
        cpu[name] = (min(r["work_cpu"] for r in rs), min(r["client_cpu"] for r in rs))
        n = b["workers"]
        print(f"{name:<14} {n:>7} {b['seconds']:>9.2f} {max(sec) / min(sec) - 1:>6.0%} "
              f"{steps / b['seconds']:>10.0f} {steps / b['seconds'] / n:>13.0f} "
              f"{cpu[name][0]:>8.2f} {steps / cpu[name][0]:>12.0f} {cpu[name][1]:>13.2f}")
    print("(seconds: the fastest run; spread: slowest over fastest - 1; cpu s: the least CPU "
          "time of the process(es) doing the work, this one or the Dask workers together; "
          "client cpu s: this process while the workers ran)")
    return best, cpu


def _comparisons(figures: dict, runs: dict[str, list[dict]], startup: dict, memory: dict,
                 threads: dict) -> list[str]:
    """The lines comparing the paths (and the ratios added to ``figures``)."""
    per_core, per_cpu = figures["rates_per_core"], figures["rates_per_cpu_s"]

    def ratio(slow, fast):
        if slow in per_core and fast in per_core:
            figures[f"{slow}_over_{fast}"] = per_core[fast] / per_core[slow]
            figures[f"{slow}_over_{fast}_cpu"] = per_cpu[fast] / per_cpu[slow]
            return (f"{per_core[fast] / per_core[slow]:.2f}x "
                    f"(cpu {per_cpu[fast] / per_cpu[slow]:.2f}x)")
        return None

    lines = []
    for ref, what in (("eval-only", "the model's evaluation of the outputs an envelope needs "
                       "(target: dask-1 <= 1.3x)"),
                      ("direct", "the sweep's arithmetic in one loop (what tasks and Dask "
                       "add)"),
                      ("evaluate", "the public Evaluator.evaluate_quiet, all outputs")):
        parts = [f"{k} {r}" for k in ("envelope-only", "direct", "serial", "dask-1", "dask-2")
                 if k != ref and (r := ratio(k, ref))]
        if parts:
            lines.append(f"time per step per core against {ref}, {what}: " + ", ".join(parts))
    if "dask-1" in runs and "dask-2" in runs:
        figures["speedup_2_over_1"] = per_core["dask-2"] * 2 / per_core["dask-1"]
        pairs = sorted(a["seconds"] / b["seconds"] for a, b in zip(runs["dask-1"],
                                                                 runs["dask-2"]))
        figures["speedup_2_over_1_runs"] = pairs
        lines.append(f"2 workers over 1 (target >= 1.7x): {figures['speedup_2_over_1']:.2f}x "
                     "fastest over fastest; run by run " +
                     ", ".join(f"{p:.2f}x" for p in pairs))
    if startup:
        lines.append("LocalCluster start-up with the workers' imports: " +
                     ", ".join(f"{n} worker(s) {s:.2f} s" for n, s in startup.items()))
    if memory:
        lines.append("workers' peak memory: " +
                     ", ".join(f"{k} {v:.0f} MB" for k, v in memory.items()) +
                     f"; this process {figures['client_peak_rss_mb']:.0f} MB")
    if threads:
        lines.append(f"a worker's threads: {next(iter(threads.values()))}")
    return lines


def main() -> None:
    args = _arguments()
    native.is_compiled()
    ws = workspace(int(args.steps))
    runs: dict[str, list[dict]] = {name: [] for name in args.paths}
    for _ in range(args.repeat):
        for name in args.paths:
            runs[name].append(run_path(name, ws, args.chunk))
    startup = {int(k[-1]): min(r["startup"] for r in v) for k, v in runs.items()
               if k.startswith("dask")}
    memory = {k: max(r["memory"] for r in v) for k, v in runs.items() if k.startswith("dask")}
    threads = {k: v[0]["threads"] for k, v in runs.items() if k.startswith("dask")}
    first = next(iter(runs.values()))[0]
    steps = first["steps"]
    tasks = next((r[0]["tasks"] for r in runs.values() if r[0]["tasks"]), None)
    print(f"sweep of {steps} steps ({ws.samples} poses x {ws.states} states), "
          f"{args.chunk} steps per task ({tasks} tasks), {BLOCK_STEPS} steps per block, "
          f"{args.repeat} interleaved run(s) of each path")
    best, cpu = _table(runs, steps)
    per_core = {k: v[0] / v[1] / v[2] for k, v in best.items()}
    per_cpu = {k: best[k][0] / cpu[k][0] for k in best}
    figures = {"steps": steps, "chunk": args.chunk, "tasks": tasks, "repeat": args.repeat,
               "block": BLOCK_STEPS, "rates_per_core": per_core, "rates_per_cpu_s": per_cpu,
               "cpu_s": cpu, "runs": runs,
               "cluster_startup_s": startup, "worker_peak_rss_mb": memory,
               "client_peak_rss_mb": peak_rss_mb(), "worker_threads": threads}
    print("\n".join(_comparisons(figures, runs, startup, memory, threads)))
    if args.json:
        args.json.write_text(json.dumps(figures, indent=1))


if __name__ == "__main__":
    main()
