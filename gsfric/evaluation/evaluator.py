"""Evaluation of a platform over a motion: the reaction map, the friction map, both combined.

``Evaluator`` holds an immutable platform packed into the generated functions' parameter
vectors and calls the compiled functions; ``evaluate`` is the one-call form. Results are named
arrays with the step as the leading axis.

Step flags (bits of ``Result.flag``; 0 = sound step):

* 1 ``FLAG_NONFINITE``: a non-finite input or output value (outputs set to NaN);
* 2 ``FLAG_STROKE``: a leg length outside ``geometry.stroke``;
* 4 ``FLAG_SINGULAR``: the platform's 6x6 force Jacobian (columns ``(u_i, (E_i - p) x u_i)``)
  is near singular: its singularity measure ``h`` (output ``h``, derive/conditioning.py: the
  volume spanned by the legs' unit wrenches, moments in units of the platform's size, relative
  to orthogonal ones) is below ``SINGULAR_LIMIT = 2 / COND_LIMIT``. Unflagged steps are
  guaranteed a condition number below ``COND_LIMIT`` for that Jacobian with its moment rows
  divided by the platform's size and its columns scaled to unit length;
* 8 ``FLAG_UNIVERSAL``: a leg within ``UNIVERSAL_LIMIT`` of the direction of its universal
  joint's first axis (``1 - (u.a1)^2 < UNIVERSAL_LIMIT``), where the joint's torsion moment is
  undefined;
* 16 ``FLAG_COUPLING``: the coupled friction model's fixed point has not converged: the axial
  forces changed by more than ``COUPLING_TOLERANCE * (1 N + |F0|)`` over the last of its
  iterations (joint friction so large that it nearly locks the mechanism; docs/friction.md).

Every flag is computed in C in the same pass as the outputs (``compiled/batch.c``).

Detail outputs (``DETAILS``: R_3 and M_3 in the leg frames, the parts of the prismatic
friction, the bushings' normal forces, the coupled solve's last change) are not kept by the
evaluation: a Result computes them, all at once, in one more compiled pass over its motion the
first time one of them is read (``Result.arrays`` holds them from then on). The evaluation then
writes 229 of the 313 values per step (1.8 kB instead of 2.5 kB).

Memory: result arrays of 1 MiB and more are each on a mapping of whole huge pages of their
own; the memory of results the caller has dropped is kept (up to ``POOL_KEEP_BYTES``) and
reused by the next evaluation of the same size, which then neither faults pages in nor has the
kernel zero them (``release_memory()`` returns it to the system).

Concurrency: an ``Evaluator`` is immutable after construction (its parameter vectors are
read-only arrays) and every call works on its own buffers, so one Evaluator, or several, may be
called from any number of threads at once; the compiled code runs without the GIL. An output
buffer passed as ``out`` belongs to the call until it returns: do not share one between
concurrent calls.
"""

from __future__ import annotations

import ctypes
import functools
import math
import mmap
import os
import threading
import warnings
import weakref
from collections.abc import MutableMapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from tqdm import tqdm

from gsfric._checks import short
from gsfric.compiled import native
from gsfric.compiled.manifest import function, layout, manifest
from gsfric.errors import GsfricError, InputError, StepFlagError
from gsfric.evaluation.breakdown import parts as breakdown_parts
from gsfric.evaluation.columns import annotate, plan
from gsfric.evaluation.paper_constants import paper_constants as pc
from gsfric.io.readers import motion_from_frame
from gsfric.platform.catalog import GENERATED_EFFECTS, apply_sensor, sensor_parameters
from gsfric.platform.description import Platform
from gsfric.trajectory import Motion

FLAG_NONFINITE = 1
FLAG_STROKE = 2
FLAG_SINGULAR = 4
FLAG_UNIVERSAL = 8
FLAG_COUPLING = 16
FLAG_NAMES = {FLAG_NONFINITE: "non-finite value", FLAG_STROKE: "leg length outside the stroke",
              FLAG_SINGULAR: "near-singular platform Jacobian",
              FLAG_UNIVERSAL: "leg near its universal joint's first axis",
              FLAG_COUPLING: "coupled friction solve not converged"}
COUPLING_TOLERANCE = 1e-6
COND_LIMIT = 1e6
SINGULAR_LIMIT = 2.0 / COND_LIMIT
UNIVERSAL_LIMIT = 1e-4

JOINT_EPS = 1e-4       # rad/s, regularisation of the joints' sign function
PRISMATIC_EPS = 1e-5   # m/s, regularisation of the prismatic sign function
PRISMATIC_POINT = 0.5  # prismatic joint point, fraction of D from C_i (the paper's zone 3)

MODES = ("kinematic", "paper")
CHUNK = 200_000

DETAILS = ("R_3_leg", "M_3_leg", "coupling_change", "Ffr_viscous", "Ffr_coulomb",
           "Ffr_bushing", "Ffr_seal", "Ffr_effects", "N_bushing")
"""Outputs computed on first access (see the module's docstring): copies of other outputs in
another frame, and the parts of sums that are kept (``Ffr``)."""

