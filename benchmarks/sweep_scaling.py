"""Throughput of ``gsfric sweep``: direct evaluation, in-process tasks, Dask with 1 and 2 workers.

One workspace sweep (Latin-hypercube poses x dynamic states on the reference platform) is run
four ways on the same steps:

* ``direct``: ``Evaluator.evaluate`` called on the same states, chunk by chunk, in this
  process, no reduction (what a user looping over the evaluator would get);
* ``serial``: ``gsfric.sweep(scheduler="serial")``: the same tasks in this process, with the
  reduction to envelopes, the chunk files and the merge;
* ``dask-1`` and ``dask-2``: ``gsfric.sweep`` on a ``LocalCluster`` of 1 and 2 single-threaded
  worker processes (cluster start-up and the workers' imports timed apart: paid once per sweep).

It prints steps/s of each, the Dask path's cost per core against ``direct`` (target <= 1.3x on
>= 1e7 steps) and the speed-up of 2 workers over 1 (target >= 1.7x)::

    .venv/bin/python benchmarks/sweep_scaling.py                    # 1e6 steps
    .venv/bin/python benchmarks/sweep_scaling.py --steps 10000000   # the target's size
    .venv/bin/python benchmarks/sweep_scaling.py --steps 200000 --json out.json

The machine it runs on should be otherwise idle; docs/sizing.md has the figures of one run and
the cost of a 1e10-step sweep computed from them.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import tempfile
import time
import warnings
from pathlib import Path

# one core per path, as Dask's workers have (they set these to 1): otherwise numpy's LAPACK
# (the flags' condition numbers) would use every core in this process and not in the workers
for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_name] = "1"

import numpy as np  # noqa: E402


def workspace(steps: int, states: int = 8):
    from gsfric.sweep import Workspace

    return Workspace.from_dict({
        "sampling": "lhs", "samples": max(1, steps // states), "states": states, "seed": 0,
        "pose": {"x": [-0.05, 0.05], "y": [-0.05, 0.05], "z": [0.65, 0.75],
                 "roll": [-0.1, 0.1], "pitch": [-0.1, 0.1], "yaw": [-0.15, 0.15]},
        "bounds": {"velocity": 0.2, "omega": 0.5, "acceleration": 2.0, "alpha": 5.0}})


def direct(ws, chunk: int) -> tuple[int, float]:
    """Evaluator.evaluate over the workspace's states in chunks; (steps, seconds)."""
    from gsfric import models
    from gsfric.evaluation import Evaluator
    from gsfric.trajectory import Motion

    poses = ws.poses()
    ev = Evaluator(models.reference_platform())
    per = max(1, chunk // ws.states)
    steps = 0
    start = time.perf_counter()
    for p0 in range(0, len(poses), per):
        x = ws.states_of(poses[p0:p0 + per], p0)
        n = len(x)
        motion = Motion(np.zeros(n), x[:, 0:3], x[:, 3:12].reshape(n, 3, 3), x[:, 12:15],
                        x[:, 15:18], x[:, 18:21], x[:, 21:24])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ev.evaluate(motion)
        steps += n
    return steps, time.perf_counter() - start


def warm() -> None:
    """A worker's one-time cost: import the sweep and load (or compile) the library."""
    import gsfric.sweep  # noqa: F401
    from gsfric import native

    native.get("eval")


def swept(ws, chunk: int, scheduler) -> tuple[int, float]:
    import gsfric

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        result = gsfric.sweep(Path(tmp) / "out", workspace=ws, scheduler=scheduler,
                              chunk_steps=chunk, plots=False, progress=False)
        return result.info["steps"], time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, default=1e6)
    parser.add_argument("--chunk", type=int, default=100_000, help="steps per task")
    parser.add_argument("--json", type=Path, help="also write the figures as JSON")
    args = parser.parse_args()
    from distributed import Client, LocalCluster

    from gsfric import native

    native.is_compiled()
    ws = workspace(int(args.steps))
    rows = {}
    steps, sec = direct(ws, args.chunk)
    rows["direct"] = (steps, sec, 1)
    steps, sec = swept(ws, args.chunk, "serial")
    rows["serial"] = (steps, sec, 1)
    startup = {}
    for n in (1, 2):
        t0 = time.perf_counter()
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=logging.ERROR) as cluster, \
                Client(cluster) as client:
            client.wait_for_workers(n)
            client.run(warm)       # import gsfric and load the cached compiled library
            startup[n] = time.perf_counter() - t0
            steps, sec = swept(ws, args.chunk, client)
        rows[f"dask-{n}"] = (steps, sec, n)
    print(f"sweep of {steps} steps ({ws.samples} poses x {ws.states} states), "
          f"{args.chunk} steps per task")
    print(f"{'path':<8} {'workers':>7} {'seconds':>9} {'steps/s':>10} {'steps/s/core':>13}")
    for name, (steps, sec, n) in rows.items():
        print(f"{name:<8} {n:>7} {sec:>9.2f} {steps / sec:>10.0f} {steps / sec / n:>13.0f}")
    rate = {k: v[0] / v[1] for k, v in rows.items()}
    figures = {
        "steps": steps, "chunk": args.chunk, "rates": rate,
        "cluster_startup_s": startup,
        "serial_over_direct": rate["direct"] / rate["serial"],
        "dask1_over_direct_per_core": rate["direct"] / rate["dask-1"],
        "dask2_over_direct_per_core": rate["direct"] / (rate["dask-2"] / 2),
        "speedup_2_over_1": rate["dask-2"] / rate["dask-1"],
    }
    print(f"LocalCluster start-up: 1 worker {startup[1]:.2f} s, 2 workers {startup[2]:.2f} s")
    print(f"time per step relative to direct: serial {figures['serial_over_direct']:.2f}x, "
          f"dask 1 worker {figures['dask1_over_direct_per_core']:.2f}x, "
          f"dask 2 workers (per core) {figures['dask2_over_direct_per_core']:.2f}x")
    print(f"2 workers over 1: {figures['speedup_2_over_1']:.2f}x")
    if args.json:
        args.json.write_text(json.dumps(figures, indent=1))


if __name__ == "__main__":
    main()
