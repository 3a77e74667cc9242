"""Fault cases of the Python API: wrong types, shapes, NaN states, thread counts and bad
settings given to every public entry point; each must raise the library's own error class
(also the matching builtin) with a one-line message."""

from __future__ import annotations

import functools
import re

import numpy as np
from makers import platform, trajectory
from runner import ApiCase

import gsfric
from gsfric import models
from gsfric.compiled.state import state_layout
from gsfric.discovery import discover
from gsfric.errors import InputError, InputTypeError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.loginspect import inspect_log
from gsfric.platform.description import Platform
from gsfric.platform.rig import Rig
from gsfric.simulate import simulate_file, view_file
from gsfric.sweep import sweep
from gsfric.throughput import measure
from gsfric.trajectory import Motion

T, V = InputTypeError, InputError


@functools.cache
def P() -> Platform:
    return models.reference_platform()


@functools.cache
def M() -> Motion:
    return models.sinusoidal(np.linspace(0, 1, 11))


def X() -> np.ndarray:
    return np.ascontiguousarray(state_array(M()))


def with_nan(row: int, column: int, value: float = np.nan) -> np.ndarray:
    x = X()
    x[row, column] = value
    return x


def _motion(**changes) -> Motion:
    m = M()
    parts = dict(t=m.t, position=m.position, rotation=m.rotation, velocity=m.velocity,
                 omega=m.omega, acceleration=m.acceleration, alpha=m.alpha)
    parts.update(changes)
    return Motion(*parts.values())


def _forces(*arrays):
    m = M()
    parts = [m.position, m.rotation, m.velocity, m.omega, m.acceleration, m.alpha]
    for k, a in enumerate(arrays):
        if a is not None:
            parts[k] = a
    return Evaluator(P()).forces(*parts)


def _nan_position():
    p = np.array(M().position)
    p[4, 2] = np.nan
    return p


