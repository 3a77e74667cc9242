"""The layout of the generated functions' state input x: where each part of a motion sits.

The layout is the manifest's (``layout("eval", "x")``: position, rotation row-major, velocity,
omega, acceleration, alpha, 24 values per step); ``state_layout()`` reads it once and every
Python indexing of a state takes its slots from there. The compiled driver lays the states out
itself, block by block, the same way (``layout_states`` in ``batch.c``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from gsfric.compiled.manifest import layout
from gsfric.errors import GsfricError, InputError, InputTypeError

MOTION_NAMES = ("position", "rotation", "velocity", "omega", "acceleration", "alpha")
"""The parts of a motion, in the order of the arrays of ``state_of``."""
MOTION_SHAPES = ((3,), (3, 3), (3,), (3,), (3,), (3,))
"""The shape of each part at one step."""


@dataclass(frozen=True)
class StateLayout:
    """Slots of the state vector x (one step), from the manifest.

    Attributes
    ----------
    size : int
        Values per step (24).
    position, rotation, velocity, omega, acceleration, alpha : slice
        Where each part sits: position (m), rotation T row-major (platform to base), velocity
        (m/s), omega (rad/s), acceleration (m/s^2), alpha (rad/s^2), base frame.
    """

    size: int
    position: slice
    rotation: slice
    velocity: slice
    omega: slice
    acceleration: slice
    alpha: slice

    def slots(self) -> tuple[slice, ...]:
        """The six slots in the order of ``MOTION_NAMES``."""
        return tuple(getattr(self, name) for name in MOTION_NAMES)

    def split(self, x: np.ndarray) -> tuple[np.ndarray, ...]:
        """p, T, v, omega, a, alpha of states x (..., size): views, T shaped (..., 3, 3)."""
        lead = x.shape[:-1]
        return tuple(x[..., slot].reshape(lead + shape)
                     for slot, shape in zip(self.slots(), MOTION_SHAPES))


@functools.lru_cache(maxsize=None)
def state_layout() -> StateLayout:
    """The state input's layout (read from the manifest once)."""
    blocks = {b["name"]: b for b in layout("eval", "x")}
    slots = {}
    for name, shape in zip(MOTION_NAMES, MOTION_SHAPES):
        block = blocks.get(name)
        if block is None or tuple(block["shape"]) != shape:
            raise GsfricError(f"generated/manifest.json: the state input x has no block "
                              f"{name} of shape {shape}; run `gsfric derive`")
        slots[name] = slice(block["offset"], block["offset"] + int(np.prod(shape)))
    size = max(s.stop for s in slots.values())
    if size != sum(s.stop - s.start for s in slots.values()):
        raise GsfricError("generated/manifest.json: the state input x has gaps or overlaps; "
                          "run `gsfric derive`")
    return StateLayout(size=size, **slots)


def motion_arrays(name: str, motion) -> list[np.ndarray]:
    """The six arrays of a motion, C-contiguous float64 with one N, else ``InputError``
    naming the caller ``name``."""
    try:
        parts = [np.ascontiguousarray(a, dtype=np.float64) for a in motion]
    except (TypeError, ValueError):
        raise InputTypeError(f"{name}: a motion is 6 arrays of numbers") from None
    if len(parts) != 6:
        raise InputError(f"{name}: a motion is 6 arrays, got {len(parts)}")
    n = parts[0].shape[0] if parts[0].ndim else 0
    for part, shape, label in zip(parts, MOTION_SHAPES, MOTION_NAMES):
        if part.shape != (n,) + shape:
            raise InputError(f"{name}: {label} has shape {part.shape}, expected "
                              f"{(n,) + shape}")
    return parts


def first_nonfinite(x: np.ndarray) -> str | None:
    """Where the states x (N, size) first hold a NaN or an infinity, as ``"row 3
    (omega)"`` (0-based row, the motion part of its column), or None when all are finite."""
    bad = ~np.isfinite(np.asarray(x, dtype=float).reshape(len(x), -1))
    rows = np.flatnonzero(bad.any(axis=1))
    if not len(rows):
        return None
    column = int(np.flatnonzero(bad[rows[0]])[0])
    part = next((n for n, s in zip(MOTION_NAMES, state_layout().slots())
                 if s.start <= column < s.stop), f"column {column}")
    return f"row {int(rows[0])} ({part})"


def state_of(motion) -> np.ndarray:
    """The (N, 24) state array of a motion's six arrays (p, T row-major, v, omega, a,
    alpha), laid out by ``state_layout()``: the one layout in Python
    (``evaluation.state_array``)."""
    parts = motion_arrays("motion", motion)
    n = parts[0].shape[0]
    states = state_layout()
    out = np.empty((n, states.size))
    for part, slot in zip(parts, states.slots()):
        out[:, slot] = part.reshape(n, -1)
    return out
