"""Evaluation of a platform over a motion: the reaction map, the friction map, both combined.

``Evaluator`` holds an immutable platform packed into the generated functions' parameter
vectors (``gsfric.evaluation.parameters``) and calls the compiled functions; ``evaluate`` is the
one-call form. Results (``gsfric.evaluation.result``) are named arrays with the step as the
leading axis, with the step flags of ``gsfric.evaluation.flags``; their large arrays live on
the reused memory of ``gsfric.evaluation.memory``.

Concurrency: an ``Evaluator`` is immutable after construction (its parameter vectors are
read-only arrays) and every call works on its own buffers, so one Evaluator, or several, may be
called from any number of threads at once; the compiled code runs without the GIL. An output
buffer passed as ``out`` belongs to the call until it returns: do not share one between
concurrent calls.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
from tqdm import tqdm

from gsfric._checks import as_count, as_flag, short
from gsfric.compiled import native
from gsfric.compiled.functions import FlagSpec
from gsfric.compiled.state import first_nonfinite, state_of
from gsfric.errors import GsfricWarning, InputError, InputTypeError, StepFlagError
from gsfric.evaluation.flags import FLAG_NONFINITE, flag_message, flag_spec, rotation_spec
from gsfric.evaluation.memory import aligned_empty
from gsfric.evaluation.paper_constants import paper_constants as pc
from gsfric.evaluation.parameters import model_function, packed, uniform_model
from gsfric.evaluation.result import DETAILS, Outputs, Pending, Result
from gsfric.evaluation.uncertainty import (
    force_sigma,
    leg_speed_sigma,
    possibly_at_rest,
    rest_legs,
)
from gsfric.platform.catalog import apply_sensor, sensor_parameters
from gsfric.platform.description import Platform
from gsfric.trajectory import Motion

MODES = ("kinematic", "paper")
UNCERTAINTY_OUTPUTS = {"sigma_F": 6, "rest": 1}
"""Outputs computed in Python from the motion's ``rate_uncertainty`` (``Evaluator.uncertainty``)
and their sizes per step; NaN for a motion without it."""
CHUNK = 200_000
MAX_THREADS = 1024
"""The largest ``n_threads`` accepted: a sane bound on a count of threads (the compiled code
starts at most 64 per call, and at least 2048 steps each)."""


def state_array(motion: Motion) -> np.ndarray:
    """The generated functions' state input, (N, 24): p, T (row-major), v, omega, a, alpha.

    Laid out by ``gsfric.compiled.state.state_of``, the one Python layout of the states (the
    compiled code lays them out itself, block by block, in ``compiled/batch.c``).
    """
    return state_of((motion.position, motion.rotation, motion.velocity, motion.omega,
                     motion.acceleration, motion.alpha))


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

    Raises
    ------
    InputTypeError
        ``platform`` is not a Platform; ``n_threads`` is not an integer. Every method raises
        it (a ``TypeError``) for an argument of the wrong type, and ``InputError`` (a
        ``ValueError``) for a wrong shape or a NaN or infinite state, in one line: no NaN row
        comes from a NaN state.
    InputError
        ``mode`` is not one of ``MODES``; ``n_threads`` is not from 1 to ``MAX_THREADS``.

    Examples
    --------
    >>> import numpy as np, gsfric
    >>> from gsfric.evaluation import state_array
    >>> motion = gsfric.models.sinusoidal(np.linspace(0, 1, 101))
    >>> evaluator = gsfric.Evaluator(gsfric.reference_platform())
    >>> evaluator.actuator_forces(state_array(motion)).shape
    (101, 6)
    """

    def __init__(self, platform: Platform, mode: str = "kinematic", n_threads: int = 1,
                 paper_constants=None) -> None:
        if not isinstance(platform, Platform):
            raise InputTypeError(f"Evaluator: platform must be a gsfric.Platform, got "
                                 f"{_kind(platform)} (gsfric.reference_platform() or "
                                 "Platform.from_toml(path))")
        if not isinstance(mode, str) or mode not in MODES:
            raise InputError(f"mode: unknown mode {mode!r}; expected one of {', '.join(MODES)}")
        self.platform = platform
        self.mode = mode
        self.n_threads = as_count(n_threads, "n_threads", minimum=1, maximum=MAX_THREADS)
        self.P, self.Q, self._calls = packed(platform)
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
        No flags: the control loop's call. A finite state whose forces are not finite (a
        singular pose) gives its NaN or infinite row; ``evaluate`` flags such steps. Every
        state's rotation block is tested in C as it is evaluated (``FLAG_ROTATION``'s test,
        ``gsfric.trajectory.ROTATION_TOL``): a step that fails it raises, with or without
        ``out`` (whose rows of such steps are then NaN).

        Raises
        ------
        InputTypeError
            ``x`` or ``out`` is not an array (with ``out``, ``x`` must be a NumPy array).
        InputError
            A wrong shape or dtype, ``P`` or ``Q`` of another shape than (size,) or (N, size),
            a read-only ``out``, a NaN or infinite state (naming its row), a rotation block
            that is not a rotation (naming the first such step, ``x[k]``), paper mode.
        """
        if self.mode != "kinematic":
            raise InputError("actuator_forces: the kinematic mode's hot path; this Evaluator "
                             "is in paper mode")
        if P is None and Q is None and out is not None:
            key = ("actuator", self.n_threads)
            actuator = self._calls.get(key)
            if actuator is None:  # two threads may both build one: either is right
                actuator = self._calls[key] = native.get(self._actuator).bound(
                    [self.P, self.Q], "F", self.n_threads, rotation_spec(), "actuator_forces")
            return _finite_states(actuator(x, out), "actuator_forces", x)
        P = self.P if P is None else _parameters(P, "actuator_forces", "P", self.P.size)
        Q = self.Q if Q is None else _parameters(Q, "actuator_forces", "Q", self.Q.size)
        f = native.get(self._actuator if P is self.P
                       else model_function("actuator", uniform_model(P)))
        res = f([x, P, Q], None if out is None else {"F": out}, self.n_threads,
                check=rotation_spec(), caller="actuator_forces")
        return _finite_states(res["F"], "actuator_forces", x)

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

        The states are laid out in C, block by block (no ``state_array``); no flags. Every
        rotation matrix is tested in C as it is evaluated (as in ``actuator_forces``).

        Raises
        ------
        InputTypeError
            An argument that is not an array of numbers.
        InputError
            Wrong shapes, a NaN or infinite value (naming the array and row), a matrix that
            is not a rotation (naming the first, ``rotation[k]``), paper mode.
        """
        if self.mode != "kinematic":
            raise InputError("forces: the kinematic mode's hot path; this Evaluator is in "
                             "paper mode")
        key = ("forces", self.n_threads)
        call = self._calls.get(key)
        if call is None:  # two threads may both build one: either is right
            call = self._calls[key] = native.get(self._actuator).bound_motion(
                [self.P, self.Q], "F", self.n_threads, rotation_spec(), "forces")
        F = call(position, rotation, velocity, omega, acceleration, alpha, out)
        if not math.isfinite(_total(F, None)):
            motion = (position, rotation, velocity, omega, acceleration, alpha)
            for name, value in zip(("position", "rotation", "velocity", "omega",
                                    "acceleration", "alpha"), motion):
                value = np.asarray(value, dtype=float)
                rows = np.flatnonzero(~np.isfinite(value.reshape(len(value), -1)).all(axis=1))
                if len(rows):
                    raise InputError(f"forces: {name} row {int(rows[0])} is not finite "
                                     f"({len(rows)} rows); give finite states")
        return F

    def jacobian(self, x: np.ndarray, Q=None, P=None) -> tuple[np.ndarray, np.ndarray]:
        """F (N, 6) and dF/dtheta (N, 6, n_theta); theta names in ``jacobian_parameters()``.

        ``P`` and ``Q`` replace the Evaluator's own parameters (as in ``actuator_forces``).

        Raises
        ------
        InputTypeError, InputError
            As ``actuator_forces``: not an array, a wrong shape, a NaN or infinite state, a
            rotation block that is not a rotation.
        """
        Q = self.Q if Q is None else _parameters(Q, "jacobian", "Q", self.Q.size)
        P = self.P if P is None else _parameters(P, "jacobian", "P", self.P.size)
        res = native.get("jacobian")([x, P, Q], None, self.n_threads, check=rotation_spec(),
                                     caller="jacobian")
        x = np.asarray(x, dtype=float)
        where = first_nonfinite(x.reshape(-1, x.shape[-1]))
        if where is not None:
            raise InputError(f"jacobian: state {where} is not finite; give finite states")
        n = res["F"].shape[0]
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

        Raises
        ------
        InputTypeError
            ``motion`` is not a Motion; ``strict`` or ``progress`` not a bool; ``chunk`` not
            an integer.
        InputError
            ``chunk`` < 1.
        StepFlagError
            ``strict=True`` and a flagged step.
        """
        strict = as_flag(strict, "strict")
        result = self.evaluate_quiet(motion, progress=progress, chunk=chunk)
        msg = flag_message(result.flag)
        if msg is not None:
            if strict:
                raise StepFlagError(msg)
            warnings.warn(msg, GsfricWarning, stacklevel=2)
        return result

    def evaluate_quiet(self, motion: Motion, progress: bool = False, chunk: int = CHUNK,
                       buffers: dict | None = None, sensor: bool = True) -> Result:
        """``evaluate`` without reporting the flagged steps (no warning, no error).

        ``buffers`` (a dict, filled on first use) lends the output arrays: a caller that
        evaluates chunk after chunk passes the same dict and reuses the memory; the Result's
        arrays are then views into it, valid until the next call with it. ``sensor=False``
        leaves F as the mechanism's (no sensor effects): for a caller that applies them
        over a longer record than this motion (``gsfric.simulate``, chunk by chunk).
        """
        if not isinstance(motion, Motion):
            raise InputTypeError(f"motion: expected a gsfric.Motion, got {_kind(motion)} "
                                 "(Motion.from_samples or gsfric.io.read_trajectory)")
        chunk = as_count(chunk, "chunk")
        progress = as_flag(progress, "progress")
        n = len(motion)
        details = [name for name, _, _ in self._full.outputs if name in DETAILS]
        kept = [(name, size) for name, size, _ in self._full.outputs if name not in DETAILS]
        if buffers is None:
            outs = {name: aligned_empty(n, size) for name, size in kept}
        else:
            outs = {}
            for name, size in kept:
                buf = buffers.get(name)
                if buf is None or buf.shape[0] < n:
                    buf = buffers[name] = aligned_empty(n, size)
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
        if "D_dot" in arrays:
            arrays.update(self.uncertainty(motion, arrays["D_dot"]))
        later = Pending(tuple(details), functools.partial(
            _details, self.platform, self.mode, self.K, self.n_threads, motion, flag))
        return Result(t=np.asarray(motion.t, float), arrays=Outputs(arrays, later), flag=flag,
                      mode=self.mode, source=(self.platform, motion), runner=_evaluate_quietly)

    def uncertainty(self, motion: Motion, D_dot: np.ndarray, start: int = 0
                    ) -> dict[str, np.ndarray]:
        """``sigma_F`` (N, 6), N, and ``rest`` (N,) of a motion with ``rate_uncertainty``
        whose leg speeds are ``D_dot`` (N, 6) (``gsfric.evaluation.uncertainty``; ``start``:
        the index of its first step in a longer record); empty for one without, or in paper
        mode."""
        sigma = force_sigma(self, motion, start)
        if sigma is None:
            return {}
        at_rest = possibly_at_rest(D_dot, leg_speed_sigma(self.platform, motion))
        return {"sigma_F": sigma, "rest": rest_legs(at_rest).astype(float)}

    def _inputs(self) -> list:
        return [self.P, self.Q] + ([self.K] if self.K is not None else [])

    def _run(self, motion: Motion, s: int, e: int, view: dict,
             flag: np.ndarray | None = None) -> None:
        """Steps s..e-1 of ``motion`` into the output views and, given ``flag``, the step
        flags (non-finite steps' outputs NaN)."""
        m = motion
        parts = (m.position[s:e], m.rotation[s:e], m.velocity[s:e], m.omega[s:e],
                 m.acceleration[s:e], m.alpha[s:e])
        self._full([None] + self._inputs(), view, self.n_threads, select=view,
                   flags=None if flag is None else self.flag_spec(), flag=flag, motion=parts)

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

    def flag_spec(self) -> FlagSpec:
        """The settings of the step flags computed in C (read-only, shared by calls)."""
        spec = self._flag_spec
        if spec is None:
            spec = self._flag_spec = flag_spec(self._full.outputs, self._stroke)
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


def _details(platform: Platform, mode: str, constants, threads: int, motion: Motion,
             flag: np.ndarray, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The detail outputs ``names`` of an evaluation (``Pending.compute`` of its Result)."""
    evaluator = Evaluator(platform, mode=mode, paper_constants=constants, n_threads=threads)
    return evaluator.details(motion, names, flag)


_EVALUATE_OPTIONS = ("strict", "progress", "chunk")
"""The keyword arguments of ``evaluate_motion`` besides ``mode``."""


def evaluate_motion(platform: Platform, motion: Motion, mode: str = "kinematic",
                    **kwargs) -> Result:
    """Reaction forces and friction in every joint of ``platform`` over a ``Motion``: the
    core of ``gsfric.evaluate`` (which also takes a DataFrame of samples).

    Parameters
    ----------
    platform : Platform
    motion : Motion
        N steps.
    mode : {"kinematic", "paper"}
        "kinematic": accelerations from the motion; "paper": the paper's constants.
    **kwargs
        ``strict``, ``progress``, ``chunk`` of ``Evaluator.evaluate``.

    Returns
    -------
    Result

    Raises
    ------
    InputError
        ``chunk`` not an integer >= 1.
    InputTypeError
        ``platform`` is not a Platform or ``motion`` not a Motion, an unknown keyword
        argument; ``strict`` not a bool.
    StepFlagError
        ``strict=True`` and a flagged step.
    """
    unknown = sorted(set(kwargs) - set(_EVALUATE_OPTIONS))
    if unknown:
        raise InputTypeError(f"evaluate: unknown argument {unknown[0]!r}; expected "
                             f"{', '.join(_EVALUATE_OPTIONS + ('window', 'polyorder', 'log_format'))}")
    evaluation_arguments(platform, motion, kwargs.get("chunk", 1))
    return Evaluator(platform, mode=mode).evaluate(motion, **kwargs)


_total = np.add.reduce
"""The sum of an array's values: NaN or infinite when one value is (the hot paths' check)."""


def _finite_states(F: np.ndarray, name: str, x) -> np.ndarray:
    """``F``, after checking that a non-finite force comes from no non-finite state ``x``
    (one sum when all is finite); ``InputError`` naming the first non-finite state's row."""
    if math.isfinite(_total(F, None)):
        return F
    x = np.asarray(x, dtype=float)
    where = first_nonfinite(x.reshape(-1, x.shape[-1]))
    if where is not None:
        raise InputError(f"{name}: state {where} is not finite; give finite states")
    return F


def _parameters(value, name: str, argument: str, size: int) -> np.ndarray:
    """A parameter input (``P`` or ``Q``) as float64 of shape (size,) or (N, size), else a
    one-line ``InputError`` naming it and the expected shape."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputTypeError(f"{name}: {argument} must be an array of numbers, got "
                             f"{_kind(value)}") from None
    if array.shape != (size,) and not (array.ndim == 2 and array.shape[1] == size):
        raise InputError(f"{name}: {argument} has shape {array.shape}; expected ({size},) or "
                         f"(N, {size})")
    return array


def _kind(value: object) -> str:
    if isinstance(value, np.ndarray):
        return f"a NumPy array of shape {value.shape}"
    return "None" if value is None else f"a {type(value).__module__}.{type(value).__name__}"


def evaluation_arguments(platform: object, motion: object, chunk: object = 1) -> None:
    """The checks of ``gsfric.evaluate(platform, motion, chunk=...)``, each one line.

    Raises
    ------
    InputTypeError
        ``platform`` not a ``Platform`` or ``motion`` not a ``Motion`` (naming what was given,
        and saying so when the two are swapped).
    InputError
        ``chunk`` not an integer >= 1.
    """

    if isinstance(platform, Motion) and isinstance(motion, Platform):
        raise InputTypeError("evaluate(platform, motion): the arguments are swapped; give the "
                        "Platform first, then the Motion")
    if not isinstance(platform, Platform):
        raise InputTypeError(f"evaluate: platform must be a gsfric.Platform, got {_kind(platform)} "
                        "(gsfric.reference_platform() or Platform.from_toml(path))")
    if not isinstance(motion, Motion):
        hint = ("; for states (N, 24) use Evaluator.actuator_forces, for samples "
                "Motion.from_samples") if isinstance(motion, np.ndarray) else \
            " (Motion.from_samples, Motion.from_arrays or gsfric.io.read_trajectory)"
        raise InputTypeError(f"evaluate: motion must be a gsfric.Motion or a pandas DataFrame of "
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


def breakdown(platform: Platform, motion: Motion):
    """The actuator forces of ``platform`` along ``motion`` split into their parts
    (``Result.breakdown``: a DataFrame, columns (part, leg), N), without reporting the step
    flags (``gsfric.evaluation.breakdown``)."""
    return _evaluate_quietly(platform, motion).breakdown()


def evaluate_outputs(evaluator: Evaluator, motion: Motion, names, buffers: dict | None = None,
                     sensor: bool = True, start: int = 0
                     ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Only the outputs ``names`` of ``motion`` and its step flags, as
    ``Evaluator.evaluate_quiet`` computes them, without a Result.

    For a caller that writes a few outputs at every step (``gsfric.simulate``): the compiled
    code stores only those (the ones the flags read are computed all the same), about an
    eighth less time than every output for the 7 of ``simulate``'s default columns.

    Parameters
    ----------
    evaluator : Evaluator
    motion : Motion
        N steps.
    names : iterable of str
        Output names (``Result`` arrays, e.g. "F", "R_E", "sigma_F"; not the detail
        outputs).
    buffers : dict, optional
        Lends the output arrays from call to call (filled on first use): the arrays returned
        are then views into it, valid until the next call with it.
    sensor : bool
        Apply the sensor's effects to F (when "F" is among ``names``).
    start : int
        Index of the motion's first step in the record it is a piece of (``force_sigma``).

    Returns
    -------
    (dict of name -> ndarray (N, size), ndarray (N,) int64)
        Each output flat per step (R_E: (N, 18), leg i's x, y, z at 3 (i - 1) + 0, 1, 2)
        and the flags (``FLAG_NAMES``); a non-finite step's outputs are NaN.
    """
    n = len(motion)
    sizes = {name: size for name, size, _ in evaluator._full.outputs}
    names = list(dict.fromkeys(names))
    derived = [name for name in names if name in UNCERTAINTY_OUTPUTS]
    names = [name for name in names if name not in UNCERTAINTY_OUTPUTS]
    if derived and "D_dot" not in names:
        names.append("D_dot")
    outs: dict[str, np.ndarray] = {}
    for name in names:
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
    if derived:
        extra = evaluator.uncertainty(motion, outs["D_dot"], start)
        for name in derived:
            outs[name] = extra.get(name, np.full((n, UNCERTAINTY_OUTPUTS[name]), np.nan))
    return outs, flag