EVALUATOR = [
    ("threads-zero", lambda f: Evaluator(P(), n_threads=0), V,
     r"^n_threads: must be an integer from 1 to 1024, got 0$", ValueError),
    ("threads-negative", lambda f: Evaluator(P(), n_threads=-5), V, r"got -5$", ValueError),
    ("threads-float", lambda f: Evaluator(P(), n_threads=1.5), T,
     r"^n_threads: expected an integer, got 1\.5$", TypeError),
    ("threads-string", lambda f: Evaluator(P(), n_threads="2"), T, r"got '2'", TypeError),
    ("threads-bool", lambda f: Evaluator(P(), n_threads=True), T, r"got True", TypeError),
    ("threads-none", lambda f: Evaluator(P(), n_threads=None), T, r"got None", TypeError),
    ("threads-2^70", lambda f: Evaluator(P(), n_threads=2**70), V, r"from 1 to 1024",
     ValueError),
    ("threads-numpy", lambda f: Evaluator(P(), n_threads=np.int64(2)), None, "", None),
    ("platform-none", lambda f: Evaluator(None), T,
     r"^Evaluator: platform must be a gsfric\.Platform, got None", TypeError),
    ("platform-path", lambda f: Evaluator("p.toml"), T, r"got a builtins\.str", TypeError),
    ("platform-motion", lambda f: Evaluator(M()), T, r"Motion", TypeError),
    ("mode-unknown", lambda f: Evaluator(P(), mode="fast"), V, r"^mode: unknown mode 'fast'",
     ValueError),
    ("mode-number", lambda f: Evaluator(P(), mode=3), V, r"unknown mode 3", ValueError),
    ("evaluate-none", lambda f: Evaluator(P()).evaluate(None), T,
     r"^motion: expected a gsfric\.Motion, got None", TypeError),
    ("evaluate-array", lambda f: Evaluator(P()).evaluate(X()), T, r"NumPy array", TypeError),
    ("evaluate-chunk-zero", lambda f: Evaluator(P()).evaluate(M(), chunk=0), V,
     r"^chunk: must be an integer >= 1, got 0$", ValueError),
    ("evaluate-chunk-float", lambda f: Evaluator(P()).evaluate(M(), chunk=1.5), T,
     r"^chunk: expected an integer", TypeError),
    ("evaluate-strict-text", lambda f: Evaluator(P()).evaluate(M(), strict="yes"), T,
     r"^strict: expected True or False", TypeError),
    ("evaluate-progress-none", lambda f: Evaluator(P()).evaluate(M(), progress=None), T,
     r"^progress: expected True or False", TypeError),
    ("actuator-nan", lambda f: Evaluator(P()).actuator_forces(with_nan(3, 5)), V,
     r"^actuator_forces: state row 3 \(rotation\) is not finite", ValueError),
    ("actuator-inf", lambda f: Evaluator(P()).actuator_forces(with_nan(7, 0, np.inf)), V,
     r"state row 7 \(position\)", ValueError),
    ("actuator-nan-out", lambda f: Evaluator(P()).actuator_forces(
        with_nan(10, 23), np.empty((11, 6))), V, r"state row 10 \(alpha\)", ValueError),
    ("actuator-nan-one-state", lambda f: Evaluator(P()).actuator_forces(with_nan(0, 20)[0]), V,
     r"state row 0 \(acceleration\)", ValueError),
    ("actuator-list", lambda f: Evaluator(P()).actuator_forces(X().tolist()), None, "", None),
    ("actuator-list-out", lambda f: Evaluator(P()).actuator_forces(
        X().tolist(), np.empty((11, 6))), T, r"must be NumPy arrays, got list", TypeError),
    ("actuator-none", lambda f: Evaluator(P()).actuator_forces(None), T, r"input x is None",
     TypeError),
    ("actuator-text", lambda f: Evaluator(P()).actuator_forces("x"), T,
     r"must be an array of numbers", TypeError),
    ("actuator-shape", lambda f: Evaluator(P()).actuator_forces(X()[:, :5]), V,
     r"input x has shape \(11, 5\), expected \(N, 24\)", ValueError),
    ("actuator-out-shape", lambda f: Evaluator(P()).actuator_forces(X(), np.empty((10, 6))),
     V, r"x must be C-contiguous float64 \(N, 24\) and out \(N, 6\)", ValueError),
    ("actuator-out-int", lambda f: Evaluator(P()).actuator_forces(
        X(), np.empty((11, 6), dtype=int)), V, r"out \(N, 6\)", ValueError),
    ("actuator-paper-mode", lambda f: Evaluator(P(), mode="paper").actuator_forces(X()), V,
     r"paper mode", ValueError),
    ("forces-nan", lambda f: _forces(_nan_position()), V,
     r"^forces: position row 4 is not finite", ValueError),
    ("forces-none", lambda f: _forces(None, None, None, None, None, np.zeros((3, 3))), V,
     r"must be \(N, 3\)", ValueError),
    ("forces-text", lambda f: _forces("a"), T, r"arrays of numbers", TypeError),
    ("forces-paper-mode", lambda f: Evaluator(P(), mode="paper").forces(
        *[np.zeros((1, 3))] * 6), V, r"paper mode", ValueError),
    ("jacobian-nan", lambda f: Evaluator(P()).jacobian(with_nan(2, 14)), V,
     r"^jacobian: state row 2 \(velocity\) is not finite", ValueError),
    ("jacobian-shape", lambda f: Evaluator(P()).jacobian(X()[:, :3]), V,
     r"input x has shape \(11, 3\)", ValueError),
    ("jacobian-list", lambda f: Evaluator(P()).jacobian(X().tolist()), None, "", None),
]
"""``Evaluator``: (id, call, error class or None, message, builtin)."""

EVALUATE = [
    ("swapped", lambda f: gsfric.evaluate(M(), P()), T, r"arguments are swapped", TypeError),
    ("platform-none", lambda f: gsfric.evaluate(None, M()), T, r"platform must be", TypeError),
    ("motion-array", lambda f: gsfric.evaluate(P(), X()), T, r"Evaluator\.actuator_forces",
     TypeError),
    ("unknown-keyword", lambda f: gsfric.evaluate(P(), M(), stirct=True), T,
     r"^evaluate: unknown argument 'stirct'", TypeError),
    ("mode", lambda f: gsfric.evaluate(P(), M(), mode="x"), V, r"unknown mode 'x'", ValueError),
    ("chunk", lambda f: gsfric.evaluate(P(), M(), chunk=-1), V, r"^chunk", ValueError),
]

