"""Sweep tasks and their evaluation on a worker: a trajectory file or a block of workspace
poses, on some platform variants, reduced to envelope rows.

A task runs in one thread, block after block of ``BLOCK_STEPS`` steps: each block is
evaluated for every variant of the task into the same reused buffers and folded into the
variant's envelope at once, so memory follows ``BLOCK_STEPS``, not the task's size.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pandas as pd

from gsfric.evaluation.evaluator import state_array
from gsfric.evaluation.uncertainty import steps_at_rest
from gsfric.platform.description import Platform
from gsfric.simulate.differentiate import iter_motions
from gsfric.sweep.blocks import Block, Evaluation
from gsfric.sweep.envelope import ENVELOPE_COLUMNS, Envelope
from gsfric.sweep.workspace import Workspace
from gsfric.trajectory import Motion

BLOCK_STEPS = 2048
"""Steps evaluated and reduced at a time inside a task. A block's values (78 per step, 1.3 MB,
in the core's cache between the evaluation and the reduction) are reused from block to block
and from variant to variant, so a worker's memory follows this size and the task's poses, not
the sweep's size."""

STREAM_CHUNK = 50_000
"""Steps of a trajectory file read and evaluated at a time inside a task (bounds memory)."""


@dataclass
class Task:
    """One unit of work: a trajectory file or a block of workspace poses, on some variants.

    Attributes
    ----------
    id : int
        Index of the task in its plan (the order envelopes are merged in).
    motion : str
        Case name: the file's name, or "workspace".
    variants : list of int
        Indices of the platform variants evaluated.
    platforms : list of Platform
        Those variants' platforms.
    steps : int
        Evaluated steps (all variants).
    path : str, optional
        The trajectory file (a motion task).
    poses : ndarray (n, 6), optional
        The block of workspace poses (``POSE`` columns) of a workspace task.
    first_pose : int
        Index of the block's first pose in the workspace.
    workspace : Workspace, optional
        The workspace of a workspace task.
    """

    id: int
    motion: str
    variants: list[int]
    platforms: list[Platform]
    steps: int
    path: str | None = None
    poses: np.ndarray | None = None
    first_pose: int = 0
    workspace: Workspace | None = None


def _pieces(task: Task, block: Block
            ) -> Iterator[tuple[int, np.ndarray, np.ndarray, Motion | None]]:
    """(first step, states (n, 24), times (n,), the motion or None) of a task, piece by piece:
    a trajectory file as it is streamed, a block of workspace poses ``BLOCK_STEPS`` states at
    a time (in the block's buffers: valid until the next piece; no motion)."""
    if task.path is not None:
        for piece in iter_motions(task.path, chunk=STREAM_CHUNK):
            yield (piece.start, state_array(piece.motion), np.asarray(piece.motion.t, float),
                   piece.motion)
        return
    ws = task.workspace
    per = max(1, block.size // ws.states)
    for p0 in range(0, len(task.poses), per):
        first = task.first_pose + p0
        x = ws.states_of(task.poses[p0:p0 + per], first, out=block.states)
        yield first * ws.states, x, block.times[:len(x)], None


def run_task(task: Task) -> pd.DataFrame:
    """Evaluate one task and reduce it to envelope rows (a DataFrame of ``task`` then
    ``ENVELOPE_COLUMNS``, one row per variant, quantity and leg).

    Runs on a worker, in one thread, block after block of ``BLOCK_STEPS`` steps: each block is
    evaluated for every variant of the task into the same reused buffers and folded into the
    variant's envelope at once, so memory follows ``BLOCK_STEPS``, not the task's size.
    """
    states = task.workspace.states if task.workspace is not None else 1
    block = Block(max(BLOCK_STEPS, states))
    evaluations = [Evaluation(p) for p in task.platforms]
    envelopes = [Envelope() for _ in task.platforms]
    timed = task.path is not None
    for start, x, t, motion in _pieces(task, block):
        for platform, evaluation, envelope in zip(task.platforms, evaluations, envelopes):
            if motion is not None:
                envelope.at_rest += steps_at_rest(platform, motion)
            for s, e in evaluation.blocks(block, x, t):
                envelope.add(block.values, block.flag, x[s:e], t[s:e], start + s, timed,
                             block.pairs)
    rows = []
    for v, envelope in zip(task.variants, envelopes):
        rows += envelope.rows(task.motion, v, timed)
    frame = pd.DataFrame(rows, columns=list(ENVELOPE_COLUMNS))
    frame.insert(0, "task", task.id)
    return frame
