"""Platform variants of a sweep: parameter ranges, drawn at random (Latin hypercube) or on an
even grid, and Monte-Carlo tolerances applied to the nominal platform (``--vary``, ``--grid``,
``--tolerance``)."""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.stats import qmc

from gsfric._checks import as_float, short, suggest
from gsfric.errors import InputError, InputTypeError
from gsfric.platform.description import MAX_GRAVITY, Platform
from gsfric.sweep.workspace import parse_interval

SCALAR_PARAMETERS = (
    "gravity", "platform.mass", "platform.payload_mass", "legs.lower_mass", "legs.upper_mass",
    "friction.joint_viscous", "friction.joint_coulomb", "friction.joint_radius",
    "friction.prismatic_viscous", "friction.prismatic_coulomb",
    "geometry.base_scale", "geometry.platform_scale")
"""Parameters a variant may change: ranges (uniform, Latin hypercube) or tolerances (normal).
``geometry.*_scale`` scale the joints' horizontal positions (the joint circles' radii)."""

MAX_MASS = 1e5
"""The largest mass a range may reach, kg: 100 t, beyond the heaviest motion-simulator
payloads (about 15 t); larger values are a unit error or overflow the forces."""
MAX_MU = 2.0
"""The largest Coulomb coefficient a range may reach: no dry contact exceeds about 1.5."""
MAX_VISCOUS = 1e6
"""The largest viscous coefficient a range may reach (N s/m, N m s/rad): a joint this damped
does not move."""
MIN_SCALE, MAX_SCALE = 0.1, 10.0
"""The range of the joint circles' scales: at 0 the joints coincide and the legs meet at a
point (a singular mechanism); beyond 10 the legs lie nearly flat."""

VALID_RANGES = {
    "gravity": (0.0, MAX_GRAVITY), "platform.mass": (0.0, MAX_MASS),
    "platform.payload_mass": (0.0, MAX_MASS), "legs.lower_mass": (0.0, MAX_MASS),
    "legs.upper_mass": (0.0, MAX_MASS), "friction.joint_viscous": (0.0, MAX_VISCOUS),
    "friction.joint_coulomb": (0.0, MAX_MU), "friction.joint_radius": (0.0, 1.0),
    "friction.prismatic_viscous": (0.0, MAX_VISCOUS), "friction.prismatic_coulomb": (0.0, MAX_MU),
    "geometry.base_scale": (MIN_SCALE, MAX_SCALE),
    "geometry.platform_scale": (MIN_SCALE, MAX_SCALE)}
"""The values a range of each of ``SCALAR_PARAMETERS`` may span (inclusive), in its unit:
a platform outside them is degenerate or absurd (the constants above give the reasons; a
joint's friction radius beyond 1 m is no joint)."""

JOINT_TOLERANCES = ("geometry.base_joints", "geometry.platform_joints")
"""Tolerances only: a normal error of this standard deviation (m) on every joint coordinate."""


def parse_vary(vary: Mapping | None, tolerances: Mapping | None
               ) -> tuple[dict[str, tuple[float, float]], dict[str, float]]:
    """The checked ranges (name -> (min, max)) and tolerances (name -> standard deviation)."""
    for label, given in (("vary", vary), ("tolerances", tolerances)):
        if given is not None and not isinstance(given, Mapping):
            raise InputTypeError(f"{label}: expected a dict of parameter name -> "
                                 f"{'(min, max)' if label == 'vary' else 'standard deviation'}"
                                 f", got {short(given)}")
    vary = dict(vary or {})
    tolerances = dict(tolerances or {})
    ranges = {}
    for name, value in vary.items():
        if name not in SCALAR_PARAMETERS:
            raise InputError(f"vary: {name}: unknown parameter"
                             f"{suggest(str(name), SCALAR_PARAMETERS)}; one of "
                             f"{', '.join(SCALAR_PARAMETERS)}")
        ranges[name] = parse_interval(value, f"vary: {name}")
        lo, hi = VALID_RANGES[name]
        if ranges[name][0] < lo or ranges[name][1] > hi:
            raise InputError(f"vary: {name}: {ranges[name][0]:g}:{ranges[name][1]:g} leaves "
                             f"the valid range {lo:g}:{hi:g}")
        if ranges[name][0] == ranges[name][1]:
            raise InputError(f"vary: {name}: {ranges[name][0]:g}:{ranges[name][1]:g} is one "
                             "value, and every variant would be the same: give MIN < MAX, or "
                             "set the value in the platform file")
    sds = {}
    for name, value in tolerances.items():
        if name not in SCALAR_PARAMETERS + JOINT_TOLERANCES:
            raise InputError(f"tolerance: {name}: unknown parameter"
                             f"{suggest(str(name), SCALAR_PARAMETERS + JOINT_TOLERANCES)}")
        sds[name] = as_float(value, f"tolerance: {name}", minimum=0.0)
    return ranges, sds


MAX_GRID_VARIANTS = 100_000
"""A grid of more variants than this is refused: its count grows as the power of the number
of varied parameters, and a mistyped count would start hours of evaluation."""


