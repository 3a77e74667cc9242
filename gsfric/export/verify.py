"""Checking an export (``gsfric export --verify``): build it, compare it with ``Evaluator``.

The library checked is the one the folder's ``manifest.json`` names (a folder holding another
library too is refused). The folder is copied to a temporary directory and built there with
the system compiler (``CC``, default ``cc``) and the flags of its Makefile (``CFLAGS`` when set,
as ``make`` reads it), with a driver (``templates/verify.c.in``) that runs the library on
states from a file. The valid states are random ones (poses of ``gsfric.models.random_motion``
with random rates, kept where ``Evaluator`` flags nothing) and the reference motions
(``gsfric.models.sinusoidal``, ``paper_motion``): each output's error is relative to the
largest magnitude of that output (``max |C - Python| / max |Python|``; for
``coupling_change``, of F0: ``SCALE_OF``). The flagged states are poses beyond the stroke and
a singular one (``flagged_motion``) and states gsfric refuses (``refused_states``: a
non-finite entry, a rotation block that is not a rotation): their flags must match
``Evaluator``'s (or, for those it refuses, the flag of the reason), and the outputs of the
last ones be NaN. The latency is the median time of one ``<prefix>_actuator_forces`` call on
the valid states, measured in C.
"""

from __future__ import annotations

import importlib.resources
import json
import os
import shlex
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gsfric.compiled.state import state_layout
from gsfric.errors import BuildError, InputError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import FLAG_NONFINITE, FLAG_ROTATION
from gsfric.evaluation.parameters import model_function
from gsfric.export.text import outputs
from gsfric.export.writer import CFLAGS, MANIFEST_FILE, PLATFORM_FILE, libraries
from gsfric.models import paper_motion, random_motion, sinusoidal
from gsfric.platform.description import Platform
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.trajectory import ROTATION_TOL, Motion, first_non_rotation

TOLERANCE = 1e-12
"""The largest relative error ``verify_library`` accepts."""

SCALE_OF = {"coupling_change": "F0"}
"""Outputs whose error is relative to another output's magnitude: ``coupling_change`` is a
change of the axial forces F0 (nearly zero at convergence, where its own magnitude is the
rounding of F0)."""

ROUNDS = 20_000
"""Timed groups of calls for the latency (16 calls each)."""


@dataclass(frozen=True)
class VerifyReport:
    """The outcome of ``verify_library``.

    Attributes
    ----------
    folder : Path
        The export checked.
    prefix, model : str
        Its prefix and friction model.
    compiler : str
        The compiler command and flags used.
    states : int
        Valid states compared, output by output (random ones and the reference motions'
        steps).
    flagged_states : int
        Flagged states compared by their flags (``flagged_motion``: beyond the stroke,
        singular; ``refused_states``: non-finite, not rotations).
    worst_error : float
        The worst relative error over every output (``evaluate``) and F (``actuator_forces``)
        of the valid states.
    worst_output : str
        The output where it occurred.
    flag_mismatches : int
        Steps whose flags differ from ``Evaluator``'s (of ``first_non_rotation`` for a
        rotation block that is not a rotation, ``FLAG_NONFINITE`` for a non-finite entry),
        counted once per call (``evaluate``, ``actuator_forces``).
    unmasked : int
        Steps flagged non-finite or not a rotation whose outputs are not all NaN.
    pose_error : float
        The largest absolute difference of ``<prefix>_pose_state``'s states from the reference
        motions' (rotation from a unit quaternion: about 1e-16).
    latency_ns : float
        Median time of one ``<prefix>_actuator_forces`` call, ns.
    """

    folder: Path
    prefix: str
    model: str
    compiler: str
    states: int
    flagged_states: int
    worst_error: float
    worst_output: str
    flag_mismatches: int
    unmasked: int
    pose_error: float
    latency_ns: float

    @property
    def ok(self) -> bool:
        """True when every error is within ``TOLERANCE``, every flag matches and every
        step flagged non-finite or not a rotation has NaN outputs."""
        return self.worst_error <= TOLERANCE and self.flag_mismatches == 0 and \
            self.unmasked == 0 and self.pose_error <= TOLERANCE

    def lines(self) -> list[str]:
        """The report as ``gsfric export --verify`` prints it."""
        verdict = "ok" if self.ok else "FAILED"
        return [f"{self.folder}: {self.prefix} ({self.model} model), built with {self.compiler}",
                f"  {self.states} states: worst relative error {self.worst_error:.2e} "
                f"({self.worst_output}), goal <= {TOLERANCE:g}",
                f"  {self.flagged_states} flagged states (beyond the stroke, singular, "
                f"non-finite, not rotations); flags differing from Evaluator: "
                f"{self.flag_mismatches} steps; flagged outputs not NaN: {self.unmasked}",
                f"  pose_state: largest difference {self.pose_error:.2e}",
                f"  latency of one {self.prefix}_actuator_forces call: "
                f"{self.latency_ns:.0f} ns (median)",
                f"  {verdict}"]


