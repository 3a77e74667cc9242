"""What a log's values say: the time counter (unit, wrap, jitter), units from value ranges, the
rate columns against the differentiated poses, the angle convention, and the rest pose.

Every threshold lives here with its reason. Arrays have the sample as leading axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gsfric.io.logs import UNITS, WRAP_STEPS
from gsfric.signal.local import local_polynomial_derivatives
from gsfric.signal.rotations import angular_rates, continuous_quaternions, quaternion_from_rpy
from gsfric.trajectory import time_unit_hint

DECREASING_SHARE = 0.01
"""Largest share of a time column's steps that may go down (wraps of a counter): a column that
drops more often is not a clock."""

MM_REACH = 20.0
"""Positions, in the unit they are written in, beyond which they are taken as mm, not m: no
motion platform moves its frame 20 m from its origin, and 20 mm is a small motion."""

DEGREE_REACH = 2 * math.pi
"""Angles beyond this (in the unit they are written in) are degrees: no log's roll, pitch or
yaw in rad leaves (-2 pi, 2 pi)."""

MATCH_CORRELATION = 0.9
"""Correlation, over the log, of a rate column with the derivative of its pose column above
which the column is taken as that rate: a rate of another axis or quantity correlates far less,
the log's own rate of the right one (its own filter, its delay of a sample) 0.95 or more."""

CHECK_SECONDS = 0.1
"""Span, s, of the local cubic that differentiates the poses for the checks and the rest: long
enough to average the pose noise of a 100 Hz log, short against a motion platform's motions
(2 Hz and below)."""

REST_SHARE = 0.01
"""A sample is still when its speed is below this share of the log's speed (99th percentile),
and its angular speed below the same share of the log's: a still platform's differentiated pose
noise stays below it, any motion worth logging above."""

EVEN_STAMPS = 1e-6
"""Jitter (share of the step) below which stamps are reported as evenly spaced: the rounding of
times written in decimal seconds."""

MIN_ROWS = 20
"""Fewest rows a log needs: the checks differentiate with local cubics of at least 7 rows,
and a record shorter than a few of them shows no motion to tell units and rates by."""

REST_SECONDS = 0.5
"""Shortest still stretch, s, reported as a rest."""


@dataclass(frozen=True)
class Clock:
    """A log's time column read as seconds.

    Attributes
    ----------
    t : ndarray, shape (N,)
        s from the first row, increasing (the counter unwrapped).
    unit : str
        The counter's unit (``gsfric.io.logs.UNITS["time"]``).
    unit_evidence : str
    wrap : int or None
        The modulus of an integer counter that wraps, or None.
    wrap_evidence : str
        The rows where it wraps, with the steps across them ("" without a wrap).
    jitter : float
        Largest deviation of a step from the median step, as a share of it.
    resets : tuple of int
        0-based rows whose time does not advance from the row before (after unwrapping): a
        counter that resets, or rows out of order.
    """

    t: np.ndarray
    unit: str
    unit_evidence: str
    wrap: int | None
    wrap_evidence: str
    jitter: float
    resets: tuple[int, ...]

    @property
    def step(self) -> float:
        """Median time step, s."""
        return float(np.median(np.diff(self.t)))


def looks_like_clock(values: np.ndarray) -> bool:
    """Whether a column's values (N,) go up at every step but a few drops (wraps)."""
    steps = np.diff(values.astype(float))
    if len(steps) < 2 or not np.all(np.isfinite(steps)):
        return False
    return bool(np.mean(steps <= 0) <= DECREASING_SHARE and np.median(steps) > 0)


def read_clock(values: np.ndarray, named_unit: str | None) -> Clock:
    """The time column's values (N,) as a ``Clock``: its unit from the name or else from the
    median step (the unit putting the sampling rate closest to a motion log's), its wrap from
    the drops of an integer counter."""
    raw = values.astype(float)
    steps = np.diff(raw)
    typical = float(np.median(steps[steps > 0]))
    wrap, wrap_evidence, counts = None, "", raw
    if np.any(steps <= 0) and np.all(raw == np.round(raw)):
        wrap, wrap_evidence = _wrap(raw, typical)
        counts = raw + np.concatenate([[0.0], np.cumsum((steps <= 0) * float(wrap or 0))])
    if named_unit is not None:
        unit, evidence = named_unit, "the column's name"
    else:
        unit = time_unit_hint(typical, "s") or "s"
        evidence = (f"the median step of {typical:.6g} gives "
                    f"{1.0 / (typical * UNITS['time'][unit]):.4g} Hz in {unit}, the unit "
                    "closest to a motion log's rate")
    t = (counts - counts[0]) * UNITS["time"][unit]
    dt = np.diff(t)
    resets = tuple(int(i) + 1 for i in np.flatnonzero(dt <= 0))
    median = float(np.median(dt))
    spread = float(np.max(np.abs(dt[dt > 0] - median)) / median) if median > 0 else 0.0
    return Clock(t, unit, evidence, wrap, wrap_evidence, spread, resets)