def _grid(ranges: Mapping, per: int) -> np.ndarray:
    """Every combination of ``per`` evenly spaced values of each range, (per^k, k), as unit
    fractions of the ranges (0 and 1 included; 0.5 for one value)."""
    if isinstance(per, bool) or not isinstance(per, (int, np.integer)) or per < 1:
        raise InputError(f"grid: expected an integer >= 1 (values per parameter), got "
                         f"{short(per)}")
    if per ** len(ranges) > MAX_GRID_VARIANTS:
        raise InputError(f"grid: {per} values of {len(ranges)} parameters make "
                         f"{per ** len(ranges)} variants (more than {MAX_GRID_VARIANTS}); "
                         "give fewer values")
    axis = np.linspace(0.0, 1.0, per) if per > 1 else np.array([0.5])
    return np.array(list(itertools.product(axis, repeat=len(ranges))))


def _value(platform: Platform, name: str) -> float:
    """The nominal value of a scalar parameter (1 for the ``*_scale`` ones)."""
    if name == "gravity":
        return platform.gravity
    section, key = name.split(".")
    if key.endswith("_scale"):
        return 1.0
    return getattr({"platform": platform.platform, "legs": platform.legs,
                    "friction": platform.friction}[section], key)


def _apply(platform: Platform, values: Mapping[str, Any]) -> Platform:
    """The platform with the parameters ``values`` (name -> value or joint error (6, 3))."""
    body, legs, friction, geometry = {}, {}, {}, {}
    gravity = platform.gravity
    g = platform.geometry
    for name, value in values.items():
        if name == "gravity":
            gravity = float(value)
            continue
        section, key = name.split(".")
        if key == "base_scale":
            geometry["base_joints"] = geometry.get("base_joints", g.base_joints) * \
                np.array([value, value, 1.0])
        elif key == "platform_scale":
            geometry["platform_joints"] = geometry.get("platform_joints", g.platform_joints) * \
                np.array([value, value, 1.0])
        elif key in ("base_joints", "platform_joints"):
            geometry[key] = geometry.get(key, getattr(g, key)) + np.asarray(value)
        else:
            {"platform": body, "legs": legs, "friction": friction}[section][key] = float(value)
    out = platform.replace(gravity=gravity)
    if body:
        out = out.with_body(**body)
    if legs:
        out = out.with_legs(**legs)
    if friction:
        out = out.with_friction(**friction)
    if geometry:
        out = out.with_geometry(**geometry)
    return out


def _draw(ranges: Mapping, sds: Mapping, nominal: Mapping, unit: np.ndarray, k: int,
          rng: np.random.Generator) -> dict[str, Any]:
    """The parameter values of drawn variant ``k + 1``: its Latin-hypercube row ``unit[k]``
    over the ranges, then the normal errors of the tolerances."""
    values: dict[str, Any] = {}
    for j, (name, (lo, hi)) in enumerate(ranges.items()):
        values[name] = lo + unit[k, j] * (hi - lo)
    for name, sd in sds.items():
        if name in JOINT_TOLERANCES:
            values[name] = rng.normal(0.0, sd, (6, 3))
        else:
            values[name] = max(0.0, values.get(name, nominal[name]) + rng.normal(0.0, sd))
    return values


def make_variants(platform: Platform, vary: Mapping | None = None,
                  tolerances: Mapping | None = None, samples: int = 16,
                  seed: int = 0, grid: int | None = None) -> tuple[list[Platform], list[dict]]:
    """Platform variants: the nominal one, then ``samples`` drawn ones (or a grid).

    Parameters
    ----------
    platform : Platform
        The nominal platform (variant 0).
    vary : dict name -> (min, max)
        Uniform ranges (Latin hypercube over all of them); names in ``SCALAR_PARAMETERS``.
    tolerances : dict name -> standard deviation
        Normal errors added to the nominal (or ranged) value: scalars in their unit, joints
        (``JOINT_TOLERANCES``) in m on every coordinate. Values are truncated at 0.
    samples : int
        Drawn variants (ignored without ``vary`` and ``tolerances``, and with ``grid``).
    seed : int
    grid : int, optional
        Instead of random draws: ``grid`` evenly spaced values of each range, ends included,
        every combination (``grid ** len(vary)`` variants, the first parameter varying
        slowest); not with ``tolerances`` (random by nature).

    Returns
    -------
    platforms : list of Platform, length 1 + samples (1 without ranges or tolerances)
    table : list of dict
        Each variant's parameter values (joint errors as their largest magnitude, m).
    """
    ranges, sds = parse_vary(vary, tolerances)
    names = list(dict.fromkeys([*ranges, *sds]))
    nominal = {n: (_value(platform, n) if n not in JOINT_TOLERANCES else 0.0) for n in names}
    platforms, table = [platform], [{"variant": 0, **nominal}]
    if grid is not None and not ranges:
        raise InputError("grid: give the ranges to lay the grid over (vary)")
    if not names:
        return platforms, table
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
        raise InputError(f"variants: expected an integer >= 1, got {short(samples)}")

    rng = np.random.default_rng(seed)
    if grid is not None:
        if sds:
            raise InputError("grid: not with tolerances, which are random draws; sweep the "
                             "grid, or draw the tolerances with the ranges at random")
        unit = _grid(ranges, grid)
        samples = len(unit)
    else:
        unit = (qmc.LatinHypercube(d=len(ranges), seed=seed).random(samples) if ranges
                else np.zeros((samples, 0)))
    for k in range(samples):
        values = _draw(ranges, sds, nominal, unit, k, rng)
        row: dict[str, Any] = {"variant": k + 1}
        for name in names:
            v = values[name]
            row[name] = float(np.abs(v).max()) if name in JOINT_TOLERANCES else float(v)
        try:
            platforms.append(_apply(platform, values))
        except InputError as error:
            raise type(error)(f"variant {k + 1}: {error}") from None
        table.append(row)
    return platforms, table
