"""Synthetic measured data: a platform with hidden effects, driven along a motion, with noise.

The true system is a platform (a TOML file or a ``Platform``) with hidden effects switched on
(``Platform.with_effect``). It is evaluated along an analytic motion (by default
``excitation_motion``: six sinusoids with random amplitudes, frequencies up to 2 Hz and
phases, so every leg reverses many times and inertial loads differ from static ones), and what
a rig would record is written:

* ``t, x, y, z, qw, qx, qy, qz``: the pose, optionally with pose noise (independent Gaussian
  noise of standard deviation ``pose_noise`` on x, y, z in m, and a random rotation with
  components of the same standard deviation in rad applied to the orientation);
* ``F1..F6``: the actuator forces of the true system (friction and hidden effects included, as
  a load cell in series with the actuator reads them) plus force noise of standard deviation
  ``noise``, white or AR(1) with coefficient ``noise_correlation`` (stationary from the first
  sample: ``e_t = phi e_(t-1) + sqrt(1 - phi^2) noise w_t``);
* ``D1..D6``: the true leg lengths (encoders are taken as exact).

Everything random comes from ``numpy.random.default_rng(seed)``: the same arguments give the
same file.

A hidden effect is given as ``"name:param=value,..."`` (parameters left out take the catalog's
defaults, except ``stroke_friction.reference``, which defaults to the motion's mean leg length)
or as a mapping ``{name: {param: value}}``.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.signal import lfilter

from gsfric._checks import as_count, as_float, short, suggest
from gsfric.errors import InputError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.io.files import check_outputs
from gsfric.io.readers import check_force_range, read_trajectory
from gsfric.io.tables import table_kind, write_table
from gsfric.models import HOME_HEIGHT, platform_from, reference_platform, sinusoidal
from gsfric.platform.catalog import EFFECTS, apply_sensor, sensor_parameters
from gsfric.platform.description import Platform
from gsfric.platform.usable import check_gaps, check_poses, home_height
from gsfric.signal.rotations import quaternion_multiply, rotation_from_quaternion
from gsfric.trajectory import Motion

__all__ = ["SyntheticData", "parse_effect", "synthesize", "run_synth", "effect_contributions",
           "ar1_noise", "excitation_motion"]

EXCITATION_FREQUENCY = (0.3, 2.0)
"""Range of the excitation motion's frequencies, Hz."""

def excitation_motion(rng: np.random.Generator, t: np.ndarray, scale: float = 1.0,
                      frequency: tuple[float, float] = EXCITATION_FREQUENCY,
                      platform: Platform | None = None) -> Motion:
    """A random six-axis motion that excites the effects the workflow looks for.

    Like ``gsfric.models.random_motion`` (amplitudes within its workspace-safe range: 30% to
    100% of (0.06, 0.06, 0.05) m and (0.1, 0.1, 0.12) rad, times ``scale``), with frequencies
    drawn in ``frequency`` (Hz): every leg reverses several times a second, so Coulomb-like
    friction is seen in both directions and at every speed, and the accelerations are large
    enough for the inertial loads to differ from the static ones (payload mass against leg
    weight or sensor offsets).

    Parameters
    ----------
    rng : numpy.random.Generator
    t : ndarray, shape (N,)
        Times, s.
    scale : float
        Multiplies every amplitude.
    frequency : (float, float)
        Range of the frequencies, Hz.
    platform : Platform, optional
        The motion carried to this platform's size (``similar_pose``): about its home pose,
        the translations scaled by its stroke, the rotations by its stroke against its radius,
        the frequencies so that the accelerations stay the reference's. Default (and for the
        reference platform): as drawn.

    Returns
    -------
    Motion
    """

    amplitude = rng.uniform(0.3, 1.0, 6) * np.array([0.06, 0.06, 0.05, 0.1, 0.1, 0.12]) * scale
    freq = rng.uniform(frequency[0], frequency[1], 6)
    phase = rng.uniform(0.0, 2 * np.pi, 6)
    similar = similar_pose(platform)
    amplitude[:3] *= similar.reach
    amplitude[3:] *= similar.turn
    return sinusoidal(np.asarray(t, float), amplitude, freq / similar.pace, phase,
                      centre=similar.centre)


