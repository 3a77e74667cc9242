"""The current model as a function of its adjustable parameters, evaluated by the compiled code.

The adjustable parameters are those of the generated Jacobian (``jacobian_parameters()``): the
friction coefficients and masses of the platform (``joint_viscous``, ..., ``platform_mass``)
and every catalog effect's parameter (``effect.parameter``). A parameter vector ``theta`` holds
all of them, in that order; ``ParametricModel`` evaluates the actuator forces F(theta) and their
derivatives dF/dtheta over the measured motion with the compiled functions (never SymPy).

Derivatives come from the compiled Jacobian function when its layout in the manifest is the
dense (6, n_theta) block per step; otherwise from central differences of the compiled actuator
map (two evaluations per parameter), which gives the same numbers to about 1e-8 relative.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence

import numpy as np

from gsfric.compiled.manifest import function, jacobian_platform_parameters, layout
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.parameters import (
    effect_vector,
    jacobian_parameters,
    parameter_vector,
)
from gsfric.evaluation.result import Result
from gsfric.platform.catalog import (
    EFFECTS,
    SENSOR_EFFECTS,
    apply_sensor,
    sensor_jacobian,
    sensor_parameters,
)
from gsfric.platform.description import Platform
from gsfric.trajectory import Motion

BASE_PARAMETERS = jacobian_platform_parameters()
"""Parameters of the platform description among the Jacobian's parameters (from the manifest)."""

_BODY_FIELDS = {"payload_mass": "payload_mass", "platform_mass": "mass"}
"""The body parameters among ``BASE_PARAMETERS``, by their field of ``Platform.platform``; the
others are fields of ``Platform.friction``."""

_FRICTION = tuple(n for n in BASE_PARAMETERS if n not in _BODY_FIELDS)
"""The friction coefficients among ``BASE_PARAMETERS``."""

_STATE = {block["name"]: block["offset"] for block in layout("eval", "x")}
"""Offset of each block (position, velocity, acceleration, ...) in a state row (``x``)."""


def _compiled_jacobian_is_dense() -> bool:
    n_theta = len(jacobian_parameters())
    try:
        outputs = {o["name"]: o["size"] for o in function("jacobian")["outputs"]}
    except Exception:
        return False
    return outputs.get("dF") == 6 * n_theta


def _take_columns(part: np.ndarray, columns: Sequence[int], out: np.ndarray,
                  into: Sequence[int]) -> None:
    """``out[:, :, into] = part[:, :, columns]`` (shapes (m, 6, .)); into a stretch of
    consecutive columns by ``np.take``, which copies without the fancy index's temporary and
    scatter (several times faster on a chunk of a long record)."""
    first = into[0] if len(into) else 0
    if list(into) == list(range(first, first + len(into))):
        np.take(part, columns, axis=2, out=out[:, :, first:first + len(into)], mode="clip")
    else:
        out[:, :, list(into)] = part[:, :, columns]