MOTION = [
    ("nan-position", lambda f: _motion(position=_nan_position()), V,
     r"^Motion\.position\[4\]\[2\]: must be finite, got nan$", ValueError),
    ("inf-velocity", lambda f: _motion(velocity=np.full((11, 3), np.inf)), V,
     r"Motion\.velocity\[0\]\[0\]: must be finite", ValueError),
    ("t-none", lambda f: _motion(t=None), T, r"^Motion\.t: expected an array", TypeError),
    ("t-text", lambda f: _motion(t="t"), T, r"Motion\.t", TypeError),
    ("short-position", lambda f: _motion(position=M().position[:5]), V,
     r"Motion\.position: expected an array of shape \(11, 3\), got \(5, 3\)", ValueError),
    ("not-a-rotation", lambda f: _motion(rotation=np.tile(2 * np.eye(3), (11, 1, 1))), V,
     r"Motion\.rotation", ValueError),
    ("from-samples-none", lambda f: Motion.from_samples(None, None), T, r"^t: expected",
     TypeError),
    ("from-samples-nan", lambda f: Motion.from_samples(np.arange(11.0),
                                                         np.full((11, 3), np.nan)), V,
     r"^position\[0\]\[0\]: must be finite", ValueError),
    ("from-samples-text", lambda f: Motion.from_samples("abc", M().position), T, r"^t:",
     TypeError),
    ("from-samples-2^70", lambda f: Motion.from_samples(np.arange(11.0),
                                                          [[2**70, 0, 1]] * 11), V,
     r"position: integer too large", ValueError),
]

PLATFORM = [
    ("from-toml-none", lambda f: Platform.from_toml(None), T,
     r"^platform file: expected a file path", TypeError),
    ("from-toml-number", lambda f: Platform.from_toml(3), T, r"got 3", TypeError),
    ("from-toml-empty-path", lambda f: Platform.from_toml(""), V, r"path is empty",
     ValueError),
    ("from-dict-none", lambda f: Platform.from_dict(None), V, r"expected a table", ValueError),
    ("gravity-nan", lambda f: P().replace(gravity=float("nan")), V,
     r"^gravity: must be finite, got nan$", ValueError),
    ("gravity-huge", lambda f: P().replace(gravity=1e308), V,
     r"^gravity: 1e\+308 m/s\^2 is beyond the valid range 0 to 100 m/s\^2$", ValueError),
    ("gravity-2^70", lambda f: P().replace(gravity=2**70), V, r"integer too large",
     ValueError),
    ("payload-nan", lambda f: P().with_body(payload_mass=float("nan")), V,
     r"platform\.payload_mass: must be finite", ValueError),
    ("friction-text", lambda f: P().with_friction(prismatic_viscous="x"), T,
     r"friction\.prismatic_viscous: expected a number", TypeError),
    ("stroke-nan", lambda f: P().with_geometry(stroke=float("nan")), V, r"geometry\.stroke",
     ValueError),
    ("joints-2^70", lambda f: P().with_geometry(base_joints=[[2**70, 0, 0]] * 6), V,
     r"integer too large", ValueError),
    ("effects-none", lambda f: P().with_effects(None), T,
     r"^effects: expected a dict", TypeError),
    ("effects-unknown", lambda f: P().with_effects({"warp": {}}), V, r"effects\.warp",
     ValueError),
    ("effect-parameter-nan", lambda f: P().with_effect("seal_friction", force=float("nan")),
     V, r"effects\.seal_friction\.force: must be finite", ValueError),
    ("model-unknown", lambda f: models.reference_platform("magic"), V, r"friction\.model",
     ValueError),
]

FILES = {"t": trajectory(), "p": platform()}

SIMULATE_API = [
    ("trajectory-none", lambda f: simulate_file(None, f["tmp"] / "o.csv"), T,
     r"^trajectory: expected a file path", TypeError),
    ("out-number", lambda f: simulate_file(f["t"], 3), T, r"^out: expected a file path",
     TypeError),
    ("threads-zero", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv", n_threads=0), V,
     r"^n_threads: must be an integer from 1", ValueError),
    ("threads-float", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv", n_threads=2.0), T,
     r"^n_threads: expected an integer", TypeError),
    ("strict-text", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv", strict="no"), T,
     r"^strict", TypeError),
    ("out-is-input", lambda f: simulate_file(f["t"], f["t"]), V, r"is the trajectory file "
     r"itself", ValueError),
    ("platform-is-output", lambda f: simulate_file(f["t"], f["p"], platform=f["p"]), V,
     r"is the platform file itself", ValueError),
    ("platform-missing", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv",
                                                 platform=f["tmp"] / "none.toml"), V,
     r"none\.toml: file not found", ValueError),
    ("chunk-zero", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv", chunk=0), V,
     r"^chunk", ValueError),
]