def _wrap(raw: np.ndarray, typical: float) -> tuple[int | None, str]:
    """The modulus (a power of 2 above the largest count) across which every drop is a step of
    at most ``WRAP_STEPS`` typical steps, and the evidence; (None, "") when there is none."""
    drops = np.flatnonzero(np.diff(raw) <= 0)
    bits = max(8, int(np.ceil(np.log2(raw.max() + 1))))
    for modulus in (2**b for b in range(bits, 65)):
        across = raw[drops + 1] + modulus - raw[drops]
        if np.all((across > 0) & (across <= WRAP_STEPS * typical)):
            shown = ", ".join(f"row {int(i) + 2}: {int(raw[i])} -> {int(raw[i + 1])}, a step of "
                              f"{int(a)} counts" for i, a in zip(drops[:3], across[:3]))
            return modulus, (f"{shown} across 2**{int(np.log2(modulus))}, against a "
                             f"typical {typical:g}")
        if modulus > raw.max() * 4:
            break
    return None, ""


def mm_reach(longest: float | None) -> float:
    """Positions beyond which they are mm (``length_unit``): ``MM_REACH``, or for a platform
    whose longest leg is ``longest`` m, twice that when it is more (no pose of it in m lies
    beyond)."""
    return MM_REACH if longest is None else max(MM_REACH, 2.0 * float(longest))


def length_unit(values: np.ndarray, limit: float = MM_REACH) -> tuple[str, str]:
    """m or mm for positions (N, 3) written without a unit, with the evidence: mm beyond
    ``limit`` (``mm_reach``)."""
    reach = float(np.nanmax(np.abs(values)))
    if reach > limit:
        return "mm", f"values up to {reach:.4g}, beyond {limit:g} m: mm"
    return "m", f"values within {reach:.4g}, below {limit:g} m: m"


def angle_unit(values: np.ndarray) -> tuple[str, str]:
    """deg or rad for angles (N, 3) written without a unit, with the evidence."""
    reach = float(np.nanmax(np.abs(values)))
    if reach > DEGREE_REACH:
        return "deg", f"|angle| up to {reach:.4g}, beyond 2 pi: deg"
    return "rad", f"|angle| within {reach:.4g}, below 2 pi: taken as rad"


def derivatives(t: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    """Value, first and second derivative (N, k) of y (N, k) at times t (N,), s, from local
    cubics of ``CHECK_SECONDS``."""
    step = float(np.median(np.diff(t)))
    window = max(7, round(CHECK_SECONDS / step) | 1)
    window = min(window, len(t) - (1 - len(t) % 2))
    return local_polynomial_derivatives(t, y, window, 3)


@dataclass(frozen=True)
class RateMatch:
    """A rate column against the derivative of its pose column.

    Attributes
    ----------
    correlation : float
        Pearson correlation of the column with the derivative.
    ratio : float
        Least-squares factor: column ~ ratio x derivative (derivative in SI).
    unit : str or None
        The unit of ``UNITS[quantity]`` whose factor to SI is closest to 1/ratio (None when
        the correlation is below ``MATCH_CORRELATION``).
    """

    correlation: float
    ratio: float
    unit: str | None

    def evidence(self, what: str) -> str:
        return (f"against {what}: correlation {self.correlation:.3f}, ratio {self.ratio:.4g}")


def match_rate(column: np.ndarray, derivative: np.ndarray, quantity: str) -> RateMatch:
    """How a rate column (N,) matches a derivative (N,) in SI, and the unit that makes them
    equal (``UNITS[quantity]``)."""
    c, d = column - column.mean(), derivative - derivative.mean()
    scale = float(np.sqrt(np.dot(c, c) * np.dot(d, d)))
    correlation = float(np.dot(c, d) / scale) if scale > 0 else 0.0
    ratio = float(np.dot(column, derivative) / np.dot(derivative, derivative)) if np.any(
        derivative) else 0.0
    unit = None
    if correlation >= MATCH_CORRELATION and ratio > 0:
        units = UNITS[quantity]
        unit = min(units, key=lambda u: abs(math.log(units[u] * ratio)))
    return RateMatch(correlation, ratio, unit)


def turning(t: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angular velocity and acceleration (N, 3 each), rad/s and rad/s^2, in the frame of the
    quaternions q (N, 4) at times t (N,), s."""
    q0, q1, q2 = derivatives(t, continuous_quaternions(q))
    return angular_rates(q0, q1, q2)


def convention_gap(angles: np.ndarray) -> float:
    """Largest angle, rad, between the rotations the angles (N, 3), rad, give as "xyz" and as
    "XYZ": how much the choice matters on this log."""
    a = quaternion_from_rpy(angles, "xyz")
    b = quaternion_from_rpy(angles, "XYZ")
    dots = np.clip(np.abs(np.sum(a * b, axis=1)), 0.0, 1.0)
    return float(2.0 * np.arccos(dots).max())


def still_samples(velocity: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Which samples (N,) are still (``REST_SHARE``): velocity (N, 3), m/s; angular velocity
    (N, 3), rad/s."""
    still = np.ones(len(velocity), bool)
    for rate in (np.linalg.norm(velocity, axis=1), np.linalg.norm(omega, axis=1)):
        top = float(np.percentile(rate, 99))
        if top > 0:
            still &= rate < REST_SHARE * top
    return still


def longest_run(flags: np.ndarray) -> tuple[int, int]:
    """First and one-past-last index of the longest run of True in flags (N,); (0, 0) if none."""
    padded = np.concatenate([[False], flags, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    if not len(edges):
        return 0, 0
    starts, stops = edges[::2], edges[1::2]
    k = int(np.argmax(stops - starts))
    return int(starts[k]), int(stops[k])