def state_array(motion: Motion) -> np.ndarray:
    """The generated functions' state input, (N, 24): p, T (row-major), v, omega, a, alpha.

    Laid out by ``native.state_of``, the one Python layout of the states (the compiled code
    lays them out itself, block by block, in ``compiled/batch.c``).
    """
    return native.state_of((motion.position, motion.rotation, motion.velocity, motion.omega,
                            motion.acceleration, motion.alpha))


MODEL_FUNCTIONS = {"coupled": "coupled", "paper": "posthoc"}
"""Suffix of the generated functions derived with the platform's friction model fixed
(derive/build.py, ``FIXED_MODELS``): the paper's model then has no fixed-point iterations."""

@functools.lru_cache(maxsize=None)
def model_function(name: str, model: str | None) -> str:
    """The generated function to run for ``name`` ("eval", "actuator") on a platform whose
    friction model is ``model`` ("coupled", "paper"; None: read from P at every step): the
    function derived with that model fixed, or the generic one."""
    suffix = MODEL_FUNCTIONS.get(model)
    if suffix is None:
        return name
    try:
        function(f"{name}_{suffix}")
    except GsfricError:  # generated/ without the fixed-model functions
        return name
    return f"{name}_{suffix}"


def _uniform_model(P: np.ndarray) -> str | None:
    """The friction model of every row of a per-step parameter input P (N, size), or None
    when the rows differ."""
    _, slots = _slots("eval", "P")
    column = next(start for name, start, _ in slots if name == "friction_model")
    values = np.asarray(P)[..., column]
    first = float(values.flat[0]) if values.size else 1.0
    if first not in (0.0, 1.0) or np.any(values != first):
        return None
    return "coupled" if first == 1.0 else "paper"


@functools.lru_cache(maxsize=None)
def _slots(function_name: str, input_name: str) -> tuple:
    """(size, ((name, start, stop), ...)) of an input's layout."""
    blocks = layout(function_name, input_name)
    slots = tuple((b["name"], b["offset"], b["offset"] + math.prod(b["shape"])) for b in blocks)
    return max(stop for _, _, stop in slots), slots


def _pack(slots: tuple, values: dict) -> np.ndarray:
    """The named values laid out in one input vector (zeros in any gap of the layout)."""
    size, where = slots
    out = np.zeros(size)
    for name, start, stop in where:
        out[start:stop] = np.ravel(values[name])
    return out


def parameter_values(platform: Platform) -> dict[str, object]:
    """The platform as the named blocks of the parameter input P (see the manifest's layout)."""
    g, b, legs, fr = platform.geometry, platform.platform, platform.legs, platform.friction
    l4, k4, l2, k2 = legs.com_placement()
    return dict(
        gravity=platform.gravity, base_joints=g.base_joints, platform_joints=g.platform_joints,
        universal_axes=g.universal_axes, platform_mass=b.mass, platform_inertia=b.inertia,
        platform_com=b.com, payload_mass=b.payload_mass, payload_inertia=b.payload_inertia,
        payload_com=b.payload_com, lower_mass=legs.lower_mass, lower_com=l4, lower_frac=k4,
        lower_inertia=legs.lower_inertia, upper_mass=legs.upper_mass, upper_com=l2,
        upper_frac=k2, upper_inertia=legs.upper_inertia, leg_weight=float(legs.weight),
        prismatic_point=PRISMATIC_POINT, joint_viscous=fr.joint_viscous,
        joint_coulomb=fr.joint_coulomb, joint_radius=fr.joint_radius,
        prismatic_viscous=fr.prismatic_viscous, prismatic_coulomb=fr.prismatic_coulomb,
        joint_eps=JOINT_EPS, prismatic_eps=PRISMATIC_EPS,
        friction_model=float(fr.model == "coupled"), bushing_offset=fr.bushing_offset,
        bushing_spacing=fr.bushing_spacing, prismatic_seal=fr.prismatic_seal)


def parameter_vector(platform: Platform) -> np.ndarray:
    """The platform packed into the generated functions' parameter input P."""
    return _pack(_slots("eval", "P"), parameter_values(platform))


def effect_vector(platform: Platform) -> np.ndarray:
    """The platform's effects packed into the effect-parameter input Q (defaults elsewhere).

    Sensor effects (``gsfric.catalog.SENSOR_EFFECTS``) are not inputs of the compiled code:
    ``Evaluator.evaluate`` applies them to F.
    """

    values = []
    for name, params in GENERATED_EFFECTS.items():
        given = platform.effects.get(name, {})
        values += [float(given.get(p, default)) for p, default in params.items()]
    return np.array(values)


_PACKED: dict[int, tuple] = {}


def _packed(platform: Platform) -> tuple[np.ndarray, np.ndarray, dict]:
    """P and Q of a platform, read-only, packed once per platform object (platforms are
    immutable) and shared by its Evaluators; and a dict, shared too, of the control loop's
    bound calls on them (filled on first use: building one costs more than a call)."""
    hit = _PACKED.get(id(platform))
    if hit is not None and hit[0]() is platform:
        return hit[1], hit[2], hit[3]
    P, Q = parameter_vector(platform), effect_vector(platform)
    P.flags.writeable = False
    Q.flags.writeable = False
    key = id(platform)
    try:
        ref = weakref.ref(platform, lambda _, key=key: _PACKED.pop(key, None))
    except TypeError:  # not weakly referable: not cached
        return P, Q, {}
    calls: dict = {}
    _PACKED[key] = (ref, P, Q, calls)
    return P, Q, calls


