"""The sizing workspace: pose ranges with velocity and acceleration bounds, sampled into poses
and dynamic states, and the check that every pose is reachable.

A workspace is read from TOML (layout in docs/howto/sizing.md); its poses are a grid or a Latin
hypercube, and each pose has ``states`` dynamic states laid out as the generated functions'
state input x (``gsfric.compiled.state.state_layout``, from the manifest).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import qmc

from gsfric._checks import as_float, short, suggest
from gsfric._threads import in_parallel
from gsfric.compiled.state import state_layout
from gsfric.errors import InputError
from gsfric.io.files import read_toml
from gsfric.platform.description import Platform
from gsfric.signal.rotations import rotation_from_rpy

POSE = ("x", "y", "z", "roll", "pitch", "yaw")
"""Pose columns of a location: platform origin (m) and ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rad)."""

_WORKSPACE_KEYS = ("sampling", "samples", "points", "states", "seed", "pose", "bounds")
_BOUNDS = ("velocity", "omega", "acceleration", "alpha")
_INTEGERS = (("samples", 1000, 1), ("points", 5, 1), ("states", 8, 1), ("seed", 0, 0))
"""Integer keys of a workspace: (key, default, smallest value)."""

SCRATCH = 3 * len(_BOUNDS)
"""Scratch values per state in ``Workspace.states_of``'s ``out`` (the uniform draws)."""


