"""Joint sizing at scale: load envelopes per joint over motions, a workspace and platform variants.

``sweep`` evaluates every *case* (a motion or the workspace, on one platform variant) and
reduces it, where it is evaluated, to a **load envelope per joint**: the largest |R_E|, |R_C|,
|M_C|, |R_3|, |M_3|, the actuator force range, the peak friction force and moments, the peak
friction power and the dissipated friction energy of each leg's three joints, each extreme with
the motion, step, time and pose where it occurs. Only these envelopes leave a worker.

Work is cut into *tasks* of about ``chunk_steps`` evaluated steps (a second or more each): one
trajectory file or one block of workspace poses, on a range of variants. Inside a task, steps
are evaluated and reduced ``BLOCK_STEPS`` at a time into reused buffers: the compiled code
(generated function ``envelope``, derive/envelope.py) writes per step only the 78 values the
envelopes maximise (squared load magnitudes, forces, friction powers) with the step flags, and
a block is folded into the running extremes in one pass while it is still in the core's cache.
Tasks run in this
process (``scheduler="serial"``), on a Dask ``LocalCluster`` of one single-threaded worker
process per core (``"local"``), or on a running Dask cluster (``"tcp://host:port"`` or the
``DASK_SCHEDULER_ADDRESS`` variable). The result does not depend on where a task runs: a task's
envelope is a deterministic function of its inputs, and envelopes are merged in task order.

Output folder ``OUT`` (built in ``OUT.partial`` and renamed when complete):

* ``envelopes.parquet``: one row per case, quantity and leg (``ENVELOPE_COLUMNS``);
* ``summary.csv``: the extreme of each quantity and leg over all cases, with where it occurs;
* ``variants.csv``: each variant's parameter values (variant 0 is the nominal platform);
* ``limits.csv``: the cases whose envelope exceeds the platform's ``[limits]`` (if any given);
* ``sweep.json``: the inputs' fingerprint, totals, timing; ``envelope.png``, ``locations.png``.

Finished tasks are kept in ``OUT.partial/chunks/`` as they arrive; a sweep interrupted and
started again with the same inputs and output folder computes only the missing tasks.

Threads: every task builds its own evaluators and buffers and evaluates in one thread
(``n_threads=1``); Dask workers are processes with one thread each (and one BLAS thread: Dask
sets ``OMP_NUM_THREADS=1`` and the like in the processes it starts), one per core.
"""

from __future__ import annotations

import glob as globmod
import hashlib
import itertools
import json
import logging
import math
import os
import shutil
import sys
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import tomllib
from scipy.spatial.transform import Rotation
from scipy.stats import qmc
from tqdm import tqdm

from gsfric import __version__
from gsfric._checks import as_float, short, suggest
from gsfric.compiled import native
from gsfric.errors import InputError
from gsfric.evaluation.evaluator import Evaluator, model_function, state_array
from gsfric.io.files import atomic_write
from gsfric.io.tables import count_rows
from gsfric.models import reference_platform
from gsfric.platform.catalog import sensor_parameters
from gsfric.platform.description import Platform
from gsfric.simulate.stream import iter_motions
from gsfric.trajectory import Motion

# -- what an envelope holds -----------------------------------------------------------------

QUANTITIES: dict[str, tuple[str, str, str]] = {
    "R_E": ("max", "N", "spherical joint load |R_E|"),
    "R_C": ("max", "N", "universal joint load |R_C|"),
    "M_C": ("max", "N m", "universal joint torsion moment |M_C|"),
    "R_3": ("max", "N", "prismatic joint transverse force |R_3|"),
    "M_3": ("max", "N m", "prismatic joint moment |M_3|"),
    "F_max": ("max", "N", "largest actuator force (pushing)"),
    "F_min": ("min", "N", "smallest actuator force (pulling when negative)"),
    "Ffr": ("max", "N", "prismatic friction force |Ffr|"),
    "MfrE": ("max", "N m", "spherical joint friction moment |MfrE|"),
    "MfrC": ("max", "N m", "universal joint friction moment |MfrC|"),
    "P_E": ("max", "W", "friction power dissipated in the spherical joint"),
    "P_C": ("max", "W", "friction power dissipated in the universal joint"),
    "P_3": ("max", "W", "friction power dissipated in the prismatic joint"),
    "W_E": ("sum", "J", "friction energy dissipated in the spherical joint (motions only)"),
    "W_C": ("sum", "J", "friction energy dissipated in the universal joint (motions only)"),
    "W_3": ("sum", "J", "friction energy dissipated in the prismatic joint (motions only)"),
}
"""Envelope quantities: name -> (reduction, unit, meaning). Loads and moments are magnitudes;
powers are dissipated (positive), ``-MfrE . omega_rel``, ``-MfrC . omega_leg``, ``-Ffr D_dot``;
energies are their trapezoidal time integrals (NaN for workspace samples, which are no motion)."""

POSE = ("x", "y", "z", "roll", "pitch", "yaw")
"""Pose columns of a location: platform origin (m) and ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rad)."""

ENVELOPE_COLUMNS = ("motion", "variant", "quantity", "leg", "value", "step", "t", *POSE,
                    "steps", "flagged")
"""Columns of ``envelopes.parquet``: ``step`` is the 0-based step of the motion (for the
workspace, ``pose * states + state``), -1 for sums; ``steps`` and ``flagged`` count the
case's evaluated and flagged steps (flagged steps are left out of the envelope)."""

LIMIT_QUANTITY = {"spherical_load": "R_E", "universal_load": "R_C", "universal_moment": "M_C",
                  "prismatic_load": "R_3", "prismatic_moment": "M_3"}

SCALAR_PARAMETERS = (
    "gravity", "platform.mass", "platform.payload_mass", "legs.lower_mass", "legs.upper_mass",
    "friction.joint_viscous", "friction.joint_coulomb", "friction.joint_radius",
    "friction.prismatic_viscous", "friction.prismatic_coulomb",
    "geometry.base_scale", "geometry.platform_scale")
"""Parameters a variant may change: ranges (uniform, Latin hypercube) or tolerances (normal).
``geometry.*_scale`` scale the joints' horizontal positions (the joint circles' radii)."""

JOINT_TOLERANCES = ("geometry.base_joints", "geometry.platform_joints")
"""Tolerances only: a normal error of this standard deviation (m) on every joint coordinate."""

CHUNK_STEPS = 1_000_000
"""Default evaluated steps per task: one to a few seconds of one core (docs/sizing.md)."""

SERIAL_BELOW = 2_000_000
"""``scheduler="auto"`` runs sweeps of fewer steps in this process: below two tasks a cluster
has nothing to share out, and starting one (0.5-5 s with the workers' imports and first task)
costs about what a second core saves on a million steps (docs/sizing.md)."""