SIMULATE_API += [
    ("plot-number", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv", plot=3), T,
     r"^plot: expected a file path", TypeError),
    ("plot-missing-folder", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv",
                                                    plot=f["tmp"] / "no" / "p.png"), V,
     r"no/p\.png: directory .* does not exist", ValueError),
    ("plot-is-out", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv",
                                            plot=f["tmp"] / "o.csv"), V,
     r"o\.csv: is the out file itself", ValueError),
    ("keep-flagged-text", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv",
                                                  keep_flagged="no"), T, r"^keep_flagged",
     TypeError),
    ("uncertainty-text", lambda f: simulate_file(f["t"], f["tmp"] / "o.csv",
                                                 uncertainty="no"), T, r"^uncertainty",
     TypeError),
    ("view-measured-text", lambda f: view_file(f["t"], f["tmp"] / "v.html", measured="no"), T,
     r"^measured: expected True or False", TypeError),
    ("view-out-folder-missing", lambda f: view_file(f["t"], f["tmp"] / "no" / "v.html"), V,
     r"no/v\.html: directory .* does not exist", ValueError),
]
"""``simulate_file`` and ``view_file``: each argument's type and each output's place."""

LOG_API = [
    ("path-number", lambda f: inspect_log(3), T, r"^path: expected a file path", TypeError),
    ("rig-dict", lambda f: inspect_log(f["t"], rig={}), T, r"^rig: expected a .*Rig",
     TypeError),
    ("platform-and-rig", lambda f: inspect_log(
        f["t"], platform=models.reference_platform(),
        rig=Rig.from_platform(models.reference_platform())), V,
     r"^give platform or rig, not both$", ValueError),
    ("platform-file-missing", lambda f: inspect_log(f["t"], platform=f["tmp"] / "none.toml"),
     V, r"none\.toml: file not found", ValueError),
    ("axes-number", lambda f: inspect_log(f["t"], axes=5), V, r"^axes: expected three signed",
     ValueError),
    ("bench-quick-text", lambda f: measure("yes"), T, r"^quick: expected True or False",
     TypeError),
]
"""``inspect_log`` (and ``gsfric.throughput.measure``): the types and combinations of their
arguments, refused before any work."""

SWEEP_API = [
    ("out-none", lambda f: sweep(None, trajectories=str(f["t"])), T,
     r"^out: expected a file path", TypeError),
    ("vary-string", lambda f: sweep(f["tmp"] / "o", trajectories=str(f["t"]),
                                    vary="gravity=0:1"), T, r"^vary: expected a dict",
     TypeError),
    ("vary-degenerate", lambda f: sweep(f["tmp"] / "o", trajectories=str(f["t"]),
                                        vary={"geometry.base_scale": (0, 0)}), V,
     r"^vary: geometry\.base_scale: 0:0 leaves the valid range 0\.1:10$", ValueError),
    ("vary-absurd", lambda f: sweep(f["tmp"] / "o", trajectories=str(f["t"]),
                                    vary={"gravity": (0, 1e308)}), V,
     r"^vary: gravity: 0:1e\+308 leaves the valid range 0:100$", ValueError),
    ("tolerances-list", lambda f: sweep(f["tmp"] / "o", trajectories=str(f["t"]),
                                        tolerances=[1]), T, r"^tolerances: expected a dict",
     TypeError),
    ("variants-zero", lambda f: sweep(f["tmp"] / "o", trajectories=str(f["t"]),
                                      vary={"gravity": (9, 10)}, variants=0), V,
     r"variants", ValueError),
]

