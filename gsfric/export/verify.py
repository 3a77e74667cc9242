"""Checking an export (``gsfric export --verify``): build it, compare it with ``Evaluator``.

The folder is copied to a temporary directory and built there with the system compiler (``CC``,
default ``cc``) and the flags of its Makefile (``CFLAGS`` when set, as ``make`` reads it), with
a driver (``templates/verify.c.in``) that runs the library on states from a file. The states are
random valid ones (poses of ``gsfric.models.random_motion`` with random rates, kept where
``Evaluator`` flags nothing) and the reference motions (``gsfric.models.sinusoidal``,
``paper_motion``). Each output's error is relative to the largest magnitude of that output
(``max |C - Python| / max |Python|``; for ``coupling_change``, of F0: ``SCALE_OF``); the flags
must match exactly. The latency is the
median time of one ``<prefix>_actuator_forces`` call, measured in C.
"""

from __future__ import annotations

import importlib.resources
import os
import re
import shlex
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gsfric.errors import BuildError, InputError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.parameters import model_function
from gsfric.export.text import outputs
from gsfric.export.writer import CFLAGS, PLATFORM_FILE
from gsfric.models import paper_motion, random_motion, sinusoidal
from gsfric.platform.description import Platform
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.trajectory import Motion

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
        States compared (random valid ones and the reference motions' steps).
    worst_error : float
        The worst relative error over every output (``evaluate``) and F (``actuator_forces``).
    worst_output : str
        The output where it occurred.
    flag_mismatches : int
        Steps whose flags differ from ``Evaluator``'s.
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
    worst_error: float
    worst_output: str
    flag_mismatches: int
    pose_error: float
    latency_ns: float

    @property
    def ok(self) -> bool:
        """True when every error is within ``TOLERANCE`` and every flag matches."""
        return self.worst_error <= TOLERANCE and self.flag_mismatches == 0 and \
            self.pose_error <= TOLERANCE

    def lines(self) -> list[str]:
        """The report as ``gsfric export --verify`` prints it."""
        verdict = "ok" if self.ok else "FAILED"
        return [f"{self.folder}: {self.prefix} ({self.model} model), built with {self.compiler}",
                f"  {self.states} states: worst relative error {self.worst_error:.2e} "
                f"({self.worst_output}), goal <= {TOLERANCE:g}",
                f"  flags differing from Evaluator: {self.flag_mismatches} steps",
                f"  pose_state: largest difference {self.pose_error:.2e}",
                f"  latency of one {self.prefix}_actuator_forces call: "
                f"{self.latency_ns:.0f} ns (median)",
                f"  {verdict}"]


def _library(folder: Path) -> tuple[str, str]:
    """(prefix, model) of the export in ``folder``; ``InputError`` when it is not one."""
    if not folder.is_dir():
        raise InputError(f"--verify: {folder} is not a directory")
    for header in sorted(folder.glob("*.h")):
        found = re.search(r'^#define (\w+)_MODEL "(\w+)"$', header.read_text(), re.M)
        if found and (folder / f"{header.stem}.c").is_file() and \
                found.group(1) == header.stem.upper():
            return header.stem, found.group(2)
    raise InputError(f"--verify: {folder} holds no library written by `gsfric export`")


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
    parts = [_steps(random, keep) if keep.any() else random,
             sinusoidal(np.linspace(0.0, 2.0, 201)), paper_motion()]
    arrays = [np.concatenate([getattr(m, a) for m in parts])
              for a in ("position", "rotation", "velocity", "omega", "acceleration", "alpha")]
    return Motion.from_arrays(np.arange(arrays[0].shape[0], dtype=float), *arrays)


def _steps(motion: Motion, keep: np.ndarray) -> Motion:
    """The steps ``keep`` (a boolean mask) of ``motion``."""
    return Motion.from_arrays(motion.t[keep], motion.position[keep], motion.rotation[keep],
                              motion.velocity[keep], motion.omega[keep],
                              motion.acceleration[keep], motion.alpha[keep])


def write_inputs(work: Path, motion: Motion) -> list[str]:
    """The driver's input files of ``motion`` in ``work`` (states.bin, poses.bin); the driver's
    arguments but the number of timed rounds (outputs written into ``work``)."""
    x = state_array(motion)
    x.astype(np.float64).tofile(work / "states.bin")
    q = quaternion_from_rotation(motion.rotation)
    poses = np.concatenate([motion.position, q, motion.velocity, motion.omega,
                            motion.acceleration, motion.alpha], axis=1)
    np.ascontiguousarray(poses, dtype=np.float64).tofile(work / "poses.bin")
    return ["states.bin", str(len(motion)), "poses.bin", "outputs.bin", "forces.bin",
            "flags.bin", "pose_states.bin"]


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


def _compare(work: Path, function: str, result, n: int, size: int) -> tuple[float, str, int]:
    """(worst error, its output, flag mismatches) of the driver's files against ``result``."""
    outs = outputs(function)
    raw = np.fromfile(work / "outputs.bin", dtype=np.uint8).reshape(n, size)
    total = sum(o.size for o in outs)
    values = raw[:, :8 * total].copy().view(np.float64)
    flags = raw[:, 8 * total:8 * total + 4].copy().view(np.int32)[:, 0]
    worst, where, start = 0.0, "", 0
    for o in outs:
        reference = getattr(result, SCALE_OF[o.name]) if o.name in SCALE_OF else None
        err = _relative(values[:, start:start + o.size], getattr(result, o.name).reshape(n, -1),
                        reference)
        start += o.size
        if err >= worst:
            worst, where = err, o.name
    F = np.fromfile(work / "forces.bin").reshape(n, -1)
    err = _relative(F, result.F)
    if err > worst:
        worst, where = err, "F of actuator_forces"
    step_flags = np.fromfile(work / "flags.bin", dtype=np.int32)
    mismatches = int(np.sum(flags != result.flag) + np.sum(step_flags != result.flag))
    return worst, where, mismatches


def verify_library(folder, n_random: int = 2000, seed: int = 0, rounds: int = ROUNDS,
                   flags=None) -> VerifyReport:
    """Build the export in ``folder`` and compare it with ``Evaluator`` (see the module);
    ``flags``: the compiler's flags (None: ``compiler_flags()``)."""
    folder = Path(folder)
    prefix, model = _library(folder)
    platform = Platform.from_toml(folder / PLATFORM_FILE)
    cc = compiler()
    motion = check_motions(platform, n_random, seed)
    result = Evaluator(platform).evaluate_quiet(motion)
    n = len(motion)
    with tempfile.TemporaryDirectory(prefix="gsfric-verify-") as tmp:
        work = Path(tmp)
        flags = compiler_flags() if flags is None else list(flags)
        driver = build(folder, prefix, work, cc, flags)
        names = [*write_inputs(work, motion), str(rounds)]
        run = subprocess.run([str(driver), *names], capture_output=True, text=True, cwd=work)
        if run.returncode:
            raise BuildError(f"--verify: the check program failed (exit {run.returncode})")
        size, latency = run.stdout.split()
        worst, where, mismatches = _compare(work, model_function("eval", model), result, n,
                                            int(size))
        pose = np.fromfile(work / "pose_states.bin").reshape(n, -1)
        pose_error = float(np.max(np.abs(pose - state_array(motion))))
    return VerifyReport(folder, prefix, model, " ".join([*cc, *flags]), n, worst,
                        where, mismatches, pose_error, float(latency))