@dataclass(frozen=True)
class Similar:
    """The reference platform's synthetic motions carried to another platform
    (``similar_pose``).

    Attributes
    ----------
    centre : (float, float, float)
        Centre of the motion, m: the platform's home pose (``home_height``) less the
        reference's offset from its own, scaled as the translations.
    reach : float
        Factor of the translations: the ratio of the strokes.
    turn : float
        Factor of the rotations: the legs' length change per stroke the reference's (a
        rotation moves a leg by about the platform's radius times its angle), at most 1.
    pace : float
        Factor of the periods, the square root of ``reach``: accelerations (amplitude over
        period squared) stay the reference's, and with them the inertial loads against the
        weight, whatever the size.
    """

    centre: tuple[float, float, float]
    reach: float
    turn: float
    pace: float


def similar_pose(platform: Platform | None) -> Similar:
    """The synthetic motions on ``platform`` (``Similar``): exactly the reference's (centre
    ``HOME_HEIGHT``, factors 1) on the reference platform, and on a platform without a
    stroke."""
    reference = reference_platform()
    home, home_ref = home_height(platform) if platform else None, home_height(reference)
    if home is None or home_ref is None:
        return Similar((0.0, 0.0, HOME_HEIGHT), 1.0, 1.0, 1.0)
    span = platform.geometry.stroke[1] - platform.geometry.stroke[0]
    span_ref = reference.geometry.stroke[1] - reference.geometry.stroke[0]
    reach = span / span_ref
    radius = float(np.linalg.norm(platform.geometry.platform_joints, axis=1).max())
    radius_ref = float(np.linalg.norm(reference.geometry.platform_joints, axis=1).max())
    turn = min(1.0, reach * radius_ref / radius) if radius > 0 else 1.0
    # the terms vanish exactly on the reference platform: its motions stay as drawn
    height = HOME_HEIGHT + (home - home_ref) + (HOME_HEIGHT - home_ref) * (reach - 1.0)
    return Similar((0.0, 0.0, height), reach, turn, float(np.sqrt(reach)))


@dataclass
class SyntheticData:
    """Synthetic measured data and the truth behind it.

    Attributes
    ----------
    frame : pandas.DataFrame
        The measured-data table: ``t, x, y, z, qw, qx, qy, qz, F1..F6, D1..D6``.
    platform : Platform
        The true system, hidden effects included.
    model : Platform
        The same platform without the hidden effects given to ``synthesize`` (the model a
        researcher would start from).
    motion : Motion
        The exact motion (before pose noise).
    forces : ndarray, shape (N, 6)
        Noise-free actuator forces of the true system, N.
    noise : ndarray, shape (N, 6)
        The force noise added, N.
    effects : dict[str, dict[str, float]]
        The hidden effects with every parameter resolved.
    contributions : dict[str, ndarray]
        Each hidden effect's contribution to F, (N, 6), N: F with all hidden effects minus F
        with that one switched off.
    sizes : dict[str, float]
        Effect size of each hidden effect: RMS of its contribution over all legs and samples
        divided by the noise standard deviation (``inf`` without noise).
    """

    frame: object
    platform: Platform
    model: Platform
    motion: Motion
    forces: np.ndarray
    noise: np.ndarray
    effects: dict[str, dict[str, float]]
    contributions: dict[str, np.ndarray] = field(default_factory=dict)
    sizes: dict[str, float] = field(default_factory=dict)


