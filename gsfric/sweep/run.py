"""Running a sweep: its tasks in this process or on Dask, stored as they arrive so that an
interrupted sweep resumes, merged and written to the output folder (``sweep``).

Tasks run in this process (``scheduler="serial"``), on a Dask ``LocalCluster`` of one
single-threaded worker process per core (``"local"``), or on a running Dask cluster
(``"tcp://host:port"`` or the ``DASK_SCHEDULER_ADDRESS`` variable). The result does not
depend on where a task runs: a task's envelope is a deterministic function of its inputs, and
envelopes are merged in task order.

Output folder ``OUT`` (built in ``OUT.partial`` and renamed when complete): ``envelopes.parquet``,
``summary.csv``, ``variants.csv``, ``limits.csv`` (when the platform has ``[limits]``),
``sweep.json``, ``envelope.png``, ``locations.png``, ``worst_cases.html`` (the 3-D view of
each joint's worst-case pose, ``gsfric.sweep.view``). Finished tasks are kept in
``OUT.partial/chunks/`` as they arrive; a sweep interrupted and started again with the same
inputs and output folder computes only the missing tasks.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import logging
import os
import shutil
import signal
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import pandas as pd
from tqdm import tqdm

from gsfric._checks import as_path
from gsfric._optional import optional
from gsfric.errors import GsfricWarning, InputError
from gsfric.io.files import atomic_write, check_outputs
from gsfric.platform.description import Platform
from gsfric.sweep.plan import CHUNK_STEPS, Plan, plan
from gsfric.sweep.plot import plot
from gsfric.sweep.result import SweepResult, check_limits, fold, load, merge, summarize
from gsfric.sweep.tasks import Task, run_task
from gsfric.sweep.view import write_worst_cases
from gsfric.sweep.workspace import Workspace

SERIAL_BELOW = 2_000_000
"""``scheduler="auto"`` runs sweeps of fewer steps in this process: below two tasks a cluster
has nothing to share out, and starting one (0.5-5 s with the workers' imports and first task)
costs about what a second core saves on a million steps (docs/howto/sizing.md)."""

MERGE_EVERY = 64
"""Task envelopes held before they are folded into the running merge (bounds client memory)."""

LOCAL_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False,
                        "distributed.admin.tick.interval": "1s",
                        "distributed.worker.memory.monitor-interval": "1s",
                        "distributed.admin.system-monitor.interval": "2s"}
"""Dask settings of the local cluster: no statistical profiler in the workers (it samples the
running task's stack 100 times a second: about 5 % of a task's CPU time); the event loops'
tick (a check that a loop is not blocked) once a second instead of every 20 ms, the memory
monitors (the nannies', which run in this process, and the workers') once a second instead of
10 times, the system monitor every 2 s instead of 0.5 s. Measured on an idle cluster of one
worker, Dask's defaults cost the worker 2.0 % of a core and this process (the scheduler and the
nannies) 3.2 %; these settings, 0.3 % and 0.7 % (docs/howto/sizing.md)."""


def local_cluster(workers: int):
    """The ``LocalCluster`` of ``scheduler="local"``: ``workers`` processes with one thread
    each, one per core (nothing shared between cores), with ``LOCAL_CLUSTER_CONFIG``."""
    dask = optional("dask")
    distributed = optional("distributed")
    with dask.config.set(LOCAL_CLUSTER_CONFIG), _children_ignore_sigint():
        return distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                        processes=True, dashboard_address=":0",
                                        silence_logs=logging.ERROR)


@contextlib.contextmanager
def _children_ignore_sigint():
    """SIGINT ignored while the cluster's processes start, which inherit it (Python leaves an
    ignored SIGINT ignored): Ctrl-C reaches the whole foreground process group, and only
    this process should handle it (close the cluster, print one line), not every worker with
    a traceback. A Ctrl-C during those seconds of start-up is lost; press it again."""
    try:
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except (ValueError, OSError):          # not the main thread: nothing to change
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _client(scheduler, workers: int | None = None):
    """A distributed Client and the LocalCluster we started for it (None otherwise)."""
    if not isinstance(scheduler, str):
        return scheduler, None
    Client = optional("distributed").Client
    if scheduler == "local":
        cluster = local_cluster(workers or os.cpu_count() or 1)
        return Client(cluster), cluster
    return Client(scheduler), None


def _resolve_scheduler(scheduler, steps: int):
    """The scheduler to use for ``steps`` steps to compute ("serial", "local", an address or
    a Client)."""
    if scheduler is None or scheduler == "auto":
        address = os.environ.get("DASK_SCHEDULER_ADDRESS")
        if address:
            return address
        return "serial" if steps < SERIAL_BELOW else "local"
    if isinstance(scheduler, str) and scheduler not in ("serial", "local") and \
            "://" not in scheduler:
        raise InputError(f"scheduler: expected auto, serial, local or an address such as "
                         f"tcp://host:8786, got {scheduler!r}")
    return scheduler


def _finished(partial: Path, fingerprint: str) -> list[tuple[int, Path]]:
    """(task index, chunk file) of the tasks an unfinished sweep of these inputs stored."""
    plan_file = partial / "plan.json"
    if not plan_file.exists():
        return []
    try:
        stored = json.loads(plan_file.read_text())["fingerprint"]
    except (ValueError, KeyError):
        stored = None
    if stored != fingerprint:
        raise InputError(f"{partial}: holds an unfinished sweep of other inputs; remove it "
                         "or choose another output folder")
    return [(int(f.stem), f) for f in sorted((partial / "chunks").glob("*.parquet"))]


class _Progress:
    """A running sweep in its partial folder: the finished tasks, the running fold of their
    envelopes (then the task envelopes not yet folded in), the progress bar."""

    def __init__(self, partial: Path, p: Plan,
                 on_chunk: Callable[[int, int], None] | None) -> None:
        self.partial, self.plan, self.on_chunk = partial, p, on_chunk
        self.merged: list[pd.DataFrame] = []
        self.done: set[int] = set()
        self.bar = None

    def absorb(self, frame: pd.DataFrame) -> None:
        self.merged.append(frame)
        if len(self.merged) > MERGE_EVERY:
            self.merged[:] = [fold(self.merged)]

    def resume(self) -> list[Task]:
        """Take in the tasks an unfinished sweep of the same inputs stored; the tasks left."""
        (self.partial / "chunks").mkdir(parents=True, exist_ok=True)
        for k, f in _finished(self.partial, self.plan.fingerprint):
            if k < len(self.plan.tasks):
                self.absorb(pd.read_parquet(f))
                self.done.add(k)
        (self.partial / "plan.json").write_text(json.dumps(
            {"fingerprint": self.plan.fingerprint, "tasks": len(self.plan.tasks)}))
        return [t for t in self.plan.tasks if t.id not in self.done]

    def finish(self, task: Task, frame: pd.DataFrame) -> None:
        """Store a finished task's envelope and take it in."""
        with atomic_write(self.partial / "chunks" / f"{task.id:07d}.parquet", "wb") as handle:
            frame.to_parquet(handle, index=False)
        self.absorb(frame)
        self.done.add(task.id)
        self.bar.update(task.steps)
        if self.on_chunk is not None:
            self.on_chunk(len(self.done), len(self.plan.tasks))


