"""Whether a record's poses and forces can be this platform's at all: the one check, before any
physics, that ``simulate`` and ``discover`` run on what they read.

Data that are mostly unusable for the platform are an ``InputError`` that says how far off they
are and which option fixes it, never a result: poses mostly outside the stroke (a controller's
frame with another origin, another rig, mm given as m), speeds no hexapod of this size reaches,
and forces a thousand times the platform's model's along the same poses (N declared as kN).
Gaps in the sample times are reported (``check_gaps``), and an error when they hold most of
the record. Problems of the force channels themselves (constant, saturated, held samples) are
an error for every command that fits a model to them (``check_force_channels``).
"""

from __future__ import annotations

import warnings

import numpy as np

from gsfric.errors import DataWarning, InputError, StepFlagError
from gsfric.platform.description import Platform

MOSTLY = 0.5
"""Fraction of the steps outside the stroke above which the record is unusable: the model
flags those steps and every statistic of the rest would stand on fewer than half."""

FLAGGED_LIMIT = 0.10
"""Fraction of the steps flagged by the model above which ``simulate`` fails unless told to
keep them (``--keep-flagged``): a rig's own log flags a step only where the motion leaves the
platform's stroke or nears a singularity, which a sound record of a real rig does for a few
moments at most; a tenth of the record flagged says that the platform or the log's frame is
not the rig's (its sizes, the offset of its poses), and the forces of the rest belong to
another machine."""

UNIT_RATIO = 30.0
"""Factor between the measured load (mean over the steps of the summed magnitudes of F1..F6)
and the model's along the same poses (``models.check_measured_forces``) beyond which the forces
are in another unit: effects the model lacks and a prior's wrong masses move the load by a
factor of a few at most; a wrong unit (N and kN) puts it 1000 times off."""

SIGN_SHARE = 0.5
"""A measured record whose summed actuator force (mean over the steps of F1 + ... + F6) has the
opposite sign of the model's and more than ``SIGN_SHARE`` of its size is read with the opposite
sign convention: the legs carry the weight, so the sum is the static load's; a model error
(masses, friction) moves it by a fraction of itself, a reversed sign by twice its size."""

SPEED_STROKES = 50.0
"""Strokes per second: a median speed of the platform above this many times the legs' stroke
(d_max - d_min) per second is implausible for the platform (no hexapod crosses its stroke in
20 ms): positions in mm given as m, or times in ms given as s. The median, because a wrong unit
scales every step while a few glitches (steps flagged one by one) do not move it."""

GAP_STEPS = 20.0
"""A time step above this many times the median step is a gap in the record (samples lost, a
pause of the logger): jittered or randomly spaced stamps almost never reach it (an exponential
spacing once in a million steps), a lost block of samples always does."""

FIXES = ("a pose offset and axes in the log format ([offset], axes; see docs/howto/read-a-log.md), "
         "`gsfric platform --template` with the rig's sizes, or --platform with the rig's "
         "platform file")


HELD_RUN = 5
"""Consecutive equal values of a noisy force channel that make a dropout (held or zeroed
samples): a load cell's noise makes equal neighbours rare (``data_problems``)."""


def check_force_channels(t: np.ndarray, forces: np.ndarray, where: str = "",
                         held_run: int = HELD_RUN) -> None:
    """``InputError`` naming the first problem of the measured force channels that no model
    effect explains (``data_problems``): ``discover`` and ``identify`` refuse such data rather
    than fit them. t (N,) s; forces (N, 6) N."""
    problems = data_problems(t, forces, held_run=held_run)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        prefix = f"{where}: " if where else "measured data: "
        raise InputError(f"{prefix}{problems[0]}{more}; not a model effect, fix or cut the "
                         "data")