class Outputs(MutableMapping):
    """The named arrays of a Result: those the evaluation kept and, on first access to any of
    them, the detail outputs (``DETAILS``), computed together in one more compiled pass over
    the motion (non-finite steps NaN, as in the first pass). Iteration lists both (the kept
    ones first); ``kept()`` gives the arrays held now, without computing.
    """

    def __init__(self, arrays: dict, later: tuple | None = None) -> None:
        self._arrays = dict(arrays)
        # (platform, mode, paper constants, motion, flag, names) of the details still to come
        self._later = later

    def _pending(self) -> tuple:
        return () if self._later is None else self._later[-1]

    def __getitem__(self, key):
        try:
            return self._arrays[key]
        except KeyError:
            if key not in self._pending():
                raise
        platform, mode, constants, threads, motion, flag, names = self._later
        evaluator = Evaluator(platform, mode=mode, paper_constants=constants, n_threads=threads)
        self._arrays.update(evaluator.details(motion, names, flag))
        self._later = None
        return self._arrays[key]

    def __setitem__(self, key, value) -> None:
        self._arrays[key] = value

    def __delitem__(self, key) -> None:
        if key in self._pending():
            self[key]
        del self._arrays[key]

    def __iter__(self):
        yield from self._arrays
        yield from (k for k in self._pending() if k not in self._arrays)

    def __len__(self) -> int:
        return len(self._arrays) + sum(k not in self._arrays for k in self._pending())

    def __contains__(self, key) -> bool:
        return key in self._arrays or key in self._pending()

    def kept(self) -> dict[str, np.ndarray]:
        """The arrays held now (no computation)."""
        return dict(self._arrays)


@dataclass
class Result:
    """Named arrays of one evaluation, step as the leading axis.

    Attributes (shapes for N steps; units SI): ``t`` (N,), ``F``, ``F0`` (N, 6) N;
    ``R_E``, ``R_C``, ``R_3`` (N, 6, 3) N; ``M_C`` (N, 6) N m; ``M_3`` (N, 6, 3) N m;
    ``MfrE``, ``MfrC`` (N, 6, 3) N m; ``Ffr`` (N, 6) N; the paper's signed scalars ``MfrE_s``,
    ``MfrC_s`` (N, 6) N m and ``Ffr_s`` (N, 6) N; ``D``, ``D_dot`` (N, 6); ``u``, ``omega_leg``,
    ``omega_rel``, ``R_3_leg``, ``M_3_leg`` (N, 6, 3); ``s2`` (N, 6); ``flag`` (N,) int.
    See the manifest for every output's description.
    """

    t: np.ndarray
    arrays: dict[str, np.ndarray]
    flag: np.ndarray
    mode: str = "kinematic"
    notes: list[str] = field(default_factory=list)
    source: tuple | None = field(default=None, repr=False)   # (platform, motion) evaluated

    def breakdown(self) -> dict[str, np.ndarray]:
        """F per leg split into inertia, gravity, payload, joint friction carried, prismatic
        friction by kind and effects, (N, 6) N each (``gsfric.evaluation.breakdown``; kinematic mode)."""
        if self.source is None or self.mode != "kinematic":
            raise GsfricError("breakdown: needs a kinematic-mode result of Evaluator.evaluate")
        platform, motion = self.source
        return breakdown_parts(self, _evaluate_quietly, platform, motion)

    def __getattr__(self, name):
        arrays = self.__dict__.get("arrays", {})
        if name in arrays:
            return arrays[name]
        raise AttributeError(name)

    def __len__(self) -> int:
        return len(self.t)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(self.__dict__.get("arrays", {})))

    def __repr__(self) -> str:
        n = len(self.t)
        span = f"t = {self.t[0]:.6g}..{self.t[-1]:.6g} s" if n else "no steps"
        flagged = int(np.count_nonzero(self.flag))
        names = ", ".join(sorted(self.arrays))
        return (f"<Result: {n} steps, {span}, mode {self.mode!r}, {flagged} flagged; "
                f"arrays {names}>")

    def flagged(self) -> np.ndarray:
        """Indices of the steps with a non-zero flag."""
        return np.flatnonzero(self.flag)

    def to_legs_frame(self):
        """Per-joint values as a DataFrame indexed by (step, leg), leg 1..6.

        Columns: every per-leg array of the result, a vector ``(N, 6, 3)`` as three columns
        ``name_x, name_y, name_z`` (base frame), a scalar ``(N, 6)`` as one column; plus ``t``.
        ``attrs["units"]`` holds each column's unit (from the manifest).

        Returns
        -------
        pandas.DataFrame
            6 N rows, MultiIndex levels ``step`` (0..N-1) and ``leg`` (1..6).
        """

        n = len(self.t)
        index = pd.MultiIndex.from_product([np.arange(n), np.arange(1, 7)],
                                           names=["step", "leg"])
        known = {o["name"]: o.get("unit", "") for o in function("eval")["outputs"]}
        cols: dict[str, np.ndarray] = {"t": np.repeat(self.t, 6)}
        units = {"t": "s"}
        for name, values in self.arrays.items():
            if values.shape[1:2] != (6,):
                continue
            if values.ndim == 2:
                cols[name] = values.reshape(-1)
                units[name] = known.get(name, "")
            elif values.ndim == 3 and values.shape[2] == 3:
                for j, axis in enumerate("xyz"):
                    cols[f"{name}_{axis}"] = values[:, :, j].reshape(-1)
                    units[f"{name}_{axis}"] = known.get(name, "")
        frame = pd.DataFrame(cols, index=index)
        frame.attrs["units"] = units
        return frame

    def to_xarray(self):
        """The per-joint values as an ``xarray.Dataset`` (dims ``step``, ``leg``); needs xarray.

        The variables and units (``attrs["units"]`` of each) of ``to_legs_frame``.
        """
        try:
            import xarray  # noqa: F401
        except ModuleNotFoundError:
            raise GsfricError("Result.to_xarray needs xarray (pip install xarray); "
                              "Result.to_legs_frame gives the same as a DataFrame") from None
        frame = self.to_legs_frame()
        data = frame.to_xarray()
        for name, unit in frame.attrs["units"].items():
            data[name].attrs["units"] = unit
        return data

    def to_frame(self):
        """A pandas DataFrame with the columns of ``gsfric simulate``, one row per step.

        ``attrs["units"]`` maps every column to its unit and ``attrs["descriptions"]`` to its
        meaning and sign convention (``gsfric.columns``; ``gsfric columns`` lists them).
        """

        n = len(self.t)
        cols = {"t": self.t}
        for column, key, index, _ in plan():
            values = self.arrays.get(key)
            if values is not None:
                cols[column] = values.reshape(n, -1)[:, index]
        cols["flag"] = self.flag
        return annotate(pd.DataFrame(cols))