DISCOVER_API = [
    ("motion-none", lambda f: discover(None, np.zeros((11, 6))), T,
     r"^data: expected a file path, a DataFrame or a Motion, got None", TypeError),
    ("forces-shape", lambda f: discover(M(), np.zeros((5, 6))), V,
     r"^forces: expected shape \(11, 6\), got \(5, 6\)", ValueError),
    ("forces-nan", lambda f: discover(M(), np.full((11, 6), np.nan)), V,
     r"no finite value", ValueError),
    ("unknown-option", lambda f: discover(M(), np.zeros((11, 6)), not_a_setting=1), T,
     r"^discover: unknown option 'not_a_setting'", TypeError),
    ("data-none", lambda f: discover(None), T, r"^data: expected a file path",
     TypeError),
    ("out-is-input", lambda f: discover(f["t"], out=f["t"]), V,
     r"is the measured-data file itself", ValueError),
]

IO_API = [
    ("read-trajectory-none", lambda f: gsfric.read_trajectory(None), T,
     r"^path: expected a file path", TypeError),
    ("read-measured-number", lambda f: gsfric.read_measured(3), T, r"got 3", TypeError),
    ("read-trajectory-window-even", lambda f: gsfric.read_trajectory(f["t"], window=4), V,
     r"t\.csv: window must be odd", ValueError),
    ("read-trajectory-missing", lambda f: gsfric.read_trajectory(f["tmp"] / "none.csv"), V,
     r"none\.csv: file not found", ValueError),
    ("to-toml-none", lambda f: P().to_toml(None), T, r"^path: expected a file path",
     TypeError),
    ("to-toml-onto-a-folder", lambda f: P().to_toml(f["tmp"]), V, r"directory", ValueError),
    ("sinusoidal-none", lambda f: models.sinusoidal(None), T, r"^t: expected an array",
     TypeError),
    ("sinusoidal-nan", lambda f: models.sinusoidal([0.0, np.nan]), V,
     r"^t\[1\]: must be finite", ValueError),
]

def _read_only() -> np.ndarray:
    out = np.empty((11, 6))
    out.flags.writeable = False
    return out


def _bytes_view() -> np.ndarray:
    return np.frombuffer(bytes(11 * 6 * 8)).reshape(11, 6)


def _not_rotation(kind: str, k: int) -> np.ndarray:
    """X() with the rotation block T of step k scaled by 2, mirrored (a column negated: det
    -1, T^T T = I), sheared (1e-3 of column 0 added to column 1), holding a NaN, or within the
    tolerance (1e-12 added to every entry)."""
    x = X()
    T = x[k, state_layout().rotation].reshape(3, 3)     # a view into x
    if kind == "scaled":
        T *= 2.0
    elif kind == "mirrored":
        T[:, 0] *= -1.0
    elif kind == "sheared":
        T[:, 1] += 1e-3 * T[:, 0]
    elif kind == "nan":
        T[1, 1] = np.nan
    else:
        T += 1e-12
    return x


def _rotations(x: np.ndarray) -> np.ndarray:
    return x[:, state_layout().rotation].reshape(-1, 3, 3)


OUTPUTS = {
    "actuator": lambda out: Evaluator(P()).actuator_forces(X(), out),
    "actuator-per-step-p": lambda out: Evaluator(P()).actuator_forces(
        X(), out, P=np.tile(Evaluator(P()).P, (11, 1))),
    "forces": lambda out: Evaluator(P()).forces(M().position, M().rotation, M().velocity,
                                                M().omega, M().acceleration, M().alpha, out),
}
"""Every call of the API that writes into a caller's array ``out``."""

PARAMETERS = {
    "actuator-p": lambda v: Evaluator(P()).actuator_forces(X(), P=v),
    "actuator-q": lambda v: Evaluator(P()).actuator_forces(X(), Q=v),
    "jacobian-q": lambda v: Evaluator(P()).jacobian(X(), Q=v),
}
"""Every call that takes a parameter vector (P, Q) given per call."""

STATE_CALLS = {
    "actuator": (lambda x: Evaluator(P()).actuator_forces(x), "actuator_forces: x"),
    "actuator-out": (lambda x: Evaluator(P()).actuator_forces(x, np.empty((11, 6))),
                     "actuator_forces: x"),
    "actuator-per-step-q": (lambda x: Evaluator(P()).actuator_forces(
        x, Q=np.tile(Evaluator(P()).Q, (11, 1))), "actuator_forces: x"),
    "jacobian": (lambda x: Evaluator(P()).jacobian(x), "jacobian: x"),
    "forces": (lambda x: _forces(None, _rotations(x)), "forces: rotation"),
    "forces-out": (lambda x: Evaluator(P()).forces(
        M().position, _rotations(x), M().velocity, M().omega, M().acceleration, M().alpha,
        np.empty((11, 6))), "forces: rotation"),
}
"""Every call that evaluates states given as arrays, and the start of its error for step k:
each tests every step's rotation block in the compiled code (``FLAG_ROTATION``'s test)."""