def parse_interval(value, name: str) -> tuple[float, float]:
    """(min, max) of ``[min, max]`` or of one number; ``InputError`` naming ``name``."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = [value, value]
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise InputError(f"{name}: expected [min, max], got {short(value)}")
    lo, hi = as_float(value[0], f"{name}[0]"), as_float(value[1], f"{name}[1]")
    if lo > hi:
        raise InputError(f"{name}: min {lo:g} > max {hi:g}")
    return (lo, hi)


def _check_keys(table: Mapping, allowed: tuple[str, ...], prefix: str, what: str,
                source: str) -> None:
    for key in table:
        if key not in allowed:
            raise InputError(f"{source}: {prefix}{key}: unknown {what}"
                             f"{suggest(str(key), allowed)}")


def _table(data: Mapping, key: str, source: str) -> Mapping:
    value = data.get(key, {})
    if not isinstance(value, Mapping):
        raise InputError(f"{source}: {key}: expected a table, got {short(value)}")
    return value


MAX_STATES = 10 ** 8
"""Dynamic states (poses x ``states``) a workspace may ask for: its poses are drawn at once,
and 10^8 states are hours of evaluation already; a larger count is a typo, refused before any
memory is taken."""


def _check_size(workspace: Workspace, source: str) -> None:
    """An ``InputError`` for a workspace of more than ``MAX_STATES`` dynamic states."""
    varying = sum(1 for k in POSE if workspace.ranges[k][1] > workspace.ranges[k][0])
    poses = (float(workspace.points) ** varying if workspace.sampling == "grid"
             else float(workspace.samples))
    if poses * workspace.states > MAX_STATES:
        what = (f"points = {workspace.points} per varying coordinate ({varying})"
                if workspace.sampling == "grid" else f"samples = {workspace.samples}")
        raise InputError(f"{source}: {what} and states = {workspace.states} make "
                         f"{poses * workspace.states:.3g} states, more than {MAX_STATES:.0e}")


def _parse_integers(data: Mapping, source: str) -> dict[str, int]:
    ints = {}
    for key, default, low in _INTEGERS:
        value = data.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise InputError(f"{source}: {key}: expected an integer >= {low}, got "
                             f"{short(value)}")
        ints[key] = value
    return ints


def _parse_ranges(data: Mapping, source: str) -> dict[str, tuple[float, float]]:
    pose = _table(data, "pose", source)
    if "z" not in pose:
        raise InputError(f"{source}: pose.z: missing (the platform height range, m)")
    _check_keys(pose, POSE, "pose.", "coordinate", source)
    return {key: parse_interval(pose.get(key, [0.0, 0.0]), f"{source}: pose.{key}")
            for key in POSE}


def _parse_bounds(data: Mapping, source: str) -> dict[str, np.ndarray]:
    bounds_in = _table(data, "bounds", source)
    _check_keys(bounds_in, _BOUNDS, "bounds.", "bound", source)
    bounds = {}
    for key in _BOUNDS:
        value = bounds_in.get(key, [0.0, 0.0, 0.0])
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            value = [value] * 3
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            raise InputError(f"{source}: bounds.{key}: expected 3 non-negative numbers, got "
                             f"{short(value)}")
        bounds[key] = np.array([as_float(v, f"{source}: bounds.{key}", minimum=0.0)
                                for v in value])
    return bounds


@dataclass(frozen=True)
class Workspace:
    """A set of poses with velocity and acceleration bounds: the worst-case-over-workspace study.

    Attributes
    ----------
    ranges : dict[str, (float, float)]
        For each of ``POSE`` the interval (min, max) (m, rad); a missing angle or horizontal
        coordinate is 0, ``z`` is required.
    sampling : {"grid", "lhs"}
        A grid of ``points`` per varying coordinate, or ``samples`` Latin-hypercube poses.
    states : int
        Dynamic states per pose: state 0 is static, states 1.. take every component of the
        velocity, angular velocity, acceleration and angular acceleration at +-its bound (random
        vertices of the bounds' box, where loads linear in the accelerations are largest).
    bounds : dict[str, ndarray (3,)]
        ``velocity`` m/s, ``omega`` rad/s, ``acceleration`` m/s^2, ``alpha`` rad/s^2 (base
        frame, per component; default 0).
    seed : int
    """

    ranges: dict
    sampling: str = "lhs"
    samples: int = 1000
    points: int = 5
    states: int = 8
    bounds: dict = field(default_factory=dict)
    seed: int = 0

    @classmethod
    def from_dict(cls, data: Mapping, source: str = "workspace") -> Workspace:
        """Build from the TOML layout (docs/howto/sizing.md); ``InputError`` naming the key."""
        _check_keys(data, _WORKSPACE_KEYS, "", "key", source)
        sampling = data.get("sampling", "lhs")
        if sampling not in ("grid", "lhs"):
            raise InputError(f"{source}: sampling: expected 'grid' or 'lhs', got "
                             f"{short(sampling)}")
        other = "points" if sampling == "lhs" else "samples"
        if other in data:
            raise InputError(f"{source}: {other}: applies to sampling = "
                             f"'{'grid' if sampling == 'lhs' else 'lhs'}', not '{sampling}'")
        ints = _parse_integers(data, source)
        ranges = _parse_ranges(data, source)
        bounds = _parse_bounds(data, source)
        workspace = cls(ranges=ranges, sampling=sampling, bounds=bounds, **ints)
        _check_size(workspace, source)
        return workspace

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> Workspace:
        """Read a workspace TOML file (layout in docs/howto/sizing.md)."""
        path = Path(path)
        data = read_toml(path)
        return cls.from_dict(data, source=str(path))

    def to_dict(self) -> dict:
        """The TOML layout of the workspace (what ``from_dict`` reads)."""
        return {"sampling": self.sampling, "samples": self.samples, "points": self.points,
                "states": self.states, "seed": self.seed,
                "pose": {k: list(v) for k, v in self.ranges.items()},
                "bounds": {k: np.asarray(self.bounds.get(k, np.zeros(3)), float).tolist()
                           for k in _BOUNDS}}

    def poses(self) -> np.ndarray:
        """The sampled poses, (n, 6): ``x, y, z`` m and ``roll, pitch, yaw`` rad."""
        lo = np.array([self.ranges[k][0] for k in POSE])
        hi = np.array([self.ranges[k][1] for k in POSE])
        varying = np.flatnonzero(hi > lo)
        if self.sampling == "grid":
            axes = [np.linspace(lo[i], hi[i], self.points) if i in varying else [lo[i]]
                    for i in range(6)]
            mesh = np.meshgrid(*axes, indexing="ij")
            return np.stack([m.ravel() for m in mesh], axis=1)

        out = np.tile(lo, (self.samples, 1))
        if varying.size:
            unit = qmc.LatinHypercube(d=varying.size, seed=self.seed).random(self.samples)
            out[:, varying] = lo[varying] + unit * (hi[varying] - lo[varying])
        return out

    def states_of(self, poses: np.ndarray, first: int, *,
                  out: np.ndarray | None = None) -> np.ndarray:
        """The ``states`` dynamic states of poses ``first, first + 1, ...``, (n * states, 24).

        Laid out as ``gsfric.evaluation.evaluator.state_array`` (``gsfric.compiled.state``).
        The signs come from a counter-based generator (Philox) positioned at the first pose,
        so each pose's states depend on the seed and its index only: the same on every
        worker, in every run, for any chunking. ``out``, a contiguous float64 buffer of at least
        24 + ``SCRATCH`` (36) values per state, receives the states in its first 24 per state (the
        rest is scratch): nothing of the size of the states is allocated then.
        """
        states = state_layout()
        n, s = len(poses), self.states
        m = n * s
        width = states.size + SCRATCH
        buf = np.empty(m * width) if out is None else out.reshape(-1)
        if buf.size < m * width:
            raise ValueError(f"states_of: out holds {buf.size} values, needs {m * width}")
        x = buf[:m * states.size].reshape(n, s, states.size)
        uniform = buf[m * states.size:m * width].reshape(n, s, SCRATCH)
        rng = np.random.Generator(np.random.Philox(key=self.seed))
        rng.bit_generator.advance(first * s * 3)   # 4 doubles per counter step, 12 per state
        rng.random(out=uniform)
        uniform -= 0.5
        for k, name in enumerate(_BOUNDS):
            slot = x[:, :, getattr(states, name)]
            bound = np.asarray(self.bounds.get(name, np.zeros(3)), float)
            np.copysign(bound, uniform[:, :, 3 * k:3 * k + 3], out=slot)  # -bound below 0.5
            slot[:, 0, :] = 0.0                                           # the static state
        x[:, :, states.position] = poses[:, None, :3]
        x[:, :, states.rotation] = rotation_from_rpy(poses[:, 3:6]).reshape(n, 1, 9)
        return x.reshape(n * s, states.size)


_LENGTH_BLOCK = 8192
"""Poses whose leg lengths are computed at a time (a workspace of a million poses is checked
in bounded memory before its sweep starts)."""

CHECK_THREADS = 4
"""Threads that share the check of the poses against the stroke, at most (and one per core,
one per block): the check is the longest serial step before a sweep's first task, and its
NumPy operations on blocks of poses release the interpreter lock."""


def check_reachable(platform: Platform, poses: np.ndarray, source: str = "workspace") -> None:
    """``InputError`` (one line) when a pose (n, 6) (``POSE`` columns) puts a leg outside the
    platform's stroke; leg lengths ``Platform.leg_lengths``, ``_LENGTH_BLOCK`` poses at a time,
    the poses shared between up to ``CHECK_THREADS`` threads."""
    stroke = platform.geometry.stroke
    if stroke is None:
        return
    blocks = -(-len(poses) // _LENGTH_BLOCK)
    parts = max(1, min(CHECK_THREADS, os.cpu_count() or 1, blocks))
    edges = [_LENGTH_BLOCK * (blocks * p // parts) for p in range(parts)] + [len(poses)]
    found = in_parallel(*(functools.partial(_outside, platform, poses, a, b)
                          for a, b in zip(edges[:-1], edges[1:])))
    count = sum(c for c, _ in found)
    first = next((f for _, f in found if f is not None), None)
    if first is None:
        return
    k, lengths = first
    leg = int(np.flatnonzero((lengths < stroke[0]) | (lengths > stroke[1]))[0])
    pose = ", ".join(f"{n}={v:.4g}" for n, v in zip(POSE, poses[k]))
    raise InputError(f"{source}: unreachable: {count} of {len(poses)} poses put a "
                     f"leg outside the stroke [{stroke[0]:g}, {stroke[1]:g}] m; first: pose "
                     f"{k} ({pose}), leg {leg + 1} length {lengths[leg]:.4g} m")


def _outside(platform: Platform, poses: np.ndarray, start: int, stop: int
             ) -> tuple[int, tuple[int, np.ndarray] | None]:
    """The poses ``start:stop`` outside the stroke: their count, and the first (its index and
    leg lengths), or None."""
    lo, hi = platform.geometry.stroke
    count, first = 0, None
    for s in range(start, stop, _LENGTH_BLOCK):
        part = poses[s:min(stop, s + _LENGTH_BLOCK)]
        D = platform.leg_lengths(part[:, :3], rotation_from_rpy(part[:, 3:6]))
        bad = ((D < lo) | (D > hi)).any(axis=1)
        count += int(bad.sum())
        if first is None and bad.any():
            k = int(np.flatnonzero(bad)[0])
            first = (s + k, D[k])
    return count, first
