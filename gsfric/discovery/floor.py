"""The noise floor the verdict compares the residual with: the load cells' own noise plus what
the pose noise puts into the model's forces, from evidence that a model error cannot fake.

Force part, by precedence:

1. ``specified``: the user's sensor specification (``--force-noise``, N, one value or one per
   leg; or ``force_noise`` in the measurement-settings TOML of ``--column-map``);
2. ``noise record``: a recording at rest (``--noise-record``): each force channel's standard
   deviation after removing its mean;
3. ``estimated``: the level of the force channels less the final model's forces above a
   quarter of the sample rate (``gsfric.signal.noise.spectral_noise_std``): the median over
   short segments (a friction step, a jump at a reversal, occupies few of them) and over the
   frequencies (a line of mains interference, the motion's harmonics occupy few of them). A
   noise that is not white reads at its level there: its slow part (AR, pink noise) is not
   in this floor, and the report says so.

Pose part: the recorded poses' white noise (``white_noise_std`` of the positions and of the
quaternions) drawn ``Settings.floor_draws`` times, passed through the very differentiating
filters the motion was made with, and through the final model: the RMS change of its forces
per leg over the sliding pairs (the model is linear in the noise at this size but for the
sign of a speed near zero, and those pairs are not sliding).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gsfric.errors import InputError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.io.logs import FORCES, UNITS, LogFormat
from gsfric.io.readers import read_trajectory
from gsfric.io.tables import numeric_columns, read_columns
from gsfric.platform.description import Platform
from gsfric.signal.noise import ForceNoise, spectral_noise_std, white_noise_std
from gsfric.signal.rotations import (
    angular_rates,
    continuous_quaternions,
    quaternion_from_rotation,
    rotation_from_quaternion,
)
from gsfric.signal.windows import savgol_adaptive
from gsfric.trajectory import Motion, taken_as_even


@dataclass
class NoiseFloor:
    """The noise floor of the verdict: the force noise and the pose noise in the forces.

    Attributes
    ----------
    force : list of float
        The load cells' noise per leg, N.
    force_source : str
        One of ``FORCE_SOURCES``.
    force_detail : str
        How the force part was obtained, in words.
    pose : list of float
        The pose noise propagated into each leg's model force, N (RMS over the sliding pairs).
    pose_source : str
        How the pose part was obtained, in words.
    total : list of float
        ``sqrt(force^2 + pose^2)`` per leg, N.
    rms : float
        RMS over the legs of ``total``, N: what the residual's RMS is compared with.
    residual_over_floor : float
        RMS of the final residual (sliding pairs) over ``rms``.
    """

    force: list[float]
    force_source: str
    force_detail: str
    pose: list[float]
    pose_source: str
    total: list[float]
    rms: float
    residual_over_floor: float = 0.0

    @property
    def trusted(self) -> bool:
        """Whether the force part is the user's (a specification or a recording at rest)."""
        return self.force_source != "estimated"


def estimated_force_noise(residual: np.ndarray, step: float, segment: int) -> np.ndarray:
    """The force noise per leg (6,), N, of the measured forces less the final model's (M, 6):
    ``spectral_noise_std`` above a quarter of the sample rate."""
    return spectral_noise_std(residual, step, 0.25 / step, segment)