def _library(folder: Path) -> tuple[str, str]:
    """(prefix, model) of the library the manifest of ``folder`` names; ``InputError`` when
    there is none, or when the folder holds another library too."""
    if not folder.is_dir():
        raise InputError(f"--verify: {folder} is not a directory")
    path = folder / MANIFEST_FILE
    try:
        manifest = json.loads(path.read_text())
        prefix, model = str(manifest["prefix"]), str(manifest["model"])
    except FileNotFoundError:
        raise InputError(f"--verify: {folder} holds no library written by `gsfric export` "
                         f"(no {MANIFEST_FILE}); export it again") from None
    except (OSError, UnicodeDecodeError, ValueError, TypeError, KeyError) as exc:
        raise InputError(f"--verify: {path} is not the manifest of an export "
                         f"({type(exc).__name__}: {exc}); export it again") from None
    found = libraries(folder)
    if prefix not in found:
        raise InputError(f"--verify: {path} names the library {prefix!r}, but {folder} has no "
                         f"{prefix}.h and {prefix}.c written by `gsfric export`")
    others = [p for p in found if p != prefix]
    if others:
        raise InputError(f"--verify: {folder} holds two libraries, {prefix}.h (its "
                         f"{MANIFEST_FILE}) and {others[0]}.h; export each into a folder of "
                         "its own")
    return prefix, model


def compiler() -> list[str]:
    command = shlex.split(os.environ.get("CC", "cc") or "cc")
    if shutil.which(command[0]) is None:
        raise BuildError(f"--verify: no C compiler {command[0]!r} (set CC)")
    return command


def compiler_flags() -> list[str]:
    """The flags of the build: ``$CFLAGS`` when set (as ``make`` reads it), else the
    Makefile's defaults (``CFLAGS`` of gsfric.export.writer)."""
    return shlex.split(os.environ.get("CFLAGS") or "") or list(CFLAGS)


def build(folder: Path, prefix: str, work: Path, cc: list[str], flags=None) -> Path:
    """The verify driver built with the library of ``folder`` in ``work``; its path."""
    shutil.copytree(folder, work / "src")
    driver = importlib.resources.files("gsfric.export").joinpath("templates", "verify.c.in")
    text = driver.read_text().replace("@prefix@", prefix).replace("@PREFIX@", prefix.upper())
    (work / "src" / "verify.c").write_text(text)
    target = work / "verify"
    flags = compiler_flags() if flags is None else flags
    command = [*cc, *flags, "-o", str(target), str(work / "src" / "verify.c"),
               str(work / "src" / f"{prefix}.c"), "-lm"]
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode:
        first = (run.stderr.strip().splitlines() or ["(no message)"])[0]
        raise BuildError(f"--verify: the build failed: {first}")
    return target


def random_states(platform: Platform, n: int, seed: int = 0) -> Motion:
    """``n`` random states of ``platform``: poses of ``random_motion``, random rates."""
    rng = np.random.default_rng(seed)
    poses = random_motion(rng, rng.uniform(0.0, 10.0, n))
    rates = [rng.uniform(-s, s, (n, 3)) for s in (0.5, 1.0, 5.0, 10.0)]
    return Motion.from_arrays(np.arange(n, dtype=float), poses.position, poses.rotation,
                              *rates[:2], *rates[2:])


def check_motions(platform: Platform, n_random: int, seed: int) -> Motion:
    """The states to compare: random ones Evaluator does not flag, then the reference
    motions', as one Motion."""
    random = random_states(platform, n_random, seed)
    keep = Evaluator(platform).evaluate_quiet(random).flag == 0
    return _joined([_steps(random, keep) if keep.any() else random,
                    sinusoidal(np.linspace(0.0, 2.0, 201)), paper_motion()])