def _run_on_dask(todo: list[Task], scheduler, workers: int | None, progress: _Progress) -> None:
    """Run the tasks on a Dask cluster (started for them when ``scheduler`` is "local")."""
    as_completed = optional("distributed").as_completed
    client, cluster = _client(scheduler, workers)
    try:
        # a bounded window of tasks in flight: the tasks' inputs (pose blocks, platforms) are
        # pickled as they are submitted, not all at once
        window = max(8, 4 * max(1, len(client.scheduler_info().get("workers", {}))))
        pending = iter(todo)
        by_key = {}

        def submit(task):
            fut = client.submit(run_task, task, key=f"gsfric-sweep-{progress.plan.fingerprint}-"
                                f"{task.id}", pure=False)
            by_key[fut.key] = task
            return fut

        queue = as_completed([submit(t) for t in itertools.islice(pending, window)],
                             loop=client.loop, with_results=True)
        for fut, frame in queue:
            progress.finish(by_key.pop(fut.key), frame)
            nxt = next(pending, None)
            if nxt is not None:
                queue.add(submit(nxt))
    finally:
        if cluster is not None:
            client.close()
            cluster.close()


def _run_tasks(todo: list[Task], scheduler, workers: int | None, progress: _Progress,
               show: bool) -> float:
    """Run the tasks left, with a progress bar; the seconds they took."""
    p = progress.plan
    steps_todo = sum(t.steps for t in todo)
    progress.bar = tqdm(total=p.steps, initial=p.steps - steps_todo, unit="step",
                        unit_scale=True, desc="sweep", disable=not show, file=sys.stderr)
    started = time.perf_counter()
    try:
        if scheduler == "serial":
            for task in todo:
                progress.finish(task, run_task(task))
        elif todo:
            _run_on_dask(todo, scheduler, workers, progress)
    finally:
        progress.bar.close()
    return time.perf_counter() - started


