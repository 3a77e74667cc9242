"""``worst_cases.html`` of a sweep: the 3-D view (``gsfric.view``) of the worst-case pose of
each joint, one frame each, the joint's leg and its values shown: the step of the largest
``|R_E|`` (spherical joint E_i) and of the largest ``|R_C|`` (universal joint C_i) of each leg
over all cases (``summary.csv``).

Each worst case's state (pose, velocities, accelerations) is rebuilt from where the sweep
found it: the step of its trajectory file, read again as the sweep read it, or the state of
its workspace pose (``Workspace.states_of``, the same for a given seed and pose index); it is
evaluated on its variant's platform. The page draws the nominal platform's geometry.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pandas as pd

from gsfric.compiled.state import state_layout
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import FLAG_NAMES
from gsfric.simulate.differentiate import iter_motions
from gsfric.sweep.plan import Plan
from gsfric.sweep.tasks import STREAM_CHUNK
from gsfric.sweep.workspace import POSE
from gsfric.trajectory import Motion
from gsfric.view import Curve, FrameCollector, Frames, Plot, page, write_page

JOINTS = {"R_E": "spherical joint E", "R_C": "universal joint C"}
"""The joints shown, by the envelope quantity of their load."""


def worst_cases(summary: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``summary`` (``summary.csv``) of the joint loads ``JOINTS`` that were found
    (a value), in the order E_1..E_6, C_1..C_6."""
    rows = summary[summary.quantity.isin(list(JOINTS)) & summary.value.notna()]
    order = rows.quantity.map({q: k for k, q in enumerate(JOINTS)})
    return rows.assign(_order=order).sort_values(["_order", "leg"]).drop(columns="_order")


def _states(plan: Plan, rows: pd.DataFrame) -> list[tuple[float, np.ndarray]]:
    """(t, state (24,)) of each row's step: a motion's read again, a workspace pose's
    rebuilt."""
    paths = {task.motion: task.path for task in plan.tasks if task.path is not None}
    workspace = next((task.workspace for task in plan.tasks if task.workspace is not None),
                     None)
    found: dict[tuple[str, int], tuple[float, np.ndarray]] = {}
    for motion in rows.motion.unique():
        steps = set(rows.step[rows.motion == motion].astype(int))
        if motion in paths:
            for piece in iter_motions(paths[motion], chunk=STREAM_CHUNK):
                x, t = state_array(piece.motion), np.asarray(piece.motion.t, float)
                for step in steps & set(range(piece.start, piece.start + len(t))):
                    found[motion, step] = (float(t[step - piece.start]),
                                           x[step - piece.start].copy())
        else:
            for row in rows[rows.motion == motion].itertuples():
                pose, state = divmod(int(row.step), workspace.states)
                x = workspace.states_of(np.array([[getattr(row, c) for c in POSE]]), pose)
                found[motion, int(row.step)] = (0.0, x[state].copy())
    return [found[row.motion, int(row.step)] for row in rows.itertuples()]


def _caption(row) -> str:
    where = (f"workspace state {int(row.step)}" if row.motion == "workspace" else
             f"{row.motion}, step {int(row.step)}, t = {row.t:.4g} s")
    return (f"largest |{row.quantity}| of {JOINTS[row.quantity]}{int(row.leg)}: "
            f"{row.value:.4g} {row.unit} ({where}, variant {int(row.variant)})")


def _frames(plan: Plan, rows: pd.DataFrame) -> Frames:
    """One frame per row, evaluated on its variant's platform; ``t`` the frame's index."""
    platforms = {v: p for task in plan.tasks for v, p in zip(task.variants, task.platforms)}
    layout = state_layout()
    parts = []
    for (t, x), row in zip(_states(plan, rows), rows.itertuples()):
        motion = Motion(np.array([t]), *layout.split(x[None]))
        result = Evaluator(platforms[int(row.variant)]).evaluate_quiet(motion)
        parts.append(FrameCollector().add_result(result, int(row.step)).finish())
    frames = Frames.concatenate(parts)
    return dataclasses.replace(frames, t=np.arange(len(frames), dtype=float))


def write_worst_cases(plan: Plan, summary: pd.DataFrame, path: str | os.PathLike[str]
                      ) -> Path | None:
    """Write the view of the worst-case pose of each joint (see the module) to ``path``;
    None (nothing written) when no joint load was found (every step flagged)."""
    rows = worst_cases(summary)
    if rows.empty:
        return None
    frames = _frames(plan, rows)
    loads = Plot("joint loads |R_E| (solid), |R_C| (dashed)", "N",
                 (Curve("|R_E|", np.linalg.norm(frames.R_E, axis=2)),
                  Curve("|R_C|", np.linalg.norm(frames.R_C, axis=2), "dashed")))
    plots = (Plot("actuator force F (+ push, \u2212 pull)", "N", (Curve("F", "F"),)), loads)
    text = page(frames, plan.platform, title="sweep: the worst-case pose of each joint",
                flag_names=FLAG_NAMES, plots=plots,
                captions=[_caption(r) for r in rows.itertuples()],
                focus=[int(leg) - 1 for leg in rows.leg])
    return write_page(path, text)