def parse_effect(text: str) -> tuple[str, dict[str, float]]:
    """Parse ``"name:param=value,param=value"`` (or just ``"name"``) into (name, parameters).

    Raises
    ------
    InputError
        Unknown effect or parameter, or a value that is not a number.
    """

    name, _, rest = str(text).strip().partition(":")
    name = name.strip()
    if name not in EFFECTS:
        raise InputError(f"effect {short(name)}: unknown effect{suggest(name, EFFECTS)}; "
                         f"known: {', '.join(EFFECTS)}")
    params: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq:
            raise InputError(f"effect {name}: expected param=value, got {short(item)}")
        if key not in EFFECTS[name]:
            raise InputError(f"effect {name}: unknown parameter {short(key)}"
                             f"{suggest(key, EFFECTS[name])}; known: {', '.join(EFFECTS[name])}")
        try:
            params[key] = float(value)
        except ValueError:
            raise InputError(f"effect {name}: parameter {key} = {short(value.strip())} "
                             "is not a number") from None
        if not np.isfinite(params[key]):
            raise InputError(f"effect {name}: parameter {key} must be finite")
    return name, params


def _effects(effects) -> dict[str, dict[str, float]]:
    if effects is None:
        return {}
    if isinstance(effects, Mapping):
        out = {}
        for name, params in effects.items():
            parsed, _ = parse_effect(name)
            out[parsed] = {str(k): float(v) for k, v in dict(params or {}).items()}
            parse_effect(f"{parsed}:" + ",".join(f"{k}={v}" for k, v in out[parsed].items()))
        return out
    if isinstance(effects, str):
        effects = [effects]
    out = {}
    for text in effects:
        name, params = parse_effect(text)
        if name in out:
            raise InputError(f"effect {name}: given twice")
        out[name] = params
    return out


def ar1_noise(rng: np.random.Generator, shape: tuple[int, int], sigma: float,
              phi: float) -> np.ndarray:
    """Stationary AR(1) noise along axis 0 with marginal standard deviation ``sigma``.

    Parameters
    ----------
    rng : numpy.random.Generator
    shape : (N, k)
    sigma : float
        Marginal standard deviation.
    phi : float
        AR(1) coefficient, ``0 <= phi < 1`` (0: white noise).

    Returns
    -------
    ndarray, shape (N, k)
    """

    if not 0.0 <= phi < 1.0:
        raise InputError(f"noise_correlation: must be in [0, 1), got {phi:g}")
    w = rng.standard_normal(shape)
    if phi == 0.0:
        return sigma * w
    scale = np.sqrt(1.0 - phi * phi)
    w[1:] *= scale
    # w[0] keeps unit variance: the stationary start
    return sigma * lfilter([1.0], [1.0, -phi], w, axis=0, zi=np.zeros((1, shape[1])))[0]


def _rotation_noise(rng: np.random.Generator, n: int, sigma: float) -> np.ndarray:
    """Quaternions (n, 4) of small random rotations, rotation-vector components N(0, sigma^2)."""
    rv = rng.normal(0.0, sigma, (n, 3))
    angle = np.linalg.norm(rv, axis=1, keepdims=True)
    half = 0.5 * angle
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = np.where(angle > 0, rv / np.where(angle > 0, angle, 1.0), 0.0)
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=1)


def effect_contributions(platform: Platform, motion: Motion,
                         names: Iterable[str]) -> dict[str, np.ndarray]:
    """Each named effect's contribution to the actuator forces, (N, 6) N.

    The contribution of effect e is ``F(platform) - F(platform without e)``.
    """
    full = read_forces(platform, motion)
    out = {}
    for name in names:
        out[name] = full - read_forces(platform.without_effects(name), motion)
    return out


def read_forces(platform: Platform, motion: Motion) -> np.ndarray:
    """What the load cells read, (N, 6) N: the actuator forces of ``platform`` along
    ``motion`` with its sensor effects (force_scale, time_offset; gsfric.platform.catalog) applied."""

    F = Evaluator(platform).actuator_forces(state_array(motion))
    gains, delay = sensor_parameters(platform.effects)
    return apply_sensor(np.asarray(motion.t, float), F, gains, delay)


