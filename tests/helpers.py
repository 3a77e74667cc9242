"""Helpers shared by the tests: perturbed platforms, random states, the chain's inputs, 1/f
noise."""

from __future__ import annotations

import contextlib
import fcntl
import sys
from pathlib import Path

import numpy as np
import pandas as pd

import gsfric
from gsfric import models
from gsfric.compiled.manifest import layout
from gsfric.compiled.state import state_layout
from gsfric.evaluation import flags
from gsfric.evaluation.evaluator import state_array
from gsfric.evaluation.parameters import effect_vector, parameter_vector
from gsfric.trajectory import ROTATION_TOL

def editable_build_folder() -> Path | None:
    """The build folder of the editable install (meson-python's finder), if gsfric is one."""
    for finder in sys.meta_path:
        folder = getattr(finder, "_build_path", None)
        if folder and getattr(finder, "_name", None) == "gsfric":
            return Path(folder)
    return None


@contextlib.contextmanager
def build_folder_lock(exclusive: bool):
    """A lock on the editable install's build folder (none without one), shared or exclusive.

    Every process that imports gsfric from the editable install checks the build there
    (meson-python runs ninja), and that check fails while another process reconfigures the
    folder, as building the wheel from it does: tests hold the lock shared, the wheel's build
    exclusively."""
    folder = editable_build_folder()
    if folder is None:
        yield
        return
    with open(folder / "gsfric-tests.lock", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        yield


PAPER_MISPRINTS = {
    (1, 10, "MfrE5", "-0.0133", ("digits", "small")),   # an order of magnitude low
    (1, 12, "MfrE1", "-0.0131", ("digits", "small")),   # an order of magnitude low
    (1, 19, "MfrE2", "-0.1430", ("digits",)),           # an extra digit
    (2, 15, "MfrC5", "-0.1216", ("digits",)),           # an extra digit
    (2, 26, "MfrC6", "-0.188", ("large",)),             # far above the rest of Table 2
    (3, 8, "Ffr5", "-0.7247", ("digits",)),             # an extra digit
    (3, 14, "Ffr1", "-0.6234", ("digits",)),            # an extra digit
    (3, 27, "Ffr5", "-0.0687", ("digits", "small")),    # an order of magnitude low
}
"""Misprints of the paper's tables, found by reading them (docs/reference/errata.md, E32):
(table, step, column, as printed, kinds in alphabetical order)."""


def perturbed_platform(rng: np.random.Generator, legs_model: str = "rigid") -> gsfric.Platform:
    """The reference platform with moved joints, tilted axes, full inertias and a payload offset."""
    base = models.reference_platform("paper")
    g = base.geometry
    axes = g.universal_axes + rng.uniform(-0.3, 0.3, (6, 3))

    def inertia(scale):
        """A full inertia of a rigid body (its principal moments obey the triangle
        inequality: the added trace bounds the largest by the sum of the other two)."""
        a = rng.normal(size=(3, 3)) * scale
        full = a @ a.T + np.eye(3) * scale
        return full + np.trace(full) * np.eye(3)

    return (base.with_geometry(base_joints=g.base_joints + rng.uniform(-0.03, 0.03, (6, 3)),
                               platform_joints=g.platform_joints
                               + rng.uniform(-0.03, 0.03, (6, 3)),
                               universal_axes=axes / np.linalg.norm(axes, axis=1)[:, None])
            .with_body(inertia=inertia(0.1), com=rng.uniform(-0.03, 0.03, 3),
                       payload_mass=rng.uniform(1, 5), payload_inertia=inertia(0.02),
                       payload_com=rng.uniform(-0.05, 0.05, 3))
            .with_legs(model=legs_model, lower_inertia=inertia(0.01),
                       upper_inertia=inertia(0.01), lower_mass=rng.uniform(0.3, 2),
                       upper_mass=rng.uniform(0.3, 2)))


def random_states(rng: np.random.Generator, n: int) -> np.ndarray:
    """States (n, 24) sampled from a random smooth motion about the home pose."""
    t = np.sort(rng.uniform(0, 5, n))
    return state_array(models.random_motion(rng, t))


def chain_values(platform, x: np.ndarray, Q=None, K=None) -> dict:
    """The chain's named input blocks for a platform and states x (N, 24)."""
    values = {}
    for vec, name in ((x, "x"), (parameter_vector(platform), "P")):
        for b in layout("eval", name):
            size = int(np.prod(b["shape"]))
            values[b["name"]] = vec[..., b["offset"]:b["offset"] + size]
    values["effects"] = effect_vector(platform) if Q is None else Q
    if K is not None:
        for b in layout("eval_paper", "K"):
            size = int(np.prod(b["shape"]))
            values[b["name"]] = K[b["offset"]:b["offset"] + size]
    return values


def with_every_effect(rng: np.random.Generator, platform: gsfric.Platform) -> gsfric.Platform:
    """Every catalog effect switched on with a random plausible parameter."""
    return platform.with_effects({
        "stribeck": {"static": rng.uniform(0.5, 3), "velocity": rng.uniform(0.005, 0.05)},
        "seal_friction": {"force": rng.uniform(0.5, 3)},
        "quadratic_drag": {"coefficient": rng.uniform(1, 20)},
        "stroke_friction": {"slope": rng.uniform(-5, 5), "reference": 0.8},
        "payload_offset": {"x": 0.02, "y": -0.03, "z": 0.01},
        "sensor_bias": {f"b{i}": rng.uniform(-1, 1) for i in range(1, 7)},
        "joint_friction_coupling": {"scale": 1.0},
        "leg_weight": {"lower_mass": 0.3, "upper_mass": 0.2},
        "bushing_friction": {"coefficient": 0.1, "spacing": 0.08},
    })


def pink_noise(rng: np.random.Generator, n: int, legs: int = 6, extra: int = 2000) -> np.ndarray:
    """1/f noise (n, legs) of unit standard deviation per column: white noise shaped in
    frequency, with periods up to ``n + extra`` samples (a record cut from a longer one)."""
    spec = np.fft.rfft(rng.standard_normal((n + extra, legs)), axis=0)
    f = np.fft.rfftfreq(n + extra)
    spec[1:] /= np.sqrt(f[1:, None])
    spec[0] = 0.0
    e = np.fft.irfft(spec, n + extra, axis=0)[extra:]
    return e / e.std(axis=0)


def trajectory_frame(n: int = 400, rate: float = 100.0) -> pd.DataFrame:
    """A trajectory file's columns (t, x, y, z and a quaternion) of ``models.sinusoidal`` sampled
    ``n`` times at ``rate`` Hz."""
    t = np.arange(n) / rate
    motion = models.sinusoidal(t)
    frame = pd.DataFrame({"t": t})
    frame[["x", "y", "z"]] = motion.position
    frame[["qw", "qx", "qy", "qz"]] = motion.quaternion()
    return frame


def numpy_flags(x: np.ndarray, arrays: dict, stroke: tuple[float, float] | None) -> np.ndarray:
    """The flags of ``compiled/batch.c`` computed again in NumPy from the outputs and the
    limits of ``gsfric.evaluation.flags``: the independent reference of the tests.

    Parameters
    ----------
    x : ndarray (N, 24)
        The states evaluated.
    arrays : dict of name -> ndarray (N, size)
        Every output of the evaluation; a non-finite step's, or one whose rotation block is
        not a rotation, are set to NaN here.
    stroke : (float, float) or None
        As for ``flag_spec``.

    Returns
    -------
    ndarray (N,) int64
    """
    n = x.shape[0]
    flag = np.zeros(n, dtype=np.int64)
    finite = np.isfinite(x).all(axis=1)
    for v in arrays.values():
        finite &= np.isfinite(v.reshape(n, -1)).all(axis=1)
    D = arrays["D"]
    if stroke is not None:
        lo, hi = stroke
        flag[((D < lo) | (D > hi)).any(axis=1)] |= flags.FLAG_STROKE
    flag[(arrays["s2"] < flags.UNIVERSAL_LIMIT).any(axis=1)] |= flags.FLAG_UNIVERSAL
    flag[arrays["h"][:, 0] < flags.SINGULAR_LIMIT] |= flags.FLAG_SINGULAR
    if "coupling_change" in arrays:
        limit = flags.COUPLING_TOLERANCE * (1.0 + np.abs(arrays["F0"]))
        flag[(finite & (np.abs(arrays["coupling_change"]) > limit).any(axis=1))] |= \
            flags.FLAG_COUPLING
    flag[~finite] |= flags.FLAG_NONFINITE
    T = x[:, state_layout().rotation].reshape(n, 3, 3)
    with np.errstate(invalid="ignore"):
        gram = np.abs(np.einsum("nji,njk->nik", T, T) - np.eye(3)).reshape(n, 9)
        rotation = (np.nan_to_num(gram, nan=0.0) > ROTATION_TOL).any(axis=1) | \
            (np.linalg.det(T) < 0)
    flag[rotation] = flags.FLAG_ROTATION                 # its only flag, outputs NaN
    for v in arrays.values():
        v[~finite | rotation] = np.nan
    return flag