def _info(p: Plan, envelopes: pd.DataFrame, exceeded: pd.DataFrame, computed: int,
          scheduler, seconds: float) -> dict:
    """The content of ``sweep.json`` (``SweepResult.info``)."""
    limits = p.platform.limits
    return {"fingerprint": p.fingerprint, "tasks": len(p.tasks), "steps": p.steps,
            "cases": int(envelopes.groupby(["motion", "variant"]).ngroups),
            "flagged": int(envelopes[(envelopes.quantity == "R_E") &
                                     (envelopes.leg == 1)].flagged.sum()),
            "computed_tasks": computed,
            "scheduler": str(scheduler) if isinstance(scheduler, str) else "client",
            "seconds": round(seconds, 3), "limits": {k: v for k, v in limits.items()},
            "exceeding_cases": int(exceeded.groupby(["motion", "variant"]).ngroups)
            if len(exceeded) else 0,
            "limits_check": limits_check(limits, exceeded),
            "variants_drawn": variants_drawn(p.inputs),
            "inputs": p.inputs}


def limits_check(limits, exceeded: pd.DataFrame) -> str:
    """What the check of the ``[limits]`` found, in a sentence (sweep.json's ``limits_check``)."""
    if not limits:
        return "no limits given: nothing checked"
    n = int(exceeded.groupby(["motion", "variant"]).ngroups) if len(exceeded) else 0
    return (f"{n} case(s) exceed the limits ({', '.join(limits)})" if n
            else f"every case within the limits ({', '.join(limits)})")


def variants_drawn(inputs: dict) -> str:
    """How the variants were chosen (sweep.json's ``variants_drawn``)."""
    n = inputs["variants"]
    if not n:
        return "none: the nominal platform only"
    names = ", ".join([*inputs["vary"], *inputs["tolerances"]])
    if "grid" in inputs:
        return f"{n} on an even grid of {inputs['grid']} values per parameter over {names}"
    return (f"{n} drawn at random (seed {inputs['seed']}: Latin hypercube over the ranges, "
            f"normal errors for the tolerances) over {names}")


def _write(out: Path, progress: _Progress, computed: int, scheduler, seconds: float,
           plots: bool) -> SweepResult:
    """Merge the task envelopes, write the output files in the partial folder and rename it
    to ``out``."""
    p, partial = progress.plan, progress.partial
    envelopes = merge(progress.merged)
    summary = summarize(envelopes)
    variants_table = pd.DataFrame(p.variants)
    exceeded = check_limits(envelopes, p.platform.limits)
    envelopes.to_parquet(partial / "envelopes.parquet", index=False)
    summary.to_csv(partial / "summary.csv", index=False)
    variants_table.to_csv(partial / "variants.csv", index=False)
    if p.platform.limits:
        exceeded.to_csv(partial / "limits.csv", index=False)
    info = _info(p, envelopes, exceeded, computed, scheduler, seconds)
    if plots:
        plot(envelopes, summary, partial, p.platform.limits, p.inputs.get("workspace"),
             variants_table)
        write_worst_cases(p, summary, partial / "worst_cases.html")
    shutil.rmtree(partial / "chunks")
    (partial / "plan.json").unlink()
    (partial / "sweep.json").write_text(json.dumps(info, indent=1, default=str))
    os.replace(partial, out)
    return SweepResult(out, envelopes, summary, variants_table, exceeded, info)


def _partial_folder(out: Path, p: Plan, workspace, platform) -> Path:
    """``OUT.partial``, where the sweep is built, after checking that neither it nor ``out`` is
    one of the sweep's input files (trajectories, the workspace's or the platform's file)."""
    partial = out.with_name(out.name + ".partial")
    check_outputs([out, partial], [*(("trajectory", f) for f in p.inputs["files"]),
                                   ("workspace", workspace), ("platform", platform)])
    return partial


def _existing(out: Path, fingerprint: str) -> bool:
    """Whether ``out`` holds this very sweep; ``InputError`` when it holds something else or
    its parent folder is missing."""
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a directory; choose another output folder")
    if out.exists():
        meta = out / "sweep.json"
        if meta.exists() and json.loads(meta.read_text()).get("fingerprint") == fingerprint:
            return True
        raise InputError(f"{out}: exists; remove it or choose another output folder")
    if not out.parent.is_dir():
        raise InputError(f"{out}: directory {str(out.parent)!r} does not exist")
    return False