def synthesize(platform: Platform | None = None, effects=(), *, motion: Motion | None = None,
               samples: int = 4000, rate: float = 200.0, noise: float = 0.1,
               noise_correlation: float = 0.0, pose_noise: float = 0.0,
               seed: int = 0) -> SyntheticData:
    """Synthetic measured data with hidden effects and noise (see the module docstring).

    Parameters
    ----------
    platform : Platform, optional
        The model (default ``reference_platform()``); its own ``effects`` stay on and are
        hidden as well.
    effects : iterable of str, or mapping
        Hidden effects, ``"name:param=value,..."`` or ``{name: {param: value}}``.
    motion : Motion, optional
        The motion to drive (its own times are used; ``samples`` and ``rate`` are then
        ignored). Default: ``excitation_motion(rng, t, platform=...)`` with
        ``t = arange(samples) / rate``, carried to the platform's size.
    samples : int
        Number of samples (>= 20).
    rate : float
        Sampling rate, Hz.
    noise : float
        Force noise standard deviation, N (>= 0).
    noise_correlation : float
        AR(1) coefficient of the force noise, in [0, 1).
    pose_noise : float
        Standard deviation of the position noise, m, and of the orientation noise, rad.
    seed : int
        Seed of every random draw.

    Returns
    -------
    SyntheticData
    """
    _check_arguments(samples if motion is None else motion, rate, noise, noise_correlation,
                     pose_noise)
    model = platform_from(platform)
    rng = np.random.default_rng(seed)
    if motion is None:
        t = np.arange(int(samples)) / float(rate)
        motion = excitation_motion(rng, t, platform=model)
    hidden = _effects(effects)
    true = _true_platform(model, hidden, motion)
    forces = read_forces(true, motion)
    lengths = Evaluator(true).evaluate(motion).D
    e = ar1_noise(rng, (len(motion), 6), float(noise), float(noise_correlation))
    frame = _measured_frame(rng, motion, forces + e, lengths, pose_noise)
    resolved = {name: dict(true.effects[name]) for name in hidden}
    contributions = effect_contributions(true, motion, hidden)
    sizes = {name: (float(np.sqrt(np.mean(c**2))) / noise if noise > 0 else float("inf"))
             for name, c in contributions.items()}
    return SyntheticData(frame=frame, platform=true, model=model, motion=motion,
                         forces=forces, noise=e, effects=resolved,
                         contributions=contributions, sizes=sizes)


MAX_SAMPLES = 1_000_000
"""Most samples of a synthetic record: ``synthesize`` holds the record, the model's outputs
along it and each effect's contribution in memory, about 2 kB a sample (2 GB at this
count); a longer record is refused before any is drawn."""


def _check_arguments(samples, rate, noise, noise_correlation, pose_noise) -> None:
    """``InputError`` (``InputTypeError`` for what is not a number) for a number of samples
    (or a ``Motion`` to drive), a rate or a noise level ``synthesize`` refuses."""
    if isinstance(samples, Motion):
        if len(samples) > MAX_SAMPLES:
            raise InputError(f"motion: {len(samples):,} steps, more than the {MAX_SAMPLES:,} "
                             "a synthetic record holds in memory (about 2 kB a sample)")
    else:
        samples = as_count(samples, "samples", minimum=1)
        if samples < 20:
            raise InputError(f"samples: at least 20 are needed, got {samples}")
        if samples > MAX_SAMPLES:
            raise InputError(f"samples: {samples:,} is more than the {MAX_SAMPLES:,} a "
                             "synthetic record holds in memory (about 2 kB a sample); a "
                             "shorter record")
        if as_float(rate, "rate") <= 0:
            raise InputError(f"rate: must be a positive number of Hz, got {rate!r}")
    as_float(noise, "noise", minimum=0.0)
    as_float(pose_noise, "pose_noise", minimum=0.0)
    if not 0.0 <= as_float(noise_correlation, "noise_correlation") < 1.0:
        raise InputError(f"noise_correlation: must be in [0, 1), got {noise_correlation!r}")


