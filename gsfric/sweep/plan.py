"""A sweep's plan: every input checked, and the work cut into tasks of about ``chunk_steps``
evaluated steps (a trajectory file, or a block of workspace poses, on a range of variants),
with the fingerprint of the inputs that a resumed sweep must match."""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gsfric import __version__
from gsfric._checks import short
from gsfric.errors import InputError
from gsfric.io.files import trajectory_files
from gsfric.io.tables import count_rows
from gsfric.models import platform_from
from gsfric.platform.description import Platform
from gsfric.sweep.tasks import BLOCK_STEPS, Task
from gsfric.sweep.variants import make_variants, parse_vary
from gsfric.sweep.workspace import Workspace, check_reachable

CHUNK_STEPS = 1_000_000
"""Default evaluated steps per task: one to a few seconds of one core (docs/howto/sizing.md)."""

_POSE_BYTES = 48
_VARIANT_BYTES = 17_000
"""What a pose and a variant weigh in a task's traffic: a pose in (6 floats), a variant's
platform in (2 kB) and its envelope out (15 kB), pickled (measured)."""


@dataclass
class Plan:
    """A sweep cut into tasks.

    Attributes
    ----------
    tasks : list of Task
        In merge order (``Task.id`` is the index).
    fingerprint : str
        16 hex digits of the inputs (files' paths, sizes and times, and ``inputs``).
    inputs : dict
        The inputs as written to ``sweep.json``.
    variants : list of dict
        Each variant's parameter values (``variants.csv``).
    platform : Platform
        The nominal platform, read once.
    """

    tasks: list[Task]
    fingerprint: str
    inputs: dict
    variants: list[dict]
    platform: Platform

    @property
    def steps(self) -> int:
        """Evaluated steps of all tasks."""
        return sum(t.steps for t in self.tasks)


def _file_rows(path: Path) -> int:
    """Data rows of a trajectory file (its steps)."""
    rows = count_rows(path)
    if rows is not None:
        return rows
    with open(path, "rb") as handle:
        return max(0, sum(1 for _ in handle) - 1)


def _pose_block(n_poses: int, states: int, variants: int, chunk_steps: int) -> int:
    """Poses per workspace task, the task covering ``chunk_steps // (block * states)``
    variants of them.

    As few as let one task hold every variant (``chunk_steps / (states * variants)``), but
    enough that the poses a task carries and its variants weigh alike (``b * 48 B = p *
    17 kB`` with ``b * p * states = chunk_steps``: 6700 poses and 19 variants for tasks of 1e6
    steps at 8 states, 0.6 MB of traffic), and at least one evaluated block per variant: a
    task does not carry all the poses when a sweep has many variants.
    """
    whole = -(-chunk_steps // states)                  # one variant per task
    balanced = int(math.sqrt(_VARIANT_BYTES * chunk_steps / (_POSE_BYTES * states)))
    block = max(BLOCK_STEPS // states, balanced, -(-chunk_steps // (states * variants)))
    return max(1, min(n_poses, whole, block))


def _file_tasks(files: list[Path], platforms: list[Platform], chunk_steps: int,
                tasks: list[Task], hasher) -> None:
    """Append the tasks of the trajectory files (a file is never split: its variants are
    grouped ``chunk_steps // rows`` to a task) and hash each file's path, size and time."""
    nv = len(platforms)
    for f in files:
        st = f.stat()
        hasher.update(f"{f.resolve()}|{st.st_size}|{st.st_mtime_ns}".encode())
        n = _file_rows(f)
        per = max(1, chunk_steps // max(n, 1))
        for lo in range(0, nv, per):
            vs = list(range(lo, min(nv, lo + per)))
            tasks.append(Task(len(tasks), f.name, vs, [platforms[v] for v in vs],
                              n * len(vs), path=str(f)))


def _workspace_tasks(workspace: Workspace, poses: np.ndarray, platforms: list[Platform],
                     chunk_steps: int, tasks: list[Task]) -> None:
    """Append the tasks of the workspace: blocks of poses of equal size, each on groups of
    variants of equal size (``_pose_block``)."""
    n_poses, nv = len(poses), len(platforms)
    block = _pose_block(n_poses, workspace.states, nv, chunk_steps)
    per = max(1, chunk_steps // (block * workspace.states))
    block = -(-n_poses // -(-n_poses // block))   # blocks of equal size, and
    per = -(-nv // -(-nv // per))                 # groups of variants of equal size
    for p0 in range(0, n_poses, block):
        part = poses[p0:p0 + block]
        for lo in range(0, nv, per):
            vs = list(range(lo, min(nv, lo + per)))
            tasks.append(Task(len(tasks), "workspace", vs, [platforms[v] for v in vs],
                              len(part) * workspace.states * len(vs), poses=part,
                              first_pose=p0, workspace=workspace))


def _checked_inputs(trajectories, workspace, chunk_steps
                    ) -> tuple[list[Path], Workspace | None, str]:
    """(files, workspace, its source name) after the checks of ``plan``."""
    if isinstance(chunk_steps, bool) or not isinstance(chunk_steps, (int, np.integer)) \
            or chunk_steps < 1:
        raise InputError(f"chunk_steps: expected an integer >= 1, got {short(chunk_steps)}")
    files = trajectory_files(trajectories)
    source = "workspace"
    if workspace is not None and not isinstance(workspace, Workspace):
        source = str(workspace)
        workspace = Workspace.from_toml(workspace)
    if not files and workspace is None:
        raise InputError("sweep: give trajectories (a glob) and/or a workspace")
    return files, workspace, source


def plan(trajectories=None, workspace: Workspace | str | os.PathLike | None = None,
         platform: Platform | str | os.PathLike | None = None, vary=None, tolerances=None,
         variants: int = 16, seed: int = 0, chunk_steps: int = CHUNK_STEPS,
         grid: int | None = None) -> Plan:
    """Cut a sweep into tasks (see ``gsfric.sweep.sweep`` for the parameters); checks every
    input."""
    platform = platform_from(platform)
    files, workspace, source = _checked_inputs(trajectories, workspace, chunk_steps)
    platforms, table = make_variants(platform, vary, tolerances, variants, seed, grid)
    tasks: list[Task] = []
    hasher = hashlib.sha256()
    _file_tasks(files, platforms, chunk_steps, tasks, hasher)
    if workspace is not None:
        poses = workspace.poses()
        check_reachable(platform, poses, source)
        _workspace_tasks(workspace, poses, platforms, chunk_steps, tasks)
    inputs = {"gsfric": __version__, "files": [str(f) for f in files],
              "workspace": workspace.to_dict() if workspace is not None else None,
              "platform": platform.to_dict(), "vary": {k: list(v) for k, v in
                                                      parse_vary(vary, tolerances)[0].items()},
              "tolerances": dict(tolerances or {}), "variants": len(platforms) - 1,
              "seed": seed, "chunk_steps": int(chunk_steps),
              **({"grid": int(grid)} if grid is not None else {})}
    hasher.update(json.dumps(inputs, sort_keys=True, default=str).encode())
    return Plan(tasks, hasher.hexdigest()[:16], inputs, table, platform)