def data_problems(t: np.ndarray, forces: np.ndarray, *, held_run: int) -> list[str]:
    """Problems of measured force data that no model effect can explain, one line each.

    A channel that is constant, or that sits at its extreme value on a run of samples
    (saturation), or that repeats one value on a run of at least ``held_run`` samples
    (``Settings.held_run``) where it otherwise never does (a dropout recorded as held or
    zeroed samples), or a gap in the sample times (dropout: a step above 1.5 times the
    median). t (N,) s; forces (N, k) N.
    """
    out = []
    forces = np.asarray(forces, float)
    for i in range(forces.shape[1]):
        f = forces[:, i]
        name = f"F{i + 1}"
        if not np.isfinite(f).any():
            out.append(f"{name}: no finite value (a column of NaN)")
            continue
        spread = float(np.ptp(f))
        if spread <= 1e-12 * max(1.0, float(np.abs(f).max())):
            out.append(f"{name}: constant ({f[0]:.6g} N in every row): a dead channel")
            continue
        saturated = False
        for edge in (f.max(), f.min()):
            at = f == edge
            if at.sum() >= max(5, len(f) // 200):
                runs = np.diff(np.flatnonzero(np.diff(np.r_[0, at.astype(int), 0])))[::2]
                if runs.size and runs.max() >= 5:
                    row = int(np.flatnonzero(at)[0]) + 1
                    out.append(f"{name}: saturated at {edge:.6g} N ({int(at.sum())} rows, "
                               f"first row {row})")
                    saturated = True
                    break
        held = None if saturated else _held_run(f, held_run)
        if held is not None:
            row, length = held
            out.append(f"{name}: the same value ({f[row]:.6g} N) in {length} rows from row "
                       f"{row + 1}: a dropout (held or zeroed samples)")
    steps = np.diff(np.asarray(t, float))
    if steps.size:
        median = float(np.median(steps))
        gaps = np.flatnonzero(steps > 1.5 * median)
        if gaps.size:
            missing = int(np.round(np.sum(steps[gaps]) / median)) - gaps.size
            out.append(f"t: dropout of about {missing} samples at {gaps.size} place(s), first "
                       f"after row {int(gaps[0]) + 1} (t = {float(t[gaps[0]]):.6g} s)")
    return out


def _held_run(f: np.ndarray, held_run: int) -> tuple[int, int] | None:
    """The longest run (first index, length) of at least ``held_run`` equal
    consecutive values of a channel whose neighbouring samples otherwise differ (a noisy load
    cell: fewer than 1% equal neighbours; a coarsely quantised channel repeats values and is
    not judged)."""
    same = np.diff(f) == 0
    edges = np.diff(np.r_[0, same.astype(np.int8), 0])
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    if starts.size == 0:
        return None
    runs = stops - starts + 1                     # samples in each run of equal values
    short = runs < held_run
    if np.sum(runs[short] - 1) > 0.01 * same.size or short.all():
        return None                               # quantised, or nothing held
    k = int(np.argmax(runs))
    return int(starts[k]), int(runs[k])


def home_height(platform: Platform) -> float | None:
    """Height, m, of the platform frame's origin above the base frame's at which the legs are
    at mid-stroke with the platform level (None without a stroke)."""
    g = platform.geometry
    if g.stroke is None:
        return None
    gap = np.asarray(g.platform_joints, float) - np.asarray(g.base_joints, float)
    mid = 0.5 * (g.stroke[0] + g.stroke[1])
    across = np.hypot(gap[:, 0], gap[:, 1])
    if np.any(across >= mid):
        return None
    return float(np.mean(np.sqrt(mid**2 - across**2) - gap[:, 2]))


def check_poses(platform: Platform, position: np.ndarray, rotation: np.ndarray,
                t: np.ndarray | None = None, where: str = "") -> None:
    """Raise ``InputError`` when most poses are outside the platform's stroke, or the platform
    moves implausibly fast for its size.

    Parameters
    ----------
    platform : Platform
    position : ndarray, shape (N, 3)
        Platform frame origin in the base frame, m.
    rotation : ndarray, shape (N, 3, 3)
    t : ndarray, shape (N,), optional
        Times, s (for the speed check).
    where : str
        What the message starts with (a file name).
    """
    prefix = f"{where}: " if where else ""
    stroke = platform.geometry.stroke
    position = np.asarray(position, float)
    if stroke is not None and len(position):
        lengths = platform.leg_lengths(position, np.asarray(rotation, float))
        outside = np.any((lengths < stroke[0]) | (lengths > stroke[1]), axis=1)
        if np.mean(outside) > MOSTLY:
            raise InputError(prefix + _stroke_message(platform, position, lengths, outside))
    if stroke is not None and t is not None and len(t) > 2:
        _check_speed(prefix, np.asarray(t, float), position, stroke[1] - stroke[0])


def _stroke_message(platform: Platform, position: np.ndarray, lengths: np.ndarray,
                    outside: np.ndarray) -> str:
    lo, hi = platform.geometry.stroke
    heave = float(np.mean(position[:, 2]))
    text = (f"{int(outside.sum())} of {len(outside)} steps have a leg outside the stroke: leg "
            f"lengths {lengths.min():.3g}-{lengths.max():.3g} m vs stroke {lo:.3g}-{hi:.3g} m; "
            f"heave mean {heave:.3g} m")
    home = home_height(platform)
    if home is not None:
        text += f" vs home height {home:.3g} m"
        if abs(home - heave) > 0.25 * (hi - lo):
            text += f" (a z offset of {home - heave:.3g} m?)"
    reach = float(np.max(np.abs(position)))
    if home is not None and reach > 300.0 * max(abs(home), hi):
        text += "; the poses look like mm: declare x=mm,y=mm,z=mm (--units)"
    return f"{text}; the poses are not this platform's: fix with {FIXES}"


def _check_speed(prefix: str, t: np.ndarray, position: np.ndarray, stroke: float) -> None:
    with np.errstate(all="ignore"):
        speed = np.linalg.norm(np.diff(position, axis=0), axis=1) / np.diff(t)
    speed = speed[np.isfinite(speed)]
    if not speed.size or stroke <= 0:
        return
    fast = float(np.median(speed))
    limit = SPEED_STROKES * stroke
    if fast > limit:
        hint = " (positions in mm declared as m? --units x=mm,y=mm,z=mm)" \
            if fast / 1000.0 <= limit else ""
        raise InputError(f"{prefix}the platform moves at {fast:.4g} m/s (median over the "
                         f"steps), implausible for a stroke of {stroke:.3g} m (more than "
                         f"{limit:.3g} m/s){hint}; check the units of t and x, y, z")


def check_forces(model_load: float, forces: np.ndarray, where: str = "",
                 limit: float = UNIT_RATIO) -> None:
    """Raise ``InputError`` when measured actuator forces (N, 6), N, are in another unit than
    N: their load (the mean over the steps of sum |F_i|) more than ``limit`` times
    ``model_load``, the platform's model's along the same steps
    (``gsfric.models.check_measured_forces``), or less than its inverse."""
    prefix = f"{where}: " if where else ""
    weight = float(model_load)
    forces = np.asarray(forces, float)
    if not weight > 0 or forces.ndim != 2 or forces.shape[1:] != (6,) or not len(forces) \
            or not np.isfinite(forces).all():
        return
    load = float(np.mean(np.sum(np.abs(forces), axis=1)))
    ratio = load / weight
    if ratio > limit:
        advice = ("forces in N declared as kN? declare F1..F6 in N, or give"
                  if ratio > 300 else "give")
        raise InputError(f"{prefix}forces: their load (mean of the summed |F1..F6|, "
                         f"{load:.4g} N) is {ratio:.3g} times the model's along the same "
                         f"poses ({weight:.4g} N): {advice} the rig's masses (--platform)")
    if ratio < 1.0 / limit:
        advice = ("forces in kN read as N? declare F1..F6 = kN (--units F1=kN,...), or give"
                  if ratio < 1.0 / 300 else "give")
        raise InputError(f"{prefix}forces: their load (mean of the summed |F1..F6|, "
                         f"{load:.4g} N) is only {ratio:.3g} times the model's along the same "
                         f"poses ({weight:.4g} N): {advice} the rig's masses (--platform)")


def check_force_sign(measured: np.ndarray, model: np.ndarray, where: str = "") -> None:
    """Raise ``InputError`` when measured actuator forces (N, 6), N, run opposite to the
    model's ``model`` (N, 6) along the same motion: their mean summed force of the other sign
    and more than ``SIGN_SHARE`` of the model's size (``F > 0`` pushes the platform away from
    the base). Only where the model's mean summed force is at least ``SIGN_SHARE`` of its
    mean summed magnitude: the legs carry a load of one sign, the weight."""
    prefix = f"{where}: " if where else ""
    got = float(np.mean(np.sum(measured, axis=1)))
    expected = float(np.mean(np.sum(model, axis=1)))
    # only where the model's legs carry a net load of one sign (not a platform whose legs
    # pull against each other, nor one moved by its inertia alone)
    carried = abs(expected) >= SIGN_SHARE * float(np.mean(np.sum(np.abs(model), axis=1)))
    if carried and np.isfinite(got) and got * expected < 0 \
            and abs(got) > SIGN_SHARE * abs(expected):
        raise InputError(f"{prefix}forces: F1..F6 sum to {got:.4g} N on average where the "
                         f"model's sum to {expected:.4g} N: the load cells' sign is the "
                         "opposite of gsfric's (F > 0 pushes the platform away from the "
                         "base); negate F1..F6")


def check_flagged_share(flagged: int, steps: int, where: str = "", ranges: str = "") -> None:
    """Raise ``StepFlagError`` when more than ``FLAGGED_LIMIT`` of the ``steps`` are flagged
    (``flagged`` of them); ``ranges`` says where they lie (time ranges)."""
    if not steps or flagged <= FLAGGED_LIMIT * steps:
        return
    prefix = f"{where}: " if where else ""
    lie = f" in {ranges}" if ranges else ""
    raise StepFlagError(
        f"{prefix}{flagged} of {steps} steps ({100.0 * flagged / steps:.3g} %) are flagged by "
        f"the model{lie}: more than the limit of {100.0 * FLAGGED_LIMIT:.3g} % (the forces of "
        "a record flagged this much are likely another platform's: a leg outside the stroke "
        f"says the platform or the poses' frame is not the rig's); fix with {FIXES}, or keep "
        "them with --keep-flagged; no output written")


def check_gaps(t: np.ndarray, where: str = "") -> None:
    """Warn (``DataWarning``) of gaps in the sample times (N,), s: steps above ``GAP_STEPS``
    times the median, across which the motion is differentiated as if it went on smoothly;
    ``InputError`` when the gaps hold more time than the samples do (the record is mostly
    missing)."""
    steps = np.diff(np.asarray(t, float))
    if steps.size < 2:
        return
    median = float(np.median(steps))
    gaps = np.flatnonzero(steps > GAP_STEPS * median)
    if median <= 0 or not gaps.size:
        return
    prefix = f"{where}: " if where else ""
    lost = float(np.sum(steps[gaps])) - gaps.size * median
    first = int(gaps[0])
    text = (f"{prefix}t: {gaps.size} gap(s) in the sample times, {lost:.4g} s in all (about "
            f"{lost / median:.0f} samples), the first after row {first + 1} "
            f"(t = {float(t[first]):.6g} s, a step of {float(steps[first]):.4g} s against "
            f"{median:.4g} s)")
    if lost > float(np.asarray(t, float)[-1] - t[0]) - lost:
        raise InputError(f"{text}: the record is mostly missing; cut it at the gaps")
    warnings.warn(f"{text}: the motion is differentiated across them; cut the record at the "
                  "gaps for forces there", DataWarning, stacklevel=2)