class Evaluator:
    """A compiled evaluator of one platform; owns its packed parameters.

    Parameters
    ----------
    platform : Platform
    mode : {"kinematic", "paper"}
        "kinematic": every acceleration from the motion; "paper": the paper's constant
        accelerations and joint speed (``paper_constants``) instead.
    n_threads : int
        Threads for long evaluations (POSIX threads created per call, at least 2048 steps each).
    paper_constants : ndarray (13,), optional
        Paper mode's constants (default ``gsfric.evaluation.paper_constants.paper_constants()``).
    """

    def __init__(self, platform: Platform, mode: str = "kinematic", n_threads: int = 1,
                 paper_constants=None) -> None:
        if mode not in MODES:
            raise InputError(f"mode: unknown mode {mode!r}; expected one of {', '.join(MODES)}")
        self.platform = platform
        self.mode = mode
        self.n_threads = int(n_threads)
        self.P, self.Q, self._calls = _packed(platform)
        self.K = None
        if mode == "paper":

            self.K = np.array(pc() if paper_constants is None else paper_constants, float)
            self.K.flags.writeable = False
        model = platform.friction.model
        self._actuator = model_function("actuator", model)
        self._full = native.get("eval_paper" if mode == "paper"
                                else model_function("eval", model))
        self._stroke = platform.geometry.stroke
        self._flag_spec = None

    # -- hot paths -------------------------------------------------------------
    def actuator_forces(self, x: np.ndarray, out: np.ndarray | None = None, P=None,
                        Q=None) -> np.ndarray:
        """Actuator forces with friction, (N, 6) N, for states x (N, 24) (``state_array``).

        ``P`` and ``Q`` may be given per step, (N, size), to vary parameters along the batch.
        No flags, no checks beyond shapes: the control loop's call.
        """
        if self.mode != "kinematic":
            raise GsfricError("actuator_forces is the kinematic mode's hot path")
        if P is None and Q is None and out is not None:
            key = ("actuator", self.n_threads)
            actuator = self._calls.get(key)
            if actuator is None:  # two threads may both build one: either is right
                actuator = self._calls[key] = native.get(self._actuator).bound(
                    [self.P, self.Q], "F", self.n_threads)
            return actuator(x, out)
        f = native.get(self._actuator if P is None
                       else model_function("actuator", _uniform_model(P)))
        res = f([x, self.P if P is None else P, self.Q if Q is None else Q],
                None if out is None else {"F": out}, self.n_threads)
        return res["F"]

    def forces(self, position, rotation, velocity, omega, acceleration, alpha,
               out: np.ndarray | None = None) -> np.ndarray:
        """Actuator forces with friction, (N, 6) N, from the motion's arrays directly.

        Parameters
        ----------
        position, velocity, acceleration : ndarray (N, 3)
            Platform frame origin in the base frame, m, m/s, m/s^2.
        rotation : ndarray (N, 3, 3)
            Platform to base rotation matrices.
        omega, alpha : ndarray (N, 3)
            Platform angular velocity and acceleration, base frame, rad/s, rad/s^2.
        out : ndarray (N, 6), optional
            C-contiguous float64 buffer for the result.

        The states are laid out in C, block by block (no ``state_array``); no flags.
        """
        if self.mode != "kinematic":
            raise GsfricError("forces is the kinematic mode's hot path")
        key = ("forces", self.n_threads)
        call = self._calls.get(key)
        if call is None:  # two threads may both build one: either is right
            call = self._calls[key] = native.get(self._actuator).bound_motion(
                [self.P, self.Q], "F", self.n_threads)
        return call(position, rotation, velocity, omega, acceleration, alpha, out)

    def jacobian(self, x: np.ndarray, Q=None) -> tuple[np.ndarray, np.ndarray]:
        """F (N, 6) and dF/dtheta (N, 6, n_theta); theta names in ``jacobian_parameters()``."""
        res = native.get("jacobian")([x, self.P, self.Q if Q is None else Q], None,
                                     self.n_threads)
        n = x.shape[0]
        # CasADi stores the (6, n_theta) Jacobian column-major
        return res["F"], res["dF"].reshape(n, -1, 6).transpose(0, 2, 1)

    # -- full evaluation -------------------------------------------------------------
    def evaluate(self, motion: Motion, strict: bool = False, progress: bool = False,
                 chunk: int = CHUNK) -> Result:
        """Every output at every step of ``motion``, with step flags.

        Parameters
        ----------
        motion : Motion
        strict : bool
            Raise StepFlagError instead of warning when steps are flagged.
        progress : bool
            Show a progress bar (tqdm) over chunks.
        chunk : int
            Steps per call to the compiled code (bounds the temporary memory).
        """
        result = self.evaluate_quiet(motion, progress=progress, chunk=chunk)
        n, flag = len(result), result.flag
        bad = result.flagged()
        if bad.size:
            kinds = sorted({FLAG_NAMES[b] for b in FLAG_NAMES if np.any(flag & b)})
            msg = (f"{bad.size} of {n} steps flagged ({'; '.join(kinds)}): steps "
                   f"{_index_list(bad)}")
            if strict:
                raise StepFlagError(msg)
            warnings.warn(msg, stacklevel=2)
        return result

    def evaluate_quiet(self, motion: Motion, progress: bool = False, chunk: int = CHUNK,
                       buffers: dict | None = None, sensor: bool = True) -> Result:
        """``evaluate`` without reporting the flagged steps (no warning, no error).

        ``buffers`` (a dict, filled on first use) lends the output arrays: a caller that
        evaluates chunk after chunk passes the same dict and reuses the memory; the Result's
        arrays are then views into it, valid until the next call with it. ``sensor=False``
        leaves F as the mechanism's (no sensor effects): for a caller that applies them
        over a longer record than this motion (``gsfric.stream``).
        """
        n = len(motion)
        if int(chunk) < 1:
            raise InputError(f"chunk: must be a positive number of steps, got {chunk!r}")
        details = [name for name, _, _ in self._full.outputs if name in DETAILS]
        kept = [(name, size) for name, size, _ in self._full.outputs if name not in DETAILS]
        if buffers is None:
            outs = {name: _aligned_empty(n, size) for name, size in kept}
        else:
            outs = {}
            for name, size in kept:
                buf = buffers.get(name)
                if buf is None or buf.shape[0] < n:
                    buf = buffers[name] = _aligned_empty(n, size)
                outs[name] = buf[:n]
        flag = np.empty(n, dtype=np.int64)
        starts = range(0, n, chunk)
        if progress and n > chunk:

            starts = tqdm(starts, total=(n + chunk - 1) // chunk, unit="chunk",
                          desc="evaluating")
        for s in starts:
            e = min(n, s + chunk)
            self._run(motion, s, e, {k: v[s:e] for k, v in outs.items()}, flag[s:e])
        shapes = {name: shape for name, _, shape in self._full.outputs}
        arrays = {k: v.reshape((n,) + tuple(shapes[k])) for k, v in outs.items()}
        if sensor:
            self._apply_sensor(np.asarray(motion.t, float), arrays, flag)
        # what the detail pass needs, picklable (a Result travels between processes)
        later = (self.platform, self.mode, self.K, self.n_threads, motion, flag, tuple(details))
        return Result(t=np.asarray(motion.t, float), arrays=Outputs(arrays, later), flag=flag,
                      mode=self.mode, source=(self.platform, motion))

    def _inputs(self) -> list:
        return [self.P, self.Q] + ([self.K] if self.K is not None else [])

    def _run(self, motion: Motion, s: int, e: int, view: dict,
             flag: np.ndarray | None = None) -> None:
        """Steps s..e-1 of ``motion`` into the output views and, given ``flag``, the step
        flags (non-finite steps' outputs NaN)."""
        m = motion
        parts = (m.position[s:e], m.rotation[s:e], m.velocity[s:e], m.omega[s:e],
                 m.acceleration[s:e], m.alpha[s:e])
        if native.is_compiled():
            self._full([None] + self._inputs(), view, self.n_threads, select=view,
                       flags=None if flag is None else self.flag_spec(), flag=flag,
                       motion=parts)
            return
        xs = native.state_of(parts)
        every = self._full([xs] + self._inputs(), None, self.n_threads,
                           select=view if flag is None else None)
        if flag is not None:
            flag[:] = self._flags(xs, every)
        for k, v in view.items():
            v[...] = every[k]

    def details(self, motion: Motion, names, flag: np.ndarray) -> dict[str, np.ndarray]:
        """The outputs ``names`` at every step of ``motion`` (flags as computed with the kept
        outputs: NaN at the non-finite steps), (N, ...) each; what ``Result`` computes on
        first access to a detail output."""
        n = len(motion)
        shapes = {name: (size, shape) for name, size, shape in self._full.outputs}
        outs = {name: np.empty((n, shapes[name][0])) for name in names}
        for s in range(0, n, CHUNK):
            e = min(n, s + CHUNK)
            self._run(motion, s, e, {k: v[s:e] for k, v in outs.items()})
        bad = (flag & FLAG_NONFINITE) != 0
        for v in outs.values():
            v[bad] = np.nan
        return {k: v.reshape((n,) + tuple(shapes[k][1])) for k, v in outs.items()}

    def flag_spec(self) -> "native.FlagSpec":
        """The settings of the step flags computed in C (read-only, shared by calls)."""
        spec = self._flag_spec
        if spec is None:
            index = {name: k for k, (name, _, _) in enumerate(self._full.outputs)}
            lo, hi = self._stroke if self._stroke is not None else (0.0, 0.0)
            spec = self._flag_spec = native.FlagSpec(
                index["D"], index["s2"], index["h"], self._stroke is not None, lo, hi,
                UNIVERSAL_LIMIT, SINGULAR_LIMIT, 24, index.get("coupling_change", -1),
                index.get("F0", -1), COUPLING_TOLERANCE)
        return spec

    def _apply_sensor(self, t: np.ndarray, arrays: dict, flag: np.ndarray) -> None:
        """Sensor effects (force_scale, time_offset: gsfric.catalog) on F, what a load cell
        reads; the reactions stay those of the mechanism. A delay interpolates between the
        steps with finite values only, so a non-finite step stays NaN and spreads nowhere."""

        gains, delay = sensor_parameters(self.platform.effects)
        if delay == 0.0 and not np.any(gains != 0.0):
            return
        good = (flag & FLAG_NONFINITE) == 0
        if good.all():
            arrays["F"] = apply_sensor(t, arrays["F"], gains, delay)
            return
        out = np.full_like(arrays["F"], np.nan)
        if good.any():
            out[good] = apply_sensor(t[good], arrays["F"][good], gains, delay)
        arrays["F"] = out

    def _flags(self, x, arrays) -> np.ndarray:
        """The flags of ``compiled/batch.c`` in NumPy, for the CasADi fallback (no compiler)."""
        n = x.shape[0]
        flag = np.zeros(n, dtype=np.int64)
        finite = np.isfinite(x).all(axis=1)
        for v in arrays.values():
            finite &= np.isfinite(v.reshape(n, -1)).all(axis=1)
        D = arrays["D"]
        if self._stroke is not None:
            lo, hi = self._stroke
            flag[((D < lo) | (D > hi)).any(axis=1)] |= FLAG_STROKE
        flag[(arrays["s2"] < UNIVERSAL_LIMIT).any(axis=1)] |= FLAG_UNIVERSAL
        flag[arrays["h"][:, 0] < SINGULAR_LIMIT] |= FLAG_SINGULAR
        if "coupling_change" in arrays:
            limit = COUPLING_TOLERANCE * (1.0 + np.abs(arrays["F0"]))
            flag[(finite & (np.abs(arrays["coupling_change"]) > limit).any(axis=1))] |= \
                FLAG_COUPLING
        flag[~finite] |= FLAG_NONFINITE
        for v in arrays.values():
            v[~finite] = np.nan
        return flag