NOT_ROTATIONS = {"scaled": r"\(\|R\^T R - I\| = 3 > 1e-06\)$",
                 "mirrored": r"\(det R = -1 < 0\)$",
                 "sheared": r"\(\|R\^T R - I\| = 0\.001 > 1e-06\)$"}
"""Blocks that are no rotation (``_not_rotation``) and the end of the error they give."""

ROTATIONS = {
    "actuator-one-state": lambda: Evaluator(P()).actuator_forces(
        _not_rotation("scaled", 0)[0]),
    "motion-mirrored": lambda: _motion(rotation=-np.array(M().rotation)),
    "motion": lambda: _motion(rotation=np.array(M().rotation) * 2.0),
}
"""The other calls that check rotation matrices: a single state; ``Motion``."""


def _array_rows() -> list:
    rows = []
    for name, call in OUTPUTS.items():
        rows += [(f"{name}-read-only-out", lambda f, c=call: c(_read_only()), V,
                  r": out(put buffer F)?: output array is read-only", ValueError),
                 (f"{name}-bytes-out", lambda f, c=call: c(_bytes_view()), V,
                  r"output array is read-only", ValueError)]
    for name, call in PARAMETERS.items():
        argument = name[-1].upper()
        rows += [(f"{name}-shape", lambda f, c=call: c(np.zeros((3, 7))), V,
                  rf": {argument} has shape \(3, 7\); expected \(\d+,\) or \(N, \d+\)$",
                  ValueError),
                 (f"{name}-text", lambda f, c=call: c("abc"), T, rf": {argument} must be an "
                  "array of numbers", TypeError)]
    for name, call in ROTATIONS.items():
        rows.append((f"{name}-not-a-rotation", lambda f, c=call: c(), V,
                     r"not a rotation( matrix)? \(\|R\^T R - I\| = \d", ValueError))
    return rows + _state_rotation_rows()


def _state_rotation_rows() -> list:
    """Each state call (``STATE_CALLS``) with each kind of block that is no rotation, a NaN in
    the block and a rotation within the tolerance, at the first and the last step."""
    rows = []
    for name, (call, start) in STATE_CALLS.items():
        what = ": the rotation block is" if start.endswith("x") else ":"
        for k in (0, 10):
            for kind, end in NOT_ROTATIONS.items():
                rows.append((f"{name}-{kind}-step-{k}", lambda f, c=call, a=(kind, k):
                             c(_not_rotation(*a)), V,
                             rf"^{re.escape(start)}\[{k}\]{what} not a rotation {end}",
                             ValueError))
            nan = (rf"^{start.split(':')[0]}: state row {k} \(rotation\) is not finite"
                   if start.endswith("x") else rf"^forces: rotation row {k} is not finite")
            rows.append((f"{name}-nan-step-{k}", lambda f, c=call, k=k:
                         c(_not_rotation("nan", k)), V, nan, ValueError))
            rows.append((f"{name}-within-tolerance-step-{k}", lambda f, c=call, k=k:
                         c(_not_rotation("within", k)), None, "", None))
    return rows


ARRAYS = _array_rows()
"""Arrays given to the hot paths, by class: outputs that cannot be written, parameter vectors
of a wrong shape, rotation blocks that are no rotation."""

GROUPS = {"evaluator": EVALUATOR, "arrays": ARRAYS, "evaluate": EVALUATE, "motion": MOTION,
          "platform": PLATFORM, "simulate": SIMULATE_API, "sweep": SWEEP_API,
          "discover": DISCOVER_API, "io": IO_API, "log": LOG_API}


def api_cases() -> list[ApiCase]:
    return [ApiCase(id=f"api-{group}-{name}", call=call, error=error, message=message,
                    builtin=builtin, files=dict(FILES))
            for group, rows in GROUPS.items() for name, call, error, message, builtin in rows]