STREAM_CHUNK = 50_000
"""Steps of a trajectory file read and evaluated at a time inside a task (bounds memory)."""

# -- workspace ------------------------------------------------------------------------------

_WORKSPACE_KEYS = ("sampling", "samples", "points", "states", "seed", "pose", "bounds")
_BOUNDS = ("velocity", "omega", "acceleration", "alpha")


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
        """Build from the TOML layout (docs/sizing.md); ``InputError`` naming the key."""
        def fail(msg):
            raise InputError(f"{source}: {msg}")

        for key in data:
            if key not in _WORKSPACE_KEYS:
                fail(f"{key}: unknown key{suggest(str(key), _WORKSPACE_KEYS)}")
        sampling = data.get("sampling", "lhs")
        if sampling not in ("grid", "lhs"):
            fail(f"sampling: expected 'grid' or 'lhs', got {short(sampling)}")
        ints = {}
        for key, default, low in (("samples", 1000, 1), ("points", 5, 1), ("states", 8, 1),
                                  ("seed", 0, 0)):
            value = data.get(key, default)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                fail(f"{key}: expected an integer >= {low}, got {short(value)}")
            ints[key] = value
        pose = data.get("pose", {})
        if not isinstance(pose, Mapping):
            fail(f"pose: expected a table, got {short(pose)}")
        if "z" not in pose:
            fail("pose.z: missing (the platform height range, m)")
        ranges = {}
        for key in pose:
            if key not in POSE:
                fail(f"pose.{key}: unknown coordinate{suggest(str(key), POSE)}")
        for key in POSE:
            ranges[key] = _interval(pose.get(key, [0.0, 0.0]), f"{source}: pose.{key}")
        bounds_in = data.get("bounds", {})
        if not isinstance(bounds_in, Mapping):
            fail(f"bounds: expected a table, got {short(bounds_in)}")
        bounds = {}
        for key in bounds_in:
            if key not in _BOUNDS:
                fail(f"bounds.{key}: unknown bound{suggest(str(key), _BOUNDS)}")
        for key in _BOUNDS:
            value = bounds_in.get(key, [0.0, 0.0, 0.0])
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                value = [value] * 3
            if not isinstance(value, (list, tuple)) or len(value) != 3:
                fail(f"bounds.{key}: expected 3 non-negative numbers, got {short(value)}")
            bounds[key] = np.array([as_float(v, f"{source}: bounds.{key}", minimum=0.0)
                                    for v in value])
        return cls(ranges=ranges, sampling=sampling, bounds=bounds, **ints)

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> Workspace:
        """Read a workspace TOML file (layout in docs/sizing.md)."""
        path = Path(path)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise InputError(f"{path}: file not found") from None
        except (OSError, UnicodeDecodeError) as error:
            raise InputError(f"{path}: cannot read ({error})") from None
        except tomllib.TOMLDecodeError as error:
            raise InputError(f"{path}: invalid TOML: {error}") from None
        return cls.from_dict(data, source=str(path))

    def to_dict(self) -> dict:
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

    def states_of(self, poses: np.ndarray, first: int, rotation: np.ndarray | None = None,
                  out: np.ndarray | None = None) -> np.ndarray:
        """The ``states`` dynamic states of poses ``first, first + 1, ...``, (n * states, 24).

        Laid out as ``gsfric.evaluation.state_array``. The signs come from a counter-based
        generator (Philox) positioned at the first pose, so each pose's states depend on the
        seed and its index only: the same on every worker, in every run, for any chunking.
        ``rotation`` (n, 3, 3), the poses' rotation matrices, saves computing them again;
        ``out``, a contiguous float64 buffer of at least 36 values per state, receives the
        states in its first 24 per state (the rest is scratch): nothing of the size of the
        states is allocated then.
        """
        n, s = len(poses), self.states
        m = n * s
        buf = np.empty(m * 36) if out is None else out.reshape(-1)
        if buf.size < m * 36:
            raise ValueError(f"states_of: out holds {buf.size} values, needs {m * 36}")
        x = buf[:m * 24].reshape(n, s, 24)
        uniform = buf[m * 24:m * 36].reshape(n, s, 12)
        rng = np.random.Generator(np.random.Philox(key=self.seed))
        rng.bit_generator.advance(first * s * 3)   # 4 doubles per counter step, 12 per state
        rng.random(out=uniform)
        uniform -= 0.5
        bound = np.concatenate([np.asarray(self.bounds.get(k, np.zeros(3)), float)
                                for k in _BOUNDS])                       # (12,)
        dyn = x[:, :, 12:24]
        np.copysign(bound, uniform, out=dyn)       # -bound where the double is below 0.5
        dyn[:, 0, :] = 0.0                         # the static state
        x[:, :, 0:3] = poses[:, None, :3]
        x[:, :, 3:12] = (_rotation(poses) if rotation is None else rotation).reshape(n, 1, 9)
        return x.reshape(n * s, 24)


def _interval(value, name: str) -> tuple[float, float]:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = [value, value]
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise InputError(f"{name}: expected [min, max], got {short(value)}")
    lo, hi = as_float(value[0], f"{name}[0]"), as_float(value[1], f"{name}[1]")
    if lo > hi:
        raise InputError(f"{name}: min {lo:g} > max {hi:g}")
    return (lo, hi)


def _rotation(poses: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) ``R = Rz(yaw) Ry(pitch) Rx(roll)`` of poses (n, 6).

    What ``scipy.spatial.transform.Rotation.from_euler("ZYX", [yaw, pitch, roll])`` gives
    (to rounding), written out: six times faster, which matters at a million poses.
    """
    c, s = np.cos(poses[:, 3:6]), np.sin(poses[:, 3:6])
    (cr, cp, cy), (sr, sp, sy) = c.T, s.T
    out = np.empty((len(poses), 3, 3))
    out[:, 0, 0] = cy * cp
    out[:, 0, 1] = cy * sp * sr - sy * cr
    out[:, 0, 2] = cy * sp * cr + sy * sr
    out[:, 1, 0] = sy * cp
    out[:, 1, 1] = sy * sp * sr + cy * cr
    out[:, 1, 2] = sy * sp * cr - cy * sr
    out[:, 2, 0] = -sp
    out[:, 2, 1] = cp * sr
    out[:, 2, 2] = cp * cr
    return out


def _angles(rotation: np.ndarray) -> np.ndarray:
    """(roll, pitch, yaw) of rotations (N, 3, 3), ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)   # gimbal lock at pitch = +-90 deg
        return Rotation.from_matrix(rotation).as_euler("ZYX")[:, ::-1]


_LENGTH_BLOCK = 8192
"""Poses whose leg lengths are computed at a time (their work arrays stay in the cache)."""