def pose_noise_forces(platform: Platform, motion: Motion,
                      poses: tuple[np.ndarray, np.ndarray] | None, rows: slice,
                      valid: np.ndarray, draws: int, seed: int = 0, *, n_threads: int
                      ) -> tuple[np.ndarray, str]:
    """The pose noise's part of each leg's model force, (6,) N, and how it was obtained.

    Parameters
    ----------
    platform : Platform
        The final model.
    motion : Motion
        The measured motion (made from ``poses`` with its filters, when it was).
    poses : (ndarray (N, 3), ndarray (N, 3, 3)) or None
        The recorded positions (m) and rotations.
    rows : slice
        The used samples; ``valid`` (M, 6) their sliding pairs.
    draws : int
        Noise draws (``Settings.floor_draws``).
    seed : int
        Seed of the draws.
    n_threads : int
        Threads of the compiled evaluation (at least 1).
    """
    if poses is None:
        return np.zeros(6), "not estimated (no recorded poses)"
    position = np.asarray(poses[0], float)
    q = continuous_quaternions(quaternion_from_rotation(np.asarray(poses[1], float)))
    sigma_p, sigma_q = white_noise_std(position), white_noise_std(q)
    t = np.asarray(motion.t, float)
    filters = motion.sample_filters() if taken_as_even(motion) else None
    if filters is not None and len(filters[0][0][0]) != len(t):
        filters = None
    if filters is None or len(position) != len(t):
        return np.zeros(6), "not estimated (the motion was not differentiated from these poses)"
    evaluator = Evaluator(platform, n_threads=n_threads)
    clean = evaluator.actuator_forces(state_array(motion))[rows]
    rng = np.random.default_rng(seed)
    step = (t[-1] - t[0]) / (len(t) - 1)
    total = np.zeros(6)
    for _ in range(draws):
        p = savgol_adaptive(position + rng.normal(size=position.shape) * sigma_p, filters[0], step)
        qq = savgol_adaptive(q + rng.normal(size=q.shape) * sigma_q, filters[1], step)
        omega, alpha = angular_rates(*qq)
        noisy = Motion.from_arrays(t, p[0], rotation_from_quaternion(qq[0]), p[1], omega, p[2],
                                   alpha)
        d = (evaluator.actuator_forces(state_array(noisy))[rows] - clean) * valid
        total += np.sum(d ** 2, axis=0) / np.maximum(valid.sum(axis=0), 1)
    how = (f"recorded pose noise ({1e6 * float(np.sqrt(np.mean(sigma_p ** 2))):.3g} um, "
           f"quaternion {float(np.sqrt(np.mean(sigma_q ** 2))):.3g}) through the motion's "
           f"differentiating filters and the final model ({draws} draws)")
    return np.sqrt(total / draws), how


def record_motion(path: str | os.PathLike[str], fmt: LogFormat) -> tuple[float, float]:
    """The largest travel (m) and turn (rad) of a noise record's poses from its first sample."""
    motion = read_trajectory(path, log_format=fmt)
    travel = np.linalg.norm(motion.position - motion.position[0], axis=1)
    cos = (np.einsum("ij,nij->n", motion.rotation[0], motion.rotation) - 1.0) / 2.0
    turn = np.arccos(np.clip(cos, -1.0, 1.0))
    return float(travel.max()), float(turn.max())


def noise_floor(force: ForceNoise | None, estimate: np.ndarray, pose: np.ndarray,
                pose_source: str, residual_rms: float) -> NoiseFloor:
    """The floor from the user's force noise (or, without it, the ``estimate`` (6,), N) and the
    pose part (6,), N; ``residual_rms`` the final residual's RMS, N."""
    if force is not None:
        f, source, detail = np.asarray(force.std, float), force.source, force.detail
    else:
        f, source = np.asarray(estimate, float), "estimated"
        detail = ("median spectral level of the measured forces less the final model's above "
                  "a quarter of the sample rate, over short segments (robust to lines and "
                  "to transients; the slow part of a coloured noise is not in it)")
    total = np.sqrt(f ** 2 + np.asarray(pose, float) ** 2)
    rms = float(np.sqrt(np.mean(total ** 2)))
    return NoiseFloor([float(v) for v in f], source, detail, [float(v) for v in pose],
                      pose_source, [float(v) for v in total], rms,
                      residual_rms / rms if rms > 0 else float("inf"))


def read_noise_record(path: str | os.PathLike[str], log_format: LogFormat | None = None
                      ) -> ForceNoise:
    """The load cells' noise from a recording at rest: a CSV or Parquet file with F1..F6 (or
    the columns and units a log's format maps to them); InputError naming the file and the
    column for a missing or bad one. A record with pose columns carries how far they move
    (``ForceNoise.motion``, checked by ``ForceNoise.check_at_rest``)."""
    fmt = log_format or LogFormat()
    found = dict(zip(*read_columns(path)))
    names = [fmt.columns.get(name, name) for name in FORCES]
    missing = [n for n in names if n not in found]
    if missing:
        raise InputError(f"{path}: no column {missing[0]!r}: a noise record needs the force "
                         "channels F1..F6")
    motion = None
    if all(fmt.columns.get(name, name) in found for name in ("t", "x", "y", "z")):
        motion = record_motion(path, fmt)
    columns = numeric_columns(Path(path), [found[n] for n in names], list(FORCES))
    scale = np.array([UNITS["force"][fmt.units.get(name, "N")] for name in FORCES])
    forces = np.stack([columns[name] for name in FORCES], axis=1) * scale
    return replace(ForceNoise.from_record(forces, f"noise record {path}"), motion=motion)