def _steps(motion: Motion, keep: np.ndarray) -> Motion:
    """The steps ``keep`` (a boolean mask) of ``motion``."""
    return Motion.from_arrays(motion.t[keep], motion.position[keep], motion.rotation[keep],
                              motion.velocity[keep], motion.omega[keep],
                              motion.acceleration[keep], motion.alpha[keep])


def flagged_motion(platform: Platform) -> Motion:
    """Poses that ``Evaluator`` flags: the sinusoidal motion raised and lowered by the length
    of the stroke (legs beyond it) and with the platform in the base's plane (a singular
    Jacobian, legs below the stroke)."""
    base = sinusoidal(np.linspace(0.0, 2.0, 21))
    stroke = platform.geometry.stroke
    shift = stroke[1] - stroke[0] if stroke is not None else 0.5
    positions = [base.position + [0.0, 0.0, shift], base.position - [0.0, 0.0, shift],
                 base.position * [1.0, 1.0, 0.0]]
    arrays = [np.concatenate(positions)] + [np.concatenate([getattr(base, a)] * 3) for a in
                                            ("rotation", "velocity", "omega", "acceleration",
                                             "alpha")]
    return Motion.from_arrays(np.arange(arrays[0].shape[0], dtype=float), *arrays)


def refused_states(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States that gsfric refuses and the library flags, made from the valid states ``x``
    (N, size): one non-finite entry (NaN or infinite; ``FLAG_NONFINITE``), or a rotation
    block scaled, mirrored or sheared beyond ``ROTATION_TOL`` (``FLAG_ROTATION``, as
    ``first_non_rotation`` finds). Returns (states (K, size), their flags (K,))."""
    layout = state_layout()
    rows, flags = [], []
    for k, (column, value) in enumerate([(layout.position.start, np.nan),
                                         (layout.rotation.start + 4, np.nan),
                                         (layout.omega.start + 2, np.inf),
                                         (layout.alpha.start, -np.inf)]):
        row = x[k % len(x)].copy()
        row[column] = value
        rows.append(row)
        flags.append(FLAG_NONFINITE)
    tol = ROTATION_TOL
    for k, change in enumerate([np.diag([2.0, 2.0, 2.0]), np.diag([1.0, 1.0, -1.0]),
                                np.diag([1.0 + 4 * tol] * 3), np.eye(3) + 4 * tol * np.eye(3, k=1)]):
        row = x[k % len(x)].copy()
        rotation = row[layout.rotation].reshape(3, 3) @ change
        row[layout.rotation] = rotation.ravel()
        if first_non_rotation(rotation[None]) is not None:
            rows.append(row)
            flags.append(FLAG_ROTATION)
    return np.array(rows), np.array(flags, dtype=np.int32)


def write_inputs(work: Path, motion: Motion, refused: np.ndarray) -> list[str]:
    """The driver's input files in ``work``: the states of ``motion`` then ``refused``
    (states.bin) and the poses of ``motion`` (poses.bin); the driver's arguments but the
    number of timed rounds (outputs written into ``work``)."""
    x = np.concatenate([state_array(motion), refused])
    x.astype(np.float64).tofile(work / "states.bin")
    q = quaternion_from_rotation(motion.rotation)
    poses = np.concatenate([motion.position, q, motion.velocity, motion.omega,
                            motion.acceleration, motion.alpha], axis=1)
    np.ascontiguousarray(poses, dtype=np.float64).tofile(work / "poses.bin")
    return ["states.bin", str(len(x)), "poses.bin", str(len(motion)), "outputs.bin",
            "forces.bin", "flags.bin", "pose_states.bin"]


def _relative(c: np.ndarray, py: np.ndarray, reference: np.ndarray | None = None) -> float:
    """``max |c - py| / max |reference|`` over the finite values (``reference``: ``py``);
    infinite when c and py are not finite at the same places."""
    good = np.isfinite(py) & np.isfinite(c)
    reference = py[good] if reference is None else reference[np.isfinite(reference)]
    scale = np.max(np.abs(reference), initial=0.0)
    diff = np.max(np.abs(c[good] - py[good]), initial=0.0)
    if np.any(np.isfinite(py) != np.isfinite(c)):
        return float("inf")
    return float(diff / scale) if scale > 0 else float(diff)


@dataclass(frozen=True)
class _Run:
    """What the driver wrote: every output of ``<prefix>_evaluate`` by name (N, size), its
    flags (N,), F and the flags of ``<prefix>_actuator_forces`` (N, legs), (N,)."""

    values: dict[str, np.ndarray]
    flags: np.ndarray
    F: np.ndarray
    step_flags: np.ndarray


def _read_run(work: Path, function: str, n: int, size: int) -> _Run:
    outs = outputs(function)
    raw = np.fromfile(work / "outputs.bin", dtype=np.uint8).reshape(n, size)
    total = sum(o.size for o in outs)
    flat = raw[:, :8 * total].copy().view(np.float64)
    flags = raw[:, 8 * total:8 * total + 4].copy().view(np.int32)[:, 0]
    starts = np.cumsum([0] + [o.size for o in outs])
    values = {o.name: flat[:, starts[k]:starts[k + 1]] for k, o in enumerate(outs)}
    return _Run(values, flags, np.fromfile(work / "forces.bin").reshape(n, -1),
                np.fromfile(work / "flags.bin", dtype=np.int32))


def _compare(run: _Run, result, compared: int) -> tuple[float, str]:
    """(worst error, its output) of the first ``compared`` steps of ``run`` against
    ``result``."""
    worst, where = 0.0, ""
    for name, values in run.values.items():
        reference = getattr(result, SCALE_OF[name])[:compared] if name in SCALE_OF else None
        err = _relative(values[:compared],
                        getattr(result, name)[:compared].reshape(compared, -1), reference)
        if err >= worst:
            worst, where = err, name
    err = _relative(run.F[:compared], result.F[:compared])
    if err > worst:
        worst, where = err, "F of actuator_forces"
    return worst, where


def verify_library(folder, n_random: int = 2000, seed: int = 0, rounds: int = ROUNDS,
                   flags=None) -> VerifyReport:
    """Build the export in ``folder`` and compare it with ``Evaluator`` (see the module);
    ``flags``: the compiler's flags (None: ``compiler_flags()``)."""
    folder = Path(folder)
    prefix, model = _library(folder)
    platform = Platform.from_toml(folder / PLATFORM_FILE)
    cc = compiler()
    valid = check_motions(platform, n_random, seed)
    motion = _joined([valid, flagged_motion(platform)])
    result = Evaluator(platform).evaluate_quiet(motion)
    refused, refused_flags = refused_states(state_array(valid)[:8])
    expected = np.concatenate([result.flag, refused_flags])
    with tempfile.TemporaryDirectory(prefix="gsfric-verify-") as tmp:
        work = Path(tmp)
        flags = compiler_flags() if flags is None else list(flags)
        driver = build(folder, prefix, work, cc, flags)
        names = [*write_inputs(work, motion, refused), str(rounds)]
        run = subprocess.run([str(driver), *names], capture_output=True, text=True, cwd=work)
        if run.returncode:
            raise BuildError(f"--verify: the check program failed (exit {run.returncode})")
        size, latency = run.stdout.split()
        out = _read_run(work, model_function("eval", model), len(expected), int(size))
        pose = np.fromfile(work / "pose_states.bin").reshape(len(motion), -1)
        pose_error = float(np.max(np.abs(pose - state_array(motion))))
    worst, where = _compare(out, result, len(valid))
    mismatches = int(np.sum(out.flags != expected) + np.sum(out.step_flags != expected))
    masked = (expected & (FLAG_NONFINITE | FLAG_ROTATION)) != 0
    kept = ~np.isnan(out.F[masked]).all(axis=1) | ~np.all(
        [np.isnan(v[masked]).all(axis=1) for v in out.values.values()], axis=0)
    return VerifyReport(folder, prefix, model, " ".join([*cc, *flags]), len(valid),
                        len(expected) - len(valid), worst, where, mismatches, int(kept.sum()),
                        pose_error, float(latency))


def _joined(motions: list[Motion]) -> Motion:
    """The steps of ``motions`` one after another, as one Motion."""
    arrays = [np.concatenate([getattr(m, a) for m in motions])
              for a in ("position", "rotation", "velocity", "omega", "acceleration", "alpha")]
    return Motion.from_arrays(np.arange(arrays[0].shape[0], dtype=float), *arrays)