def _leg_lengths(platform: Platform, poses: np.ndarray) -> np.ndarray:
    """Leg lengths |p + R e_i - c_i| (n, 6), m, of poses (n, 6) (``POSE`` columns).

    The formula of ``gsfric.discovery.rest.leg_lengths``, with every ``R e_i`` of a pose as one
    matrix product (the rotation's 9 entries times a (9, 18) matrix of the joints), over
    blocks of ``_LENGTH_BLOCK`` poses: a workspace of a million poses is checked before its
    sweep starts.
    """
    g = platform.geometry
    n = len(poses)
    joints = np.zeros((3, 3, 6, 3))           # R[i, j] e[k, j] -> component i of joint k
    for i in range(3):
        joints[i, :, :, i] = g.platform_joints.T
    joints = joints.reshape(9, 18)
    out = np.empty((n, 6))
    work = np.empty((min(n, _LENGTH_BLOCK), 18))
    for s in range(0, n, _LENGTH_BLOCK):
        part = poses[s:s + _LENGTH_BLOCK]
        m = len(part)
        legs = work[:m]
        np.matmul(_rotation(part).reshape(m, 9), joints, out=legs)
        legs3 = legs.reshape(m, 6, 3)
        legs3 += part[:, None, :3]
        legs3 -= g.base_joints
        np.square(legs, out=legs)
        np.sqrt(legs3 @ np.ones(3), out=out[s:s + m])
    return out