def _true_platform(model: Platform, hidden: dict[str, dict[str, float]],
                   motion: Motion) -> Platform:
    """``model`` with the ``hidden`` effects switched on; ``stroke_friction.reference``, when
    not given, is the mean leg length of ``model`` along ``motion`` (m)."""
    if "stroke_friction" in hidden and "reference" not in hidden["stroke_friction"]:
        lengths = Evaluator(model).evaluate(motion).D
        hidden["stroke_friction"]["reference"] = float(lengths.mean())
    true = model
    for name, params in hidden.items():
        true = true.with_effect(name, **params)
    return true


def _measured_frame(rng: np.random.Generator, motion: Motion, forces: np.ndarray,
                    lengths: np.ndarray, pose_noise: float) -> pd.DataFrame:
    """The measured-data table ``t, x, y, z, qw, qx, qy, qz, F1..F6, D1..D6`` of the measured
    ``forces`` (N, 6) N and ``lengths`` (N, 6) m, the pose with noise of standard deviation
    ``pose_noise`` (m, rad) drawn from ``rng``."""
    position = motion.position.copy()
    quaternion = motion.quaternion()
    if pose_noise > 0:
        position = position + rng.normal(0.0, pose_noise, position.shape)
        quaternion = quaternion_multiply(_rotation_noise(rng, len(motion), pose_noise),
                                         quaternion)
        quaternion *= np.where(quaternion[:, :1] < 0, -1.0, 1.0)
    columns = {"t": motion.t}
    columns.update(zip(("x", "y", "z"), position.T))
    columns.update(zip(("qw", "qx", "qy", "qz"), quaternion.T))
    columns.update((f"F{i + 1}", forces[:, i]) for i in range(6))
    columns.update((f"D{i + 1}", lengths[:, i]) for i in range(6))
    return pd.DataFrame(columns)


def run_synth(out: str | os.PathLike[str], platform_file: str | os.PathLike[str] | None = None,
              effects=(), samples: int = 4000, rate: float = 200.0, noise: float = 0.1,
              noise_correlation: float = 0.0, pose_noise: float = 0.0, seed: int = 0,
              motion_file: str | os.PathLike[str] | None = None) -> Path:
    """``gsfric synth``: write synthetic measured data to ``out`` (CSV or Parquet).

    Parameters are those of ``synthesize``; ``platform_file`` is a platform TOML (default the
    reference platform); ``motion_file`` a trajectory file to drive (``gsfric excite``'s, for
    example) instead of the random motion, its own times replacing ``samples`` and ``rate``.
    Returns the path written (atomically).
    """

    out = Path(out)
    check_outputs([out], {"platform": platform_file, "motion": motion_file})
    table_kind(out)
    platform = platform_from(platform_file)
    motion = None if motion_file is None else _motion_file(motion_file, platform)
    data = synthesize(platform, effects, motion=motion, samples=samples, rate=rate,
                      noise=noise, noise_correlation=noise_correlation, pose_noise=pose_noise,
                      seed=seed)
    _check_readable(data, f"{out} (noise = {noise:g} N, pose_noise = {pose_noise:g} m)")
    write_table(data.frame, out)
    return out


def _motion_file(path, platform: Platform) -> Motion:
    """The motion of a trajectory file, checked against the platform as every command that
    evaluates a file checks it (its poses within the stroke, its gaps), naming the file."""
    motion = read_trajectory(path)
    check_poses(platform, motion.position, motion.rotation, motion.t, str(path))
    check_gaps(motion.t, str(path))
    return motion


def _check_readable(data: SyntheticData, where: str) -> None:
    """``InputError`` when gsfric would refuse the record ``data`` on reading it (the noise
    put the forces or the poses out of what a rig can measure): it is not written."""
    frame = data.frame
    where = f"{where}: the record would be refused when read"
    check_force_range(frame[[f"F{i}" for i in range(1, 7)]].to_numpy(), where)
    quaternion = frame[["qw", "qx", "qy", "qz"]].to_numpy()
    check_poses(data.platform, frame[["x", "y", "z"]].to_numpy(),
                rotation_from_quaternion(quaternion / np.linalg.norm(quaternion, axis=1,
                                                                     keepdims=True)),
                frame["t"].to_numpy(), where)
