"""How a workspace sweep scales on Dask: one worker process against two (``benchmarks/all.py``).

Each cluster is the one ``scheduler="local"`` starts (``local_cluster``: single-threaded worker
processes), started for the measurement and warmed by a one-pose task (imports, the compiled
library), so that the time compared is the sweep's own: start-up is paid once per sweep and
is reported apart.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from gsfric._optional import optional
from gsfric.models import reference_platform
from gsfric.sweep.run import local_cluster, sweep
from gsfric.sweep.tasks import Task, run_task
from gsfric.sweep.workspace import Workspace

STATES = 8
"""Dynamic states per pose of the measured workspace."""


def scaling_workspace(steps: int) -> Workspace:
    """A Latin-hypercube workspace of ``steps // STATES`` poses, ``STATES`` states each."""
    return Workspace.from_dict({
        "sampling": "lhs", "samples": max(1, steps // STATES), "states": STATES, "seed": 0,
        "pose": {"x": [-0.05, 0.05], "y": [-0.05, 0.05], "z": [0.65, 0.75],
                 "roll": [-0.1, 0.1], "pitch": [-0.1, 0.1], "yaw": [-0.15, 0.15]},
        "bounds": {"velocity": 0.2, "omega": 0.5, "acceleration": 2.0, "alpha": 5.0}})


def warm() -> None:
    """A worker's one-time cost: a task of one pose."""
    run_task(Task(0, "workspace", [0], [reference_platform()], STATES,
                  poses=np.array([[0.0, 0.0, 0.7, 0.0, 0.0, 0.0]]),
                  workspace=scaling_workspace(STATES)))


def timed_sweep(workers: int, steps: int) -> dict:
    """``sweep`` of ``scaling_workspace(steps)`` on a fresh, warmed cluster of ``workers``
    processes: ``seconds`` (the sweep), ``startup_s`` (cluster start and warm-up), ``steps``."""
    Client = optional("distributed").Client
    start = time.perf_counter()
    with local_cluster(workers) as cluster, Client(cluster, set_as_default=False) as client:
        client.wait_for_workers(workers)
        client.run(warm)
        startup = time.perf_counter() - start
        with tempfile.TemporaryDirectory(prefix="gsfric-bench-") as tmp:
            start = time.perf_counter()
            result = sweep(Path(tmp) / "out", workspace=scaling_workspace(steps),
                           scheduler=client, plots=False, progress=False)
            seconds = time.perf_counter() - start
    return {"seconds": seconds, "startup_s": startup, "steps": int(result.info["steps"])}


def dask_scaling(steps: int, repeat: int = 1) -> dict:
    """The sweep on one worker and on two, ``repeat`` times interleaved (fastest kept):
    seconds of each, their ratio ``two_vs_one`` (one worker's time over two's), steps."""
    runs: dict[int, list[dict]] = {1: [], 2: []}
    for _ in range(max(1, repeat)):
        for workers in (1, 2):
            runs[workers].append(timed_sweep(workers, steps))
    one = min(r["seconds"] for r in runs[1])
    two = min(r["seconds"] for r in runs[2])
    return {"steps": runs[1][0]["steps"], "one_worker_s": one, "two_workers_s": two,
            "two_vs_one": one / two if two > 0 else float("nan"),
            "startup_s": max(r["startup_s"] for rs in runs.values() for r in rs)}