def check_reachable(platform: Platform, poses: np.ndarray, source: str = "workspace") -> None:
    """``InputError`` (one line) when a pose puts a leg outside the platform's stroke."""
    stroke = platform.geometry.stroke
    if stroke is None:
        return
    D = _leg_lengths(platform, poses)
    bad = ((D < stroke[0]) | (D > stroke[1])).any(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        leg = int(np.flatnonzero((D[k] < stroke[0]) | (D[k] > stroke[1]))[0])
        pose = ", ".join(f"{n}={v:.4g}" for n, v in zip(POSE, poses[k]))
        raise InputError(f"{source}: unreachable: {int(bad.sum())} of {len(poses)} poses put a "
                         f"leg outside the stroke [{stroke[0]:g}, {stroke[1]:g}] m; first: pose "
                         f"{k} ({pose}), leg {leg + 1} length {D[k, leg]:.4g} m")


# -- platform variants ----------------------------------------------------------------------


def _parse_vary(vary: Mapping | None, tolerances: Mapping | None):
    vary = dict(vary or {})
    tolerances = dict(tolerances or {})
    ranges = {}
    for name, value in vary.items():
        if name not in SCALAR_PARAMETERS:
            raise InputError(f"vary: {name}: unknown parameter"
                             f"{suggest(str(name), SCALAR_PARAMETERS)}; one of "
                             f"{', '.join(SCALAR_PARAMETERS)}")
        ranges[name] = _interval(value, f"vary: {name}")
        if ranges[name][0] < 0:
            raise InputError(f"vary: {name}: min {ranges[name][0]:g} is negative")
    sds = {}
    for name, value in tolerances.items():
        if name not in SCALAR_PARAMETERS + JOINT_TOLERANCES:
            raise InputError(f"tolerance: {name}: unknown parameter"
                             f"{suggest(str(name), SCALAR_PARAMETERS + JOINT_TOLERANCES)}")
        sds[name] = as_float(value, f"tolerance: {name}", minimum=0.0)
    return ranges, sds


def _value(platform: Platform, name: str) -> float:
    if name == "gravity":
        return platform.gravity
    section, key = name.split(".")
    if key.endswith("_scale"):
        return 1.0
    return getattr({"platform": platform.platform, "legs": platform.legs,
                    "friction": platform.friction}[section], key)


def _apply(platform: Platform, values: Mapping[str, Any]) -> Platform:
    body, legs, friction, geometry = {}, {}, {}, {}
    gravity = platform.gravity
    g = platform.geometry
    for name, value in values.items():
        if name == "gravity":
            gravity = float(value)
            continue
        section, key = name.split(".")
        if key == "base_scale":
            geometry["base_joints"] = geometry.get("base_joints", g.base_joints) * \
                np.array([value, value, 1.0])
        elif key == "platform_scale":
            geometry["platform_joints"] = geometry.get("platform_joints", g.platform_joints) * \
                np.array([value, value, 1.0])
        elif key in ("base_joints", "platform_joints"):
            geometry[key] = geometry.get(key, getattr(g, key)) + np.asarray(value)
        else:
            {"platform": body, "legs": legs, "friction": friction}[section][key] = float(value)
    out = platform.replace(gravity=gravity)
    if body:
        out = out.with_body(**body)
    if legs:
        out = out.with_legs(**legs)
    if friction:
        out = out.with_friction(**friction)
    if geometry:
        out = out.with_geometry(**geometry)
    return out


def make_variants(platform: Platform, vary: Mapping | None = None,
                  tolerances: Mapping | None = None, samples: int = 16,
                  seed: int = 0) -> tuple[list[Platform], list[dict]]:
    """Platform variants: the nominal one, then ``samples`` drawn ones.

    Parameters
    ----------
    platform : Platform
        The nominal platform (variant 0).
    vary : dict name -> (min, max)
        Uniform ranges (Latin hypercube over all of them); names in ``SCALAR_PARAMETERS``.
    tolerances : dict name -> standard deviation
        Normal errors added to the nominal (or ranged) value: scalars in their unit, joints
        (``JOINT_TOLERANCES``) in m on every coordinate. Values are truncated at 0.
    samples : int
        Drawn variants (ignored without ``vary`` and ``tolerances``).
    seed : int

    Returns
    -------
    platforms : list of Platform, length 1 + samples (1 without ranges or tolerances)
    table : list of dict
        Each variant's parameter values (joint errors as their largest magnitude, m).
    """
    ranges, sds = _parse_vary(vary, tolerances)
    names = list(dict.fromkeys([*ranges, *sds]))
    nominal = {n: (_value(platform, n) if n not in JOINT_TOLERANCES else 0.0) for n in names}
    platforms, table = [platform], [{"variant": 0, **nominal}]
    if not names:
        return platforms, table
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
        raise InputError(f"variants: expected an integer >= 1, got {short(samples)}")

    rng = np.random.default_rng(seed)
    unit = (qmc.LatinHypercube(d=len(ranges), seed=seed).random(samples) if ranges
            else np.zeros((samples, 0)))
    for k in range(samples):
        values: dict[str, Any] = {}
        row: dict[str, Any] = {"variant": k + 1}
        for j, (name, (lo, hi)) in enumerate(ranges.items()):
            values[name] = lo + unit[k, j] * (hi - lo)
        for name, sd in sds.items():
            if name in JOINT_TOLERANCES:
                values[name] = rng.normal(0.0, sd, (6, 3))
            else:
                values[name] = max(0.0, values.get(name, nominal[name]) + rng.normal(0.0, sd))
        for name in names:
            v = values[name]
            row[name] = float(np.abs(v).max()) if name in JOINT_TOLERANCES else float(v)
        try:
            platforms.append(_apply(platform, values))
        except InputError as error:
            raise InputError(f"variant {k + 1}: {error}") from None
        table.append(row)
    return platforms, table


# -- tasks and their reduction (runs on the workers) ----------------------------------------


@dataclass
class Task:
    """One unit of work: a trajectory file or a block of workspace poses, on some variants."""

    id: int
    motion: str                       # case name: the file's name or "workspace"
    variants: list[int]
    platforms: list[Platform]
    steps: int                        # evaluated steps (all variants)
    path: str | None = None
    poses: np.ndarray | None = None   # (n, 6) workspace block
    first_pose: int = 0
    workspace: Workspace | None = None


BLOCK_STEPS = 2048
"""Steps evaluated and reduced at a time inside a task. A block's values (78 per step, 1.3 MB,
in the core's cache between the evaluation and the reduction) are reused from block to block
and from variant to variant, so a worker's memory follows this size and the task's poses, not
the sweep's size."""

_ROWS = ("R_E", "R_C", "R_3", "M_3", "MfrE", "MfrC", "M_C", "F_max", "F_min", "Ffr", "P_E",
         "P_C", "P_3")
"""Rows of a step's values ``G`` (13, 6), every one maximised over the steps: the squared
magnitudes of the six vector loads (the square root is taken of the extremes only), |M_C|, F,
-F (the largest -F is the smallest F), |Ffr| and the three dissipated friction powers. The
compiled code computes them per step (generated function ``envelope``, derive/envelope.py)."""

_NONE = np.zeros(0, dtype=np.int64)
_NONE.flags.writeable = False      # shared by every task of a process


def values(arrays: Mapping[str, np.ndarray], out: np.ndarray | None = None) -> np.ndarray:
    """The values ``G`` (N, 13, 6) (rows ``_ROWS``) of evaluated outputs ``arrays`` (those of
    ``Evaluator.evaluate_quiet``): what the generated function ``envelope`` computes, in
    NumPy (the path of platforms with sensor effects and of the CasADi fallback)."""
    n = len(arrays["F"])
    G = np.empty((n, len(_ROWS), 6)) if out is None else out

    def vec(name):
        return np.asarray(arrays[name], float).reshape(n, 6, 3)

    for k, name in enumerate(_ROWS[:6]):
        v = vec(name)
        G[:, k] = np.einsum("nij,nij->ni", v, v)
    F = np.asarray(arrays["F"], float).reshape(n, 6)
    Ffr = np.asarray(arrays["Ffr"], float).reshape(n, 6)
    G[:, 6] = np.abs(np.asarray(arrays["M_C"], float).reshape(n, 6))
    G[:, 7] = F
    G[:, 8] = -F
    G[:, 9] = np.abs(Ffr)
    G[:, 10] = -np.einsum("nij,nij->ni", vec("MfrE"), vec("omega_rel"))
    G[:, 11] = -np.einsum("nij,nij->ni", vec("MfrC"), vec("omega_leg"))
    G[:, 12] = -(Ffr * np.asarray(arrays["D_dot"], float).reshape(n, 6))
    return G


class _Block:
    """Buffers of one block of at most ``size`` steps, reused: each step's values ``G`` (the
    generated ``envelope``'s 78 values), the step flags and the workspace states. Belongs to one
    task (never shared between threads). Nothing of the block's size is allocated block after
    block: Dask's workers return freed memory to the system at once
    (``MALLOC_TRIM_THRESHOLD_``), so every such allocation would cost fresh pages."""

    def __init__(self, size: int) -> None:

        self.compiled = native.is_compiled()
        self.size = size
        self._values = np.empty(size * len(_ROWS) * 6)
        self._pairs = np.empty(size * 3 * 6)           # the trapezoid's sums of neighbours
        self.states = np.empty(size * 36)               # workspace states of a block
        self.times = np.zeros(size)
        self._flag = np.empty(size, dtype=np.int64)
        self.n = 0

    def use(self, n: int) -> None:
        """Lay the buffers out for ``n <= size`` steps (every view C-contiguous)."""
        if n == self.n:
            return
        self.n = n
        self.values = self._values[:n * len(_ROWS) * 6].reshape(n, len(_ROWS), 6)
        self.out = {"G": self.values.reshape(n, len(_ROWS) * 6)}
        self.flag = self._flag[:n]


class _Evaluation:
    """One variant's evaluation of blocks of states into a ``_Block``: each step's values
    ``G`` and the step flags, in one call of the compiled code (generated ``envelope``) per
    block.

    ``G`` is what the norms and products of ``Evaluator.evaluate_quiet``'s outputs give (to
    rounding: within 1e-12), with its step flags and coupled-friction flag; a platform with
    sensor effects (which change F after the compiled code) and the CasADi fallback go through
    ``Evaluator.evaluate_quiet`` itself and ``values``.
    """

    def __init__(self, platform: Platform) -> None:

        self.evaluator = Evaluator(platform, n_threads=1)
        gains, delay = sensor_parameters(platform.effects)
        self.sensor = delay != 0.0 or bool(np.any(gains != 0.0))
        self.spec = None
        if native.is_compiled() and not self.sensor:
            # the platform's own model (derived with its friction model fixed, as evaluate's)
            self.fn = native.get(model_function("envelope", platform.friction.model))
            # the evaluator's flag settings, on the outputs of ``envelope``
            base = self.evaluator.flag_spec()
            index = {name: k for k, (name, _, _) in enumerate(self.fn.outputs)}
            self.spec = native.FlagSpec(
                *[index[name] if getattr(base, field) >= 0 else -1 for name, field in
                  (("D", "d"), ("s2", "s2"), ("h", "h"))],
                base.has_stroke, base.stroke_lo, base.stroke_hi, base.universal_limit,
                base.singular_limit, base.x_size,
                index["coupling_change"] if base.cc >= 0 else -1,
                index["F0"] if base.f0 >= 0 else -1, base.coupling_tol)

    def blocks(self, block: _Block, x: np.ndarray, t: np.ndarray):
        """Fill ``block`` with the steps ``s:e`` of states x (n, 24) at times t (n,) block
        after block; yields ``(s, e)``."""
        n = len(x)
        if self.spec is not None and block.compiled:
            ev = self.evaluator         # every flag, the coupled solve's included, set in C
            for s in range(0, n, block.size):
                e = min(n, s + block.size)
                block.use(e - s)
                self.fn([x[s:e], ev.P, ev.Q], block.out, 1, select=("G",), flags=self.spec,
                         flag=block.flag)
                yield s, e
            return

        motion = Motion(t, x[:, 0:3], x[:, 3:12].reshape(n, 3, 3), x[:, 12:15], x[:, 15:18],
                        x[:, 18:21], x[:, 21:24])
        result = self.evaluator.evaluate_quiet(motion)       # flagged steps are counted
        for s in range(0, n, block.size):
            e = min(n, s + block.size)
            block.use(e - s)
            values({k: result.arrays[k][s:e] for k in
                    ("F", "M_C", "Ffr", "D_dot", "omega_rel", "omega_leg", *_ROWS[:6])},
                   block.values)
            block.flag[...] = result.flag[s:e]
            yield s, e


class _Envelope:
    """Running extremes of one case, block by block in step order (deterministic: ties go to
    the earlier step)."""

    def __init__(self) -> None:
        shape = (len(_ROWS), 6)
        self.best = np.full(shape, -np.inf)
        self.step = np.full(shape, -1, dtype=np.int64)
        self.t = np.full(shape, np.nan)
        self.state = np.full(shape + (12,), np.nan)    # position and rotation of the step
        self.energy = np.zeros((3, 6))                  # W_E, W_C, W_3
        self.steps = 0
        self.flagged = 0
        self.last = None      # (t, powers (3, 6)) of the motion's previous step

    def add(self, block: _Block, x: np.ndarray, t: np.ndarray, step0: int, timed: bool) -> None:
        """Fold in the block's values: states x (n, 24), times t (n,), first step ``step0``.

        One pass over the block for the largest value of each of the 78 columns; the step of
        a column's largest value is searched only where it beats the running extreme, which
        becomes rare as the case goes on."""
        G = block.values                                     # (n, 13, 6)
        bad = np.flatnonzero(block.flag) if np.count_nonzero(block.flag) else _NONE
        self.steps += block.n
        self.flagged += bad.size
        if timed:
            self._integrate(G[:, 10:13], bad, t, block._pairs)
        if bad.size:
            G[bad] = -np.inf                    # flagged steps are left out of the envelope
        flat = G.reshape(block.n, -1)
        best = self.best.reshape(-1)
        better = np.flatnonzero(flat.max(axis=0) > best)
        if better.size:
            at = flat[:, better].argmax(axis=0)                     # the first largest
            best[better] = flat[at, better]
            q, leg = np.divmod(better, 6)
            self.step[q, leg] = step0 + at
            self.t[q, leg] = t[at]
            self.state[q, leg] = x[at, :12]

    def _integrate(self, P: np.ndarray, bad: np.ndarray, t: np.ndarray,
                   work: np.ndarray) -> None:
        """Trapezoid of the powers P (n, 3, 6) over t, across block boundaries (flagged: 0);
        ``work`` holds at least (n - 1) 3 6 values."""
        if bad.size:
            P = P.copy()
            P[bad] = 0.0
        if self.last is not None:
            self.energy += 0.5 * (t[0] - self.last[0]) * (P[0] + self.last[1])
        n = len(t)
        if n > 1:
            pairs = work[:(n - 1) * 18].reshape(n - 1, 18)
            np.add(P[1:].reshape(n - 1, 18), P[:-1].reshape(n - 1, 18), out=pairs)
            self.energy += 0.5 * (np.diff(t) @ pairs).reshape(3, 6)
        self.last = (t[-1], P[-1].copy())

    def rows(self, motion: str, variant: int, timed: bool) -> list[tuple]:
        found = self.step >= 0
        value = np.where(found, self.best, np.nan)
        value[0:6] = np.sqrt(value[0:6])
        value[8] = -value[8]
        pose = np.full((len(_ROWS), 6, 6), np.nan)
        pose[found, 0:3] = self.state[found, 0:3]
        if found.any():
            pose[found, 3:6] = _angles(self.state[found, 3:12].reshape(-1, 3, 3))
        out = []
        sums = {"W_E": 0, "W_C": 1, "W_3": 2}
        for q in QUANTITIES:
            for leg in range(6):
                if q in sums:
                    w = float(self.energy[sums[q], leg]) if timed else math.nan
                    where = [-1] + [math.nan] * 7
                    out.append((motion, variant, q, leg + 1, w, *where, self.steps,
                                self.flagged))
                    continue
                r = _ROWS.index(q)
                where = [int(self.step[r, leg]),
                         float(self.t[r, leg]) if timed and found[r, leg] else math.nan,
                         *pose[r, leg].tolist()]
                out.append((motion, variant, q, leg + 1, float(value[r, leg]), *where,
                            self.steps, self.flagged))
        return out


def _pieces(task: Task, block: _Block):
    """(first step, states (n, 24), times (n,)) of a task, piece by piece: a trajectory file
    as it is streamed, a block of workspace poses ``BLOCK_STEPS`` states at a time (in the
    block's buffers: valid until the next piece)."""
    if task.path is not None:

        for start, m in iter_motions(task.path, chunk=STREAM_CHUNK):
            yield start, state_array(m), np.asarray(m.t, float)
        return
    ws = task.workspace
    per = max(1, block.size // ws.states)
    rotation = _rotation(task.poses)
    for p0 in range(0, len(task.poses), per):
        first = task.first_pose + p0
        x = ws.states_of(task.poses[p0:p0 + per], first, rotation[p0:p0 + per], block.states)
        yield first * ws.states, x, block.times[:len(x)]


def run_task(task: Task):
    """Evaluate one task and reduce it to envelope rows (a DataFrame of ``ENVELOPE_COLUMNS``).

    Runs on a worker, in one thread, block after block of ``BLOCK_STEPS`` steps: each block is
    evaluated for every variant of the task into the same reused buffers and folded into the
    variant's envelope at once, so memory follows ``BLOCK_STEPS``, not the task's size.
    """

    states = task.workspace.states if task.workspace is not None else 1
    block = _Block(max(BLOCK_STEPS, states))
    evaluations = [_Evaluation(p) for p in task.platforms]
    envelopes = [_Envelope() for _ in task.platforms]
    timed = task.path is not None
    for start, x, t in _pieces(task, block):
        for evaluation, envelope in zip(evaluations, envelopes):
            for s, e in evaluation.blocks(block, x, t):
                envelope.add(block, x[s:e], t[s:e], start + s, timed)
    rows = []
    for v, envelope in zip(task.variants, envelopes):
        rows += envelope.rows(task.motion, v, timed)
    frame = pd.DataFrame(rows, columns=list(ENVELOPE_COLUMNS))
    frame.insert(0, "task", task.id)
    return frame


# -- planning ---------------------------------------------------------------------------------


def _file_rows(path: Path) -> int:

    rows = count_rows(path)
    if rows is not None:
        return rows
    with open(path, "rb") as handle:
        return max(0, sum(1 for _ in handle) - 1)


def _trajectory_files(trajectories) -> list[Path]:
    if trajectories is None:
        return []
    patterns = [trajectories] if isinstance(trajectories, (str, os.PathLike)) else \
        list(trajectories)
    files: list[Path] = []
    for pattern in patterns:
        matched = sorted(globmod.glob(os.fspath(pattern), recursive=True))
        matched = [m for m in matched if Path(m).is_file()]
        if not matched:
            raise InputError(f"trajectories: {os.fspath(pattern)!r} matches no file")
        files += [Path(m) for m in matched]
    names = [f.name for f in files]
    for name in names:
        if names.count(name) > 1:
            raise InputError(f"trajectories: two files are named {name!r}; motions are "
                             "named by file name")
    return files


_POSE_BYTES = 48
_VARIANT_BYTES = 17_000
"""What a pose and a variant weigh in a task's traffic: a pose in (6 floats), a variant's
platform in (2 kB) and its envelope out (15 kB), pickled (measured)."""

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


@dataclass
class Plan:
    tasks: list[Task]
    fingerprint: str
    inputs: dict
    variants: list[dict]
    platform: Platform          # the nominal platform, read once
    workspace_poses: int = 0

    @property
    def steps(self) -> int:
        return sum(t.steps for t in self.tasks)


def plan(trajectories=None, workspace: Workspace | str | os.PathLike | None = None,
         platform: Platform | str | os.PathLike | None = None, vary=None, tolerances=None,
         variants: int = 16, seed: int = 0, chunk_steps: int = CHUNK_STEPS) -> Plan:
    """Cut a sweep into tasks (see ``sweep`` for the parameters); checks every input."""

    if platform is None:
        platform = reference_platform()
    elif not isinstance(platform, Platform):
        platform = Platform.from_toml(platform)
    if isinstance(chunk_steps, bool) or not isinstance(chunk_steps, (int, np.integer)) \
            or chunk_steps < 1:
        raise InputError(f"chunk_steps: expected an integer >= 1, got {short(chunk_steps)}")
    files = _trajectory_files(trajectories)
    source = "workspace"
    if workspace is not None and not isinstance(workspace, Workspace):
        source = str(workspace)
        workspace = Workspace.from_toml(workspace)
    if not files and workspace is None:
        raise InputError("sweep: give trajectories (a glob) and/or a workspace")
    platforms, table = make_variants(platform, vary, tolerances, variants, seed)
    nv = len(platforms)
    tasks: list[Task] = []
    hasher = hashlib.sha256()
    for f in files:
        st = f.stat()
        hasher.update(f"{f.resolve()}|{st.st_size}|{st.st_mtime_ns}".encode())
        n = _file_rows(f)
        per = max(1, chunk_steps // max(n, 1))
        for lo in range(0, nv, per):
            vs = list(range(lo, min(nv, lo + per)))
            tasks.append(Task(len(tasks), f.name, vs, [platforms[v] for v in vs],
                              n * len(vs), path=str(f)))
    n_poses = 0
    if workspace is not None:
        poses = workspace.poses()
        n_poses = len(poses)
        check_reachable(platform, poses, source)
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
    inputs = {"gsfric": __version__, "files": [str(f) for f in files],
              "workspace": workspace.to_dict() if workspace is not None else None,
              "platform": platform.to_dict(), "vary": {k: list(v) for k, v in
                                                      _parse_vary(vary, tolerances)[0].items()},
              "tolerances": dict(tolerances or {}), "variants": nv - 1, "seed": seed,
              "chunk_steps": int(chunk_steps)}
    hasher.update(json.dumps(inputs, sort_keys=True, default=str).encode())
    return Plan(tasks, hasher.hexdigest()[:16], inputs, table, platform, n_poses)


# -- merging ----------------------------------------------------------------------------------


MERGE_EVERY = 64
"""Task envelopes held before they are folded into the running merge (bounds client memory)."""

def _reduce(frames) -> Any:
    """Fold task envelopes (and earlier folds) into one row per case, quantity and leg.

    The result does not depend on the order of ``frames`` or of their rows: an extreme is
    chosen by (value, then the lowest task index), the counts are integer sums, and an energy
    has at most one term per case (a motion's variant is one task: files are never split;
    the workspace has no energy). Rows keep the winning ``task``.
    """

    frame = pd.concat(frames, ignore_index=True)
    key = ["motion", "variant", "quantity", "leg"]
    counts = (frame[(frame.quantity == "R_E") & (frame.leg == 1)]
              .groupby(["motion", "variant"], sort=True)[["steps", "flagged"]].sum())
    parts = []
    for q, (kind, _, _) in QUANTITIES.items():
        sub = frame[frame.quantity == q]
        if kind == "sum":
            sub = sub.sort_values(["task", "motion", "variant", "leg"], kind="stable")
            parts.append(sub.groupby(key, sort=True, as_index=False).agg(
                task=("task", "min"),
                value=("value", lambda v: math.fsum(v) if v.notna().all() else math.nan),
                step=("step", "first"), t=("t", "first"), **{c: (c, "first") for c in POSE}))
            continue
        ordered = sub.sort_values(["value", "task"], ascending=[kind == "min", True],
                                  kind="stable", na_position="last")
        parts.append(ordered.drop_duplicates(key, keep="first"))
    out = pd.concat(parts, ignore_index=True).drop(columns=["steps", "flagged"],
                                                   errors="ignore")
    return out.join(counts, on=["motion", "variant"])


def merge(chunks) -> Any:
    """Per-case envelopes (``ENVELOPE_COLUMNS``) from task envelopes, in any order."""

    out = _reduce(list(chunks))
    out["quantity"] = pd.Categorical(out["quantity"], categories=list(QUANTITIES))
    out = out.sort_values(["motion", "variant", "quantity", "leg"], ignore_index=True)
    out["quantity"] = out["quantity"].astype(str)
    out["step"] = out["step"].astype("int64")
    return out[list(ENVELOPE_COLUMNS)]


def summarize(envelopes) -> Any:
    """The extreme of each quantity and leg over all cases, with its case and location."""

    parts = []
    for q, (kind, unit, _) in QUANTITIES.items():
        sub = envelopes[envelopes.quantity == q]
        ordered = sub.sort_values("value", ascending=(kind == "min"), kind="stable",
                                  na_position="last")
        best = ordered.drop_duplicates("leg", keep="first").sort_values("leg").copy()
        best.insert(best.columns.get_loc("value") + 1, "unit", unit)
        parts.append(best)
    out = pd.concat(parts, ignore_index=True)
    return out[["quantity", "leg", "value", "unit", "motion", "variant", "step", "t", *POSE]]


def check_limits(envelopes, limits: Mapping) -> Any:
    """Rows of ``envelopes`` beyond the platform's ``[limits]``, with the limit and the ratio."""

    parts = []
    for key, q in LIMIT_QUANTITY.items():
        if key in limits:
            sub = envelopes[(envelopes.quantity == q) & (envelopes.value > limits[key])].copy()
            sub["limit"] = float(limits[key])
            parts.append(sub)
    if "actuator_force" in limits:
        lo, hi = limits["actuator_force"]
        for q, bad, lim in (("F_max", envelopes.value > hi, hi), ("F_min", envelopes.value < lo,
                                                                  lo)):
            sub = envelopes[(envelopes.quantity == q) & bad].copy()
            sub["limit"] = float(lim)
            parts.append(sub)
    cols = ["motion", "variant", "quantity", "leg", "value", "limit", "ratio", "step", "t",
            *POSE]
    if not parts:
        return pd.DataFrame(columns=cols)
    out = pd.concat(parts, ignore_index=True)
    out["ratio"] = out["value"] / out["limit"]
    return out[cols].sort_values(["motion", "variant", "quantity", "leg"], ignore_index=True)


# -- running ------------------------------------------------------------------------------------


@dataclass
class SweepResult:
    """What ``sweep`` wrote and read back: the envelopes and the paths."""

    out: Path
    envelopes: Any
    summary: Any
    variants: Any
    exceeded: Any
    info: dict

    def most_loaded(self, quantity: str = "R_C") -> Any:
        """The summary row of ``quantity`` with the largest value over the legs."""
        sub = self.summary[self.summary.quantity == quantity]
        return sub.loc[sub.value.idxmax()]


def _client(scheduler, workers: int | None = None):
    """A distributed Client and the LocalCluster we started for it (None otherwise)."""
    from distributed import Client

    if not isinstance(scheduler, str):
        return scheduler, None
    if scheduler == "local":
        cluster = local_cluster(workers or os.cpu_count() or 1)
        return Client(cluster), cluster
    return Client(scheduler), None


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
nannies) 3.2 %; these settings, 0.3 % and 0.7 % (docs/sizing.md)."""

def local_cluster(workers: int):
    """The ``LocalCluster`` of ``scheduler="local"``: ``workers`` processes with one thread
    each, one per core (nothing shared between cores), with ``LOCAL_CLUSTER_CONFIG``."""

    import dask
    from distributed import LocalCluster

    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                            dashboard_address=None, silence_logs=logging.ERROR)


def _resolve_scheduler(scheduler, steps: int):
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


def _store(partial: Path, task_id: int, frame) -> None:

    with atomic_write(partial / "chunks" / f"{task_id:07d}.parquet", "wb") as handle:
        frame.to_parquet(handle, index=False)


def _finished(partial: Path, fingerprint: str):
    """(task index, chunk file) of the tasks an unfinished sweep of these inputs stored."""
    plan_file = partial / "plan.json"
    if not plan_file.exists():
        return {}
    try:
        stored = json.loads(plan_file.read_text())["fingerprint"]
    except (ValueError, KeyError):
        stored = None
    if stored != fingerprint:
        raise InputError(f"{partial}: holds an unfinished sweep of other inputs; remove it "
                         "or choose another output folder")
    return [(int(f.stem), f) for f in sorted((partial / "chunks").glob("*.parquet"))]


def sweep(out: str | os.PathLike, trajectories=None,
          workspace: Workspace | str | os.PathLike | None = None,
          platform: Platform | str | os.PathLike | None = None, vary=None, tolerances=None,
          variants: int = 16, seed: int = 0, scheduler=None, workers: int | None = None,
          chunk_steps: int = CHUNK_STEPS,
          progress: bool | None = None, plots: bool = True,
          on_chunk: Callable[[int, int], None] | None = None) -> SweepResult:
    """Load envelopes per joint over motions, a workspace and platform variants.

    Parameters
    ----------
    out : path
        Output folder (must not exist unless it holds this very sweep, which is then read
        back). Built in ``out + ".partial"``; an unfinished sweep there resumes.
    trajectories : str, path or list of them
        Glob pattern(s) of trajectory files (CSV or Parquet); each file is one motion.
    workspace : Workspace or path of its TOML
        Poses and velocity/acceleration bounds (docs/sizing.md).
    platform : Platform or path of its TOML
        The nominal platform (default: the reference platform); its ``[limits]`` are checked.
    vary : dict name -> (min, max)
        Parameter ranges of the variants (``SCALAR_PARAMETERS``).
    tolerances : dict name -> standard deviation
        Monte-Carlo tolerances (``SCALAR_PARAMETERS`` and ``JOINT_TOLERANCES``).
    variants : int
        Variants drawn besides the nominal one when ``vary`` or ``tolerances`` is given.
    seed : int
        Seed of the variants (the workspace has its own).
    scheduler : {"auto", "serial", "local"}, address "tcp://host:port", or a Client
        "auto" (None): ``DASK_SCHEDULER_ADDRESS`` if set, else "serial" below
        ``SERIAL_BELOW`` steps and "local" (a LocalCluster, one process per core) above.
        Each task evaluates in one thread; the parallelism is Dask's processes.
    workers : int, optional
        Worker processes of the "local" cluster (default: one per core).
    chunk_steps : int
        Evaluated steps per task (a trajectory file is never split: a longer file is a task of
        its own per variant, streamed in ``STREAM_CHUNK`` steps).
    progress : bool, optional
        Progress bar with total and ETA on stderr (default: when stderr is a terminal).
    plots : bool
    on_chunk : callable (done, total), optional
        Called after each finished task is stored.

    Returns
    -------
    SweepResult
    """

    out = Path(out)
    p = plan(trajectories, workspace, platform, vary, tolerances, variants, seed, chunk_steps)
    if out.exists():
        meta = out / "sweep.json"
        if meta.exists() and json.loads(meta.read_text()).get("fingerprint") == p.fingerprint:
            return load(out)
        raise InputError(f"{out}: exists; remove it or choose another output folder")
    if not out.parent.is_dir():
        raise InputError(f"{out}: directory {str(out.parent)!r} does not exist")
    partial = out.with_name(out.name + ".partial")
    (partial / "chunks").mkdir(parents=True, exist_ok=True)
    merged: list = []          # the running fold, then the task envelopes not yet folded in
    done: set[int] = set()

    def absorb(frame) -> None:
        merged.append(frame)
        if len(merged) > MERGE_EVERY:
            merged[:] = [_reduce(merged)]

    for k, f in _finished(partial, p.fingerprint):
        if k < len(p.tasks):
            absorb(pd.read_parquet(f))
            done.add(k)
    (partial / "plan.json").write_text(json.dumps({"fingerprint": p.fingerprint,
                                                   "tasks": len(p.tasks)}))
    todo = [t for t in p.tasks if t.id not in done]
    steps_todo = sum(t.steps for t in todo)
    chosen = _resolve_scheduler(scheduler, steps_todo) if todo else "serial"
    if progress is None:
        progress = sys.stderr.isatty()

    bar = tqdm(total=p.steps, initial=p.steps - steps_todo, unit="step", unit_scale=True,
               desc="sweep", disable=not progress, file=sys.stderr)
    started = time.perf_counter()

    native.is_compiled()       # compile (or load) once here, before workers need the cache

    def finish(task, frame):
        _store(partial, task.id, frame)
        absorb(frame)
        done.add(task.id)
        bar.update(task.steps)
        if on_chunk is not None:
            on_chunk(len(done), len(p.tasks))

    try:
        if chosen == "serial":
            for task in todo:
                finish(task, run_task(task))
        elif todo:
            from distributed import as_completed

            client, cluster = _client(chosen, workers)
            try:
                # a bounded window of tasks in flight: the tasks' inputs (pose blocks,
                # platforms) are pickled as they are submitted, not all at once
                window = max(8, 4 * max(1, len(client.scheduler_info().get("workers", {}))))
                pending = iter(todo)
                by_key = {}

                def submit(task):
                    fut = client.submit(run_task, task, key=f"gsfric-sweep-{p.fingerprint}-"
                                        f"{task.id}", pure=False)
                    by_key[fut.key] = task
                    return fut

                queue = as_completed([submit(t) for t in itertools.islice(pending, window)],
                                     loop=client.loop, with_results=True)
                for fut, frame in queue:
                    finish(by_key.pop(fut.key), frame)
                    nxt = next(pending, None)
                    if nxt is not None:
                        queue.add(submit(nxt))
            finally:
                if cluster is not None:
                    client.close()
                    cluster.close()
    finally:
        bar.close()
    elapsed = time.perf_counter() - started
    envelopes = merge(merged)
    summary = summarize(envelopes)
    variants_table = pd.DataFrame(p.variants)
    limits = p.platform.limits
    exceeded = check_limits(envelopes, limits)
    envelopes.to_parquet(partial / "envelopes.parquet", index=False)
    summary.to_csv(partial / "summary.csv", index=False)
    variants_table.to_csv(partial / "variants.csv", index=False)
    if limits:
        exceeded.to_csv(partial / "limits.csv", index=False)
    info = {"fingerprint": p.fingerprint, "tasks": len(p.tasks), "steps": p.steps,
            "cases": int(envelopes.groupby(["motion", "variant"]).ngroups),
            "flagged": int(envelopes[(envelopes.quantity == "R_E") &
                                     (envelopes.leg == 1)].flagged.sum()),
            "computed_tasks": len(todo), "scheduler": str(chosen) if isinstance(chosen, str)
            else "client", "seconds": round(elapsed, 3), "limits": {k: v for k, v in
                                                                    limits.items()},
            "exceeding_cases": int(exceeded.groupby(["motion", "variant"]).ngroups)
            if len(exceeded) else 0, "inputs": p.inputs}
    if plots:
        plot(envelopes, summary, partial, limits, p.inputs.get("workspace"))
    shutil.rmtree(partial / "chunks")
    (partial / "plan.json").unlink()
    (partial / "sweep.json").write_text(json.dumps(info, indent=1, default=str))
    os.replace(partial, out)
    return SweepResult(out, envelopes, summary, variants_table, exceeded, info)


def load(out: str | os.PathLike) -> SweepResult:
    """Read a finished sweep's output folder back."""

    out = Path(out)
    info = json.loads((out / "sweep.json").read_text())
    envelopes = pd.read_parquet(out / "envelopes.parquet")
    exceeded = (pd.read_csv(out / "limits.csv") if (out / "limits.csv").exists()
                else check_limits(envelopes, {}))
    return SweepResult(out, envelopes, pd.read_csv(out / "summary.csv"),
                       pd.read_csv(out / "variants.csv"), exceeded, info)


# -- plots ------------------------------------------------------------------------------------


def plot(envelopes, summary, folder: Path, limits: Mapping, workspace: dict | None) -> None:
    """``envelope.png`` (each quantity per leg, all cases, limits) and ``locations.png``."""
    from matplotlib.figure import Figure  # no pyplot: leaves the caller's backend alone
    from matplotlib.patches import Rectangle

    shown = ["R_E", "R_C", "M_C", "R_3", "M_3", "F_max", "Ffr", "P_C", "W_C"]
    limit_of = {q: k for k, q in LIMIT_QUANTITY.items()}
    fig = Figure(figsize=(12, 9), layout="constrained")
    axes = fig.subplots(3, 3)
    legs = np.arange(1, 7)
    for ax, q in zip(axes.flat, shown):
        sub = envelopes[envelopes.quantity == q]
        kind, unit, meaning = QUANTITIES[q]
        if sub.value.notna().any():
            table = sub.pivot_table(index="leg", columns=["motion", "variant"], values="value")
            ax.plot(legs, table.to_numpy(), color="0.7", lw=0.8, marker=".", ms=3)
            best = summary[summary.quantity == q].sort_values("leg")
            ax.bar(legs, best.value, alpha=0.35, color="C0")
        if q == "F_max":
            fmin = envelopes[envelopes.quantity == "F_min"].groupby("leg").value.min()
            ax.bar(legs, fmin.reindex(legs), alpha=0.35, color="C1")
            ax.set_title("actuator force range")
            if "actuator_force" in limits:
                for v in limits["actuator_force"]:
                    ax.axhline(v, color="C3", ls="--")
        else:
            ax.set_title(meaning.replace(" (motions only)", ""), fontsize=9)
        if q in limit_of and limit_of[q] in limits:
            ax.axhline(limits[limit_of[q]], color="C3", ls="--", label="limit")
        ax.set_xlabel("leg")
        ax.set_ylabel(f"{q} [{unit}]")
    fig.suptitle("Load envelope per joint: bars = over all cases, grey = each case")
    fig.savefig(folder / "envelope.png", dpi=90)

    fig = Figure(figsize=(11, 4.5), layout="constrained")
    axes = fig.subplots(1, 2)
    for ax, (i, j) in zip(axes, (("x", "y"), ("x", "z"))):
        if workspace is not None:
            (x0, x1), (y0, y1) = workspace["pose"][i], workspace["pose"][j]
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ls=":",
                                       color="0.4", label="workspace"))
        for k, q in enumerate(["R_E", "R_C", "M_C", "R_3", "M_3", "F_max"]):
            best = summary[summary.quantity == q]
            ax.scatter(best[i], best[j], s=40, marker="os^v<>"[k], label=q, alpha=0.8)
            for _, r in best.iterrows():
                ax.annotate(str(int(r.leg)), (r[i], r[j]), fontsize=7)
        ax.set_xlabel(f"{i} [m]")
        ax.set_ylabel(f"{j} [m]")
        ax.autoscale()
    axes[0].legend(fontsize=7)
    fig.suptitle("Where each joint's largest load occurs (numbers: legs)")
    fig.savefig(folder / "locations.png", dpi=90)