HUGE_PAGE = 1 << 21
"""Bytes of a transparent huge page (x86-64, arm64 with 4 kB pages)."""
POOL_MIN_BYTES = 1 << 20
"""Result arrays from this size up are taken from ``_POOL`` (smaller ones from NumPy)."""
POOL_KEEP_BYTES = 512 << 20
"""At most this much memory of dropped results is kept for the next evaluations."""

class _BlockPool:
    """Memory for large result arrays: anonymous mappings, rounded up to whole huge pages
    (``HUGE_PAGE``, 2 MiB, advised ``MADV_HUGEPAGE``: one page fault per 2 MiB instead of per
    4 kB) from 2 MiB up and to whole pages below; and the blocks of results the caller has
    dropped, kept (up to ``POOL_KEEP_BYTES``) for the next evaluation of the same rounded
    size, which then writes into memory that is already mapped: no page faults, no zeroing by
    the kernel (about 200 ns of every step's 1.8 kB otherwise).

    An array handed out is the caller's alone: its block comes back only when the array and
    every view of it are gone (a ``weakref.finalize`` on the buffer object they all keep
    alive). Thread-safe: one lock guards the free lists (keyed by length) and the count of
    kept bytes. A returning block never waits for it: the finalizer may run inside ``take``
    while this thread holds the lock (a garbage collection there), so when the lock is taken
    the block is not kept but unmapped with its last reference."""

    def __init__(self, keep: int) -> None:
        self.keep = keep
        self._free: dict[int, list] = {}
        self._kept = 0
        self._new_lock()
        if hasattr(os, "register_at_fork"):   # a fork while another thread holds the lock
            os.register_at_fork(after_in_child=self._new_lock)

    def _new_lock(self) -> None:
        self._lock = threading.Lock()

    @staticmethod
    def _length(nbytes: int) -> int:
        unit = HUGE_PAGE if nbytes >= HUGE_PAGE else mmap.PAGESIZE
        return -(-nbytes // unit) * unit

    def take(self, nbytes: int):
        """A mapping of at least ``nbytes`` bytes, page-aligned, not in use."""
        length = self._length(max(nbytes, 1))
        with self._lock:
            blocks = self._free.get(length)
            if blocks:
                block = blocks.pop()
                self._kept -= length
                return block
        block = mmap.mmap(-1, length, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
        if length >= HUGE_PAGE and hasattr(mmap, "MADV_HUGEPAGE"):
            try:
                block.madvise(mmap.MADV_HUGEPAGE)
            except OSError:  # a kernel without transparent huge pages
                pass
        return block

    def give(self, block) -> None:
        """Keep a block whose arrays are all gone, if there is room (else it is unmapped)."""
        if not self._lock.acquire(blocking=False):
            return
        try:
            if self._kept + len(block) <= self.keep:
                self._free.setdefault(len(block), []).append(block)
                self._kept += len(block)
        finally:
            self._lock.release()

    def clear(self) -> None:
        """Unmap every kept block."""
        with self._lock:
            self._free.clear()
            self._kept = 0

    def empty(self, n: int, size: int) -> np.ndarray:
        """An uninitialised C-contiguous float64 array (n, size) on a block of its own."""
        nbytes = n * size * 8
        block = self.take(nbytes)
        owner = (ctypes.c_char * nbytes).from_buffer(block)
        weakref.finalize(owner, self.give, block).atexit = False
        return np.frombuffer(owner, dtype=np.float64).reshape(n, size)


_POOL = _BlockPool(POOL_KEEP_BYTES)
_ANONYMOUS = hasattr(mmap, "MAP_ANONYMOUS")   # POSIX anonymous mappings (not on Windows)


def release_memory() -> None:
    """Return to the system the memory of dropped results that evaluations keep for reuse
    (at most ``POOL_KEEP_BYTES``)."""
    _POOL.clear()


def _aligned_empty(n: int, size: int) -> np.ndarray:
    """An uninitialised C-contiguous float64 array (n, size) whose data starts on a 64-byte
    boundary (a cache line): the compiled code then writes whole lines of it with vector
    non-temporal stores (derive/simd.py). Large ones (``POOL_MIN_BYTES``) on page-aligned
    blocks of ``_POOL``; small ones a view of a slightly larger NumPy buffer."""
    count = n * size
    if count * 8 >= POOL_MIN_BYTES and _ANONYMOUS:
        return _POOL.empty(n, size)
    raw = np.empty(count + 8)
    start = (-raw.ctypes.data % 64) // 8
    return raw[start:start + count].reshape(n, size)


def _index_list(idx: np.ndarray, limit: int = 10) -> str:
    shown = ", ".join(str(i) for i in idx[:limit])
    return shown + (f", ... ({idx.size - limit} more)" if idx.size > limit else "")


def jacobian_parameters() -> list[str]:
    """Names of the Jacobian's parameters: friction coefficients, masses, then every effect's."""

    return list(manifest()["jacobian_parameters"])


def evaluate(platform: Platform, motion, mode: str = "kinematic", **kwargs) -> Result:
    """Reaction forces and friction in every joint of ``platform`` over a motion.

    Parameters
    ----------
    platform : Platform
        E.g. ``gsfric.reference_platform()`` or ``Platform.from_toml(path)``.
    motion : Motion or pandas.DataFrame
        N steps. A DataFrame holds samples with the columns of a trajectory file (``t, x, y,
        z`` in s and m with ``alpha, beta, gamma`` in rad, ``qw, qx, qy, qz`` or ``roll,
        pitch, yaw``); it is differentiated as ``gsfric.io.read_trajectory`` does.
    mode : {"kinematic", "paper"}
        "kinematic": accelerations from the motion; "paper": the paper's constants.
    **kwargs
        ``strict``, ``progress``, ``chunk`` of ``Evaluator.evaluate``; for a DataFrame also
        ``window``, ``polyorder`` and ``log_format`` (``gsfric.io.motion_from_frame``).

    Returns
    -------
    Result
        Arrays with the step as the leading axis, SI units, base frame: ``F`` (N, 6) N,
        ``R_E`` (N, 6, 3) N, ... (see ``Result``); ``result.to_frame()`` for a table with units.

    Raises
    ------
    InputError
        A DataFrame with missing or bad columns (one line naming the row and column);
        ``chunk`` not an integer >= 1.
    TypeError
        ``platform`` is not a Platform or ``motion`` not a Motion or DataFrame (swapped
        arguments, None, a NumPy array), in one line saying what to give.
    StepFlagError
        ``strict=True`` and a flagged step.

    Examples
    --------
    >>> import numpy as np, gsfric
    >>> result = gsfric.evaluate(gsfric.reference_platform(),
    ...                          gsfric.models.sinusoidal(np.linspace(0, 1, 101)))
    >>> result.F.shape, result.R_E.shape
    ((101, 6), (101, 6, 3))
    """
    if isinstance(motion, pd.DataFrame):

        reading = {k: kwargs.pop(k) for k in ("window", "polyorder", "log_format")
                   if k in kwargs}
        motion = motion_from_frame(motion, **reading)

    evaluation_arguments(platform, motion, kwargs.get("chunk", 1))
    return Evaluator(platform, mode=mode).evaluate(motion, **kwargs)


def _kind(value: object) -> str:
    if isinstance(value, np.ndarray):
        return f"a NumPy array of shape {value.shape}"
    return "None" if value is None else f"a {type(value).__module__}.{type(value).__name__}"


def evaluation_arguments(platform: object, motion: object, chunk: object = 1) -> None:
    """The checks of ``gsfric.evaluate(platform, motion, chunk=...)``, each one line.

    Raises
    ------
    TypeError
        ``platform`` not a ``Platform`` or ``motion`` not a ``Motion`` (naming what was given,
        and saying so when the two are swapped).
    InputError
        ``chunk`` not an integer >= 1.
    """

    if isinstance(platform, Motion) and isinstance(motion, Platform):
        raise TypeError("evaluate(platform, motion): the arguments are swapped; give the "
                        "Platform first, then the Motion")
    if not isinstance(platform, Platform):
        raise TypeError(f"evaluate: platform must be a gsfric.Platform, got {_kind(platform)} "
                        "(gsfric.reference_platform() or Platform.from_toml(path))")
    if not isinstance(motion, Motion):
        hint = ("; for states (N, 24) use Evaluator.actuator_forces, for samples "
                "Motion.from_samples") if isinstance(motion, np.ndarray) else \
            " (Motion.from_samples, Motion.from_arrays or gsfric.io.read_trajectory)"
        raise TypeError(f"evaluate: motion must be a gsfric.Motion or a pandas DataFrame of "
                        f"trajectory columns, got {_kind(motion)}{hint}")
    if isinstance(chunk, (bool, np.bool_)) or not isinstance(chunk, (int, np.integer)) \
            or chunk < 1:
        raise InputError(f"chunk: must be an integer >= 1 (steps per call), got {short(chunk)}")


def _evaluate_quietly(platform: Platform, motion: Motion) -> Result:
    """The evaluation of a breakdown's platform variant: its flags are the full evaluation's
    to report."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Evaluator(platform).evaluate(motion)


def breakdown(platform: Platform, motion: Motion) -> dict[str, np.ndarray]:
    """The actuator forces of ``platform`` along ``motion`` split into their parts
    (``Result.breakdown``), without reporting the step flags: ``PARTS`` name -> (N, 6) N, and
    ``F`` (N, 6) N, their sum (``gsfric.evaluation.breakdown``)."""
    return _evaluate_quietly(platform, motion).breakdown()


def evaluate_outputs(evaluator: Evaluator, motion: Motion, names, buffers: dict | None = None,
                     sensor: bool = True) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Only the outputs ``names`` of ``motion`` and its step flags, as
    ``Evaluator.evaluate_quiet`` computes them, without a Result.

    For a caller that writes a few outputs at every step (``gsfric.stream``): the compiled
    code stores only those (the ones the flags read are computed all the same), about an
    eighth less time than every output for the 7 of ``simulate``'s default columns.

    Parameters
    ----------
    evaluator : Evaluator
    motion : Motion
        N steps.
    names : iterable of str
        Output names (``Result`` arrays, e.g. "F", "R_E"; not the detail outputs).
    buffers : dict, optional
        Lends the output arrays from call to call (filled on first use): the arrays returned
        are then views into it, valid until the next call with it.
    sensor : bool
        Apply the sensor's effects to F (when "F" is among ``names``).

    Returns
    -------
    (dict of name -> ndarray (N, size), ndarray (N,) int64)
        Each output flat per step (R_E: (N, 18), leg i's x, y, z at 3 (i - 1) + 0, 1, 2)
        and the flags (``FLAG_NAMES``); a non-finite step's outputs are NaN.
    """
    n = len(motion)
    sizes = {name: size for name, size, _ in evaluator._full.outputs}
    outs: dict[str, np.ndarray] = {}
    for name in dict.fromkeys(names):
        buf = None if buffers is None else buffers.get(name)
        if buf is None or buf.shape[0] < n:
            buf = np.empty((n, sizes[name]))
            if buffers is not None:
                buffers[name] = buf
        outs[name] = buf[:n]
    flag = np.empty(n, dtype=np.int64)
    evaluator._run(motion, 0, n, outs, flag)
    if sensor and "F" in outs:
        evaluator._apply_sensor(np.asarray(motion.t, float), outs, flag)
    return outs, flag