def sweep(out: str | os.PathLike, trajectories=None,
          workspace: Workspace | str | os.PathLike | None = None,
          platform: Platform | str | os.PathLike | None = None, vary=None, tolerances=None,
          variants: int = 16, seed: int = 0, scheduler=None, workers: int | None = None,
          chunk_steps: int = CHUNK_STEPS,
          progress: bool | None = None, plots: bool = True,
          on_chunk: Callable[[int, int], None] | None = None,
          grid: int | None = None) -> SweepResult:
    """Load envelopes per joint over motions, a workspace and platform variants.

    Parameters
    ----------
    out : path
        Output folder (must not exist unless it holds this very sweep, which is then read
        back). Built in ``out + ".partial"``; an unfinished sweep there resumes.
    trajectories : str, path or list of them
        Glob pattern(s) of trajectory files (CSV or Parquet); each file is one motion.
    workspace : Workspace or path of its TOML
        Poses and velocity/acceleration bounds (docs/howto/sizing.md).
    platform : Platform or path of its TOML
        The nominal platform (default: ``gsfric.models.platform_from(None)``, the reference
        platform); its ``[limits]`` are checked.
    vary : dict name -> (min, max)
        Parameter ranges of the variants (``SCALAR_PARAMETERS``).
    tolerances : dict name -> standard deviation
        Monte-Carlo tolerances (``SCALAR_PARAMETERS`` and ``JOINT_TOLERANCES``).
    variants : int
        Variants drawn at random (Latin hypercube over ``vary``, normal ``tolerances``)
        besides the nominal one when ``vary`` or ``tolerances`` is given.
    seed : int
        Seed of the variants (the workspace has its own).
    scheduler : {"auto", "serial", "local"}, address "tcp://host:port", or a Client
        "auto" (None): ``DASK_SCHEDULER_ADDRESS`` if set, else "serial" below
        ``SERIAL_BELOW`` steps and "local" (a LocalCluster, one process per core) above.
    workers : int, optional
        Worker processes of the "local" cluster (default: one per core).
    chunk_steps : int
        Evaluated steps per task (a trajectory file is never split).
    progress : bool, optional
        Progress bar on stderr (default: when stderr is a terminal).
    plots : bool
        Write envelope.png, locations.png and worst_cases.html.
    on_chunk : callable (done, total), optional
        Called after each finished task is stored.
    grid : int, optional
        Instead of random draws: this many evenly spaced values of each ``vary`` range, ends
        included, every combination (``grid ** len(vary)`` variants; ``variants`` is then
        not used; not with ``tolerances``).

    Returns
    -------
    SweepResult

    Raises
    ------
    InputTypeError
        ``out`` not a path, ``vary`` or ``tolerances`` not a dict.
    InputError
        Bad files or settings, in one line: an unknown parameter, a range outside
        ``gsfric.sweep.variants.VALID_RANGES``, an output that is an input.
    OutputError
        An output could not be written (a full disk): the ``.partial`` folder is kept and the
        same call resumes it.
    """
    out = as_path(out, "out")
    p = plan(trajectories, workspace, platform, vary, tolerances, variants, seed, chunk_steps,
             grid)
    partial = _partial_folder(out, p, workspace, platform)
    if _existing(out, p.fingerprint):
        return load(out)
    running = _Progress(partial, p, on_chunk)
    todo = running.resume()
    try:
        return _complete(out, running, todo, scheduler, workers, progress, plots)
    except BaseException as exc:
        _keep_or_remove(running, exc)
        raise


def _complete(out: Path, running: _Progress, todo: list[Task], scheduler,
              workers: int | None, progress: bool | None, plots: bool) -> SweepResult:
    """Run the tasks ``todo`` that ``running`` has not done yet (``sweep``'s ``scheduler``,
    ``workers``, ``progress``), and write the sweep to ``out``."""
    chosen = _resolve_scheduler(scheduler, sum(t.steps for t in todo)) if todo else "serial"
    if progress is None:
        progress = sys.stderr.isatty()
    seconds = _run_tasks(todo, chosen, workers, running, progress)
    return _write(out, running, len(todo), chosen, seconds, plots)


def _keep_or_remove(running: _Progress, exc: BaseException) -> None:
    """After a failed or interrupted sweep: keep its partial folder when it holds finished
    tasks that the same command can resume (saying so in a ``GsfricWarning``), else remove it
    (nothing done, or bad input: fixing a file changes the fingerprint, so nothing could be
    resumed)."""
    partial, done, total = running.partial, len(running.done), len(running.plan.tasks)
    if done and not isinstance(exc, InputError):
        warnings.warn(f"{partial}: the unfinished sweep is kept ({done} of {total} tasks "
                      "done); run the same command again to resume it, or remove the folder",
                      GsfricWarning, stacklevel=3)
        return
    shutil.rmtree(partial, ignore_errors=True)