class ParametricModel:
    """Actuator forces of a platform along a motion, as a function of the parameters theta.

    Parameters
    ----------
    platform : Platform
        The model; its values give the starting parameters ``theta0``.
    motion : Motion
        The (measured) motion, N steps.
    n_threads : int
        Threads of the compiled evaluation.

    Attributes
    ----------
    names : list[str]
        Names of theta's entries (``jacobian_parameters()``).
    theta0 : ndarray, shape (n_theta,)
        The platform's own values.
    """

    def __init__(self, platform: Platform, motion: Motion, n_threads: int = 1) -> None:
        self.platform = platform
        self.motion = motion
        self.n_threads = int(n_threads)
        self.x = state_array(motion)
        compiled = jacobian_parameters()
        self.n_compiled = len(compiled)
        self.names = compiled + [f"{e}.{p}" for e, ps in SENSOR_EFFECTS.items() for p in ps]
        self.index = {n: k for k, n in enumerate(self.names)}
        self.n_base = len(BASE_PARAMETERS)
        self.t = np.asarray(motion.t, float)
        f, b = platform.friction, platform.platform
        base = [getattr(b, _BODY_FIELDS[n]) if n in _BODY_FIELDS else getattr(f, n)
                for n in BASE_PARAMETERS]
        gains, delay = sensor_parameters(platform.effects)
        self.theta0 = np.concatenate([base, effect_vector(platform), gains, [delay]]
                                     ).astype(float)
        self._evaluator = Evaluator(platform, n_threads=self.n_threads)
        self._P0 = parameter_vector(platform)
        offsets = {b["name"]: b["offset"] for b in layout("eval", "P")}
        self._P_index = np.array([offsets[n] for n in BASE_PARAMETERS])
        self._dense = _compiled_jacobian_is_dense()
        self.evaluations = 0

    def __len__(self) -> int:
        return self.x.shape[0]

    # -- parameters -----------------------------------------------------------------------
    def platform_at(self, theta: np.ndarray, effects: Sequence[str] = ()) -> Platform:
        """The platform with the base parameters of ``theta`` and the named effects switched on
        with theta's values."""
        theta = np.asarray(theta, float)
        i = self.index
        p = self.platform.with_friction(**{n: float(theta[i[n]]) for n in _FRICTION})
        p = p.with_body(**{field: float(theta[i[n]]) for n, field in _BODY_FIELDS.items()})
        for name in effects:
            params = {k.split(".", 1)[1]: float(theta[j]) for k, j in i.items()
                      if k.startswith(name + ".")}
            p = p.with_effect(name, **params)
        return p

    def vectors(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The compiled functions' inputs P and Q for parameters theta."""
        theta = np.asarray(theta, float)
        P = self._P0.copy()
        P[self._P_index] = theta[:self.n_base]
        return P, theta[self.n_base:self.n_compiled].copy()

    def sensor(self, theta: np.ndarray) -> tuple[np.ndarray, float]:
        """Gains (6,) and delay (s) of the sensor effects in theta (read by name)."""
        return sensor_parameters({e: {p: theta[self.index[f"{e}.{p}"]] for p in ps}
                                  for e, ps in SENSOR_EFFECTS.items()})

    def _read(self, theta: np.ndarray, F: np.ndarray) -> np.ndarray:
        gains, delay = self.sensor(theta)
        if delay == 0.0 and not np.any(gains):
            return F
        return apply_sensor(self.t, F, gains, delay)

    def effect_names(self, theta: np.ndarray) -> list[str]:
        """Effects whose parameters in theta differ from the catalog defaults."""
        out = []
        for name, params in EFFECTS.items():
            if any(theta[self.index[f"{name}.{p}"]] != d for p, d in params.items()):
                out.append(name)
        return out

    # -- evaluations ----------------------------------------------------------------------
    def forces(self, theta: np.ndarray) -> np.ndarray:
        """F(theta), (N, 6) N."""
        P, Q = self.vectors(theta)
        self.evaluations += 1
        return self._read(theta, self._evaluator.actuator_forces(self.x, P=P, Q=Q))

    def pose_scale(self, theta: np.ndarray, rows: slice | None = None,
                   h: float = 1e-4) -> np.ndarray:
        """dF/de (M, 6, 3) over ``rows`` (default all N), N: the change of the rigid-body
        force per unit scale error e of each position axis of the motion (x, y, z, their
        velocity and acceleration read ``1 + e`` times the true ones, about the base frame's
        origin), by central differences of step ``h``.

        The rigid-body force is F(theta) with the friction coefficients at zero and no
        effect: the inertia and the weights that a mis-scaled pose moves between the legs,
        not the friction laws that its scaled speed would change (which friction candidates
        and the refit already describe)."""
        rigid = self.platform_at(theta).without_effects().with_friction(
            **dict.fromkeys(_FRICTION + ("prismatic_seal",), 0.0))
        P, Q = parameter_vector(rigid), effect_vector(rigid)
        x = self.x if rows is None else self.x[rows]
        out = np.empty((x.shape[0], 6, 3))
        for axis in range(3):
            columns = [_STATE[block] + axis for block in ("position", "velocity", "acceleration")]
            F = []
            for e in (h, -h):
                moved = x.copy()
                moved[:, columns] *= 1.0 + e
                F.append(self._evaluator.actuator_forces(moved, P=P, Q=Q))
            out[:, :, axis] = (F[0] - F[1]) / (2 * h)
        self.evaluations += 6
        return out

    def forces_batch(self, thetas: np.ndarray) -> np.ndarray:
        """F at several parameter vectors, (G, N, 6) for thetas (G, n_theta)."""
        thetas = np.atleast_2d(np.asarray(thetas, float))
        out = np.empty((thetas.shape[0], len(self), 6))
        for g, theta in enumerate(thetas):
            P, Q = self.vectors(theta)
            self._evaluator.actuator_forces(self.x, out=out[g], P=P, Q=Q)
            out[g] = self._read(theta, out[g])
        self.evaluations += thetas.shape[0]
        return out

    def jacobian(self, theta: np.ndarray, columns: Sequence[str], rows: slice | None = None,
                 out: np.ndarray | None = None, chunk: int = 20000
                 ) -> tuple[np.ndarray, np.ndarray]:
        """F(theta) (N, 6) and dF/dtheta for the named parameters, (M, 6, len(columns)) over
        ``rows`` (default all N), written into ``out`` if given. The compiled Jacobian (every
        parameter) is evaluated ``chunk`` steps at a time, so memory grows with the columns
        asked for only."""
        theta = np.asarray(theta, float)
        cols = [self.index[c] for c in columns]
        gains, delay = self.sensor(theta)
        sensor_on = delay != 0.0 or bool(np.any(gains))
        own = [c for c in cols if c < self.n_compiled]
        if self._dense:
            n = len(self)
            r0, r1, _ = (slice(0, n) if rows is None else rows).indices(n)
            if out is None:
                out = np.empty((r1 - r0, 6, len(cols)))
            own_k = [k for k, c in enumerate(cols) if c < self.n_compiled]
            # with a delay, a column needs all steps (shifted in time); otherwise only rows
            F0 = np.empty((n, 6))
            J = np.empty((n, 6, len(own))) if sensor_on else None
            needed = (0, n) if sensor_on else (r0, r1)
            for a, b, part in self._compiled_jacobian(theta, *needed, chunk, F0):
                _take_columns(part, own, J[a:b] if J is not None else out[a - r0:b - r0],
                              range(len(own)) if J is not None else own_k)
                del part            # released before the next chunk is evaluated
            if J is not None:
                for j, k in enumerate(own_k):
                    out[:, :, k] = apply_sensor(self.t, J[:, :, j], gains, delay)[r0:r1]
                del J
            F = self._read(theta, F0)
            if len(own) < len(cols):
                d_gains, d_delay = sensor_jacobian(self.t, F0, gains, delay)
                for k, c in enumerate(cols):
                    if c >= self.n_compiled + 6:
                        out[:, :, k] = d_delay[r0:r1]
                    elif c >= self.n_compiled:
                        out[:, :, k] = d_gains[r0:r1, :, c - self.n_compiled]
            return F, out
        steps = np.maximum(np.abs(theta[cols]), 1.0) * 1e-6
        plus = np.repeat(theta[None], len(cols), axis=0)
        minus = plus.copy()
        for k, (j, h) in enumerate(zip(cols, steps)):
            plus[k, j] += h
            minus[k, j] -= h
        values = self.forces_batch(np.concatenate([theta[None], plus, minus]))
        F = values[0]
        m = len(cols)
        J = (values[1:1 + m] - values[1 + m:]) / (2 * steps[:, None, None])
        return F, np.ascontiguousarray(J.transpose(1, 2, 0))

    def _compiled_jacobian(self, theta: np.ndarray, r0: int, r1: int, chunk: int,
                           F0: np.ndarray) -> Iterator[tuple[int, int, np.ndarray]]:
        """The compiled Jacobian of every compiled parameter over rows r0:r1, evaluated
        ``chunk`` steps at a time: ``(a, b, dF/dtheta)`` for rows a:b of the record,
        (b - a, 6, n_compiled) each, one chunk alive at a time; F without sensor effects
        written into ``F0`` (N, 6) by the time the iteration ends."""
        n = len(self)
        evaluator = Evaluator(self.platform_at(theta), n_threads=self.n_threads)
        Q = theta[self.n_base:self.n_compiled]
        self.evaluations += 1
        for s in range(0, n, chunk):
            e = min(n, s + chunk)
            F0[s:e], J0 = evaluator.jacobian(self.x[s:e], Q=Q)
            a, b = max(s, r0), min(e, r1)
            if a < b:
                yield a, b, J0[a - s:b - s]
            del J0

    def evaluate(self, theta: np.ndarray, keep: Sequence[str] = ("D", "D_dot"),
                 chunk: int = 20000) -> Result:
        """The outputs ``keep`` of the full evaluation at theta, with F (what the load cells
        read, sensor effects applied) and the step flags; evaluated ``chunk`` steps at a time
        so that memory stays bounded (the full evaluation has about 200 numbers a step)."""
        evaluator = Evaluator(self.platform_at(theta, self.effect_names(theta)),
                              n_threads=self.n_threads)
        self.evaluations += 1
        n = len(self)
        arrays = {}
        flags = np.zeros(n, dtype=np.int64)
        for s in range(0, n, chunk):
            e = min(n, s + chunk)
            if 0 < n - e < 8:        # no chunk too short to evaluate on its own
                e = n
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                part = evaluator.evaluate(self.motion.slice(s, e))
            for k in keep:
                value = part.arrays[k]
                if k not in arrays:
                    arrays[k] = np.empty((n,) + value.shape[1:])
                arrays[k][s:e] = value
            flags[s:e] = part.flag
            if e == n:
                break
        arrays["F"] = self.forces(theta)
        return Result(t=np.asarray(self.motion.t, float), arrays=arrays, flag=flags)
