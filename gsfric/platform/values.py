"""The checks of a platform description's values: inertia tensors, joint axes, the stroke, the
``[limits]`` table, and warnings for values in a likely wrong unit or place.

``gsfric.platform.description`` builds each part of a ``Platform`` through these; every problem
is an ``InputError`` naming the dotted key, every implausible value a ``GsfricWarning``.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping

import numpy as np

from gsfric._checks import as_array, as_float, short, suggest
from gsfric.errors import GsfricWarning, InputError

LIMITS = {
    "actuator_force": "N, actuator force: a number (|F| <= value) or [min, max]",
    "spherical_load": "N, rating of the spherical joints, |R_E|",
    "universal_load": "N, rating of the universal joints, |R_C|",
    "universal_moment": "N m, torsion moment the universal joints carry, |M_C|",
    "prismatic_load": "N, transverse load rating of the prismatic joints, |R_3|",
    "prismatic_moment": "N m, moment rating of the prismatic joints, |M_3|",
}
"""Keys of the optional ``[limits]`` table: the ratings ``gsfric sweep`` checks loads against."""

_SYMMETRY_TOL = 1e-9
"""Relative asymmetry (and negative eigenvalue) of an inertia tensor taken for rounding."""

_UNIT_TOL = 1e-12
"""Departure of an axis's length from 1 below which it is kept as given (not normalised)."""

_TRIANGLE_TOL = 1e-9
"""Relative excess of the principal moments' triangle inequality taken for rounding."""

MAX_JOINT_DISTANCE = 100.0
"""A joint farther than this from its frame's origin, m, draws a ``GsfricWarning``: lengths
given in millimetres rather than metres. The largest hexapods (test rigs for ships and
buildings) measure tens of metres; a desktop hexapod's joints in millimetres already lie
hundreds of "metres" out."""


def inertia_tensor(value: object, name: str) -> np.ndarray:
    """A (3, 3) symmetric positive semi-definite inertia tensor, kg m^2."""
    inertia = as_array(value, (3, 3), name)
    scale = float(np.abs(inertia).max())
    asymmetry = np.abs(inertia - inertia.T)
    if asymmetry.max() > _SYMMETRY_TOL * scale:
        i, j = np.unravel_index(np.argmax(asymmetry), asymmetry.shape)
        raise InputError(f"{name}: not symmetric ([{i}][{j}] = {inertia[i, j]:g} but "
                         f"[{j}][{i}] = {inertia[j, i]:g})")
    moments = np.linalg.eigvalsh(inertia)
    smallest = float(moments.min())
    if smallest < -_SYMMETRY_TOL * scale:
        raise InputError(f"{name}: not positive semi-definite (smallest eigenvalue {smallest:g})")
    check_principal_moments(moments, name, stacklevel=6)
    return inertia


def check_principal_moments(moments, name: str, stacklevel: int = 2) -> None:
    """A ``GsfricWarning`` naming ``name`` when the three principal moments of inertia
    (kg m^2, any order) break the triangle inequality (the largest more than the sum of the
    others, beyond ``_TRIANGLE_TOL`` of it): no rigid body has them (a typing or unit error)."""
    low, mid, high = sorted(float(m) for m in moments)
    if high > low + mid + _TRIANGLE_TOL * abs(high):
        warnings.warn(f"{name}: principal moments {low:.4g}, {mid:.4g}, {high:.4g} kg m^2 "
                      f"violate the triangle inequality ({high:.4g} > {low:.4g} + {mid:.4g}): "
                      "no rigid body has them; check the inertia (about the centre of mass, "
                      "kg m^2)", GsfricWarning, stacklevel=stacklevel)


def default_universal_axes(base_joints: np.ndarray) -> np.ndarray:
    """The default first axes of the universal joints, shape (6, 3).

    Each is the horizontal unit vector tangent to the base circle at C_i:
    ``normalize(e_z x C_i)``, which has no z component.

    Parameters
    ----------
    base_joints : array, shape (6, 3)
        The points C_i in the base frame, m.
    """
    base_joints = np.asarray(base_joints, dtype=float)
    axes = np.stack([-base_joints[:, 1], base_joints[:, 0], np.zeros(len(base_joints))], axis=1)
    norms = np.linalg.norm(axes, axis=1)
    for i, n in enumerate(norms):
        if n < 1e-12:
            raise InputError(f"geometry.universal_axes: base joint {i + 1} lies on the z axis, "
                             "so no default axis exists; give universal_axes")
    return axes / norms[:, None]


def unit_axes(value: object, name: str) -> np.ndarray:
    """Six axes (6, 3) of unit length, read-only; a given length off 1 is normalised."""
    axes = np.array(as_array(value, (6, 3), name))
    for i, axis in enumerate(axes):
        n = float(np.linalg.norm(axis))
        if n < 1e-12:
            raise InputError(f"{name}[{i}]: axis of zero length")
        if abs(n - 1.0) > _UNIT_TOL:
            axes[i] = axis / n
    axes.setflags(write=False)
    return axes


def stroke_range(value: object) -> tuple[float, float] | None:
    """``geometry.stroke``: the leg lengths (d_min, d_max), m, or None (not given)."""
    if value is None:
        return None
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 2:
        raise InputError(f"geometry.stroke: expected [d_min, d_max], got {short(value)}")
    d_min = as_float(value[0], "geometry.stroke[0]", minimum=0.0)
    d_max = as_float(value[1], "geometry.stroke[1]")
    if d_min >= d_max:
        raise InputError(f"geometry.stroke: d_min = {d_min:g} must be less than d_max = {d_max:g}")
    return (d_min, d_max)


def check_plausible(g, legs, body) -> None:
    """Warnings (``GsfricWarning``) for values that are possible but most likely in the wrong
    unit or place: joints beyond ``MAX_JOINT_DISTANCE`` (mm given as m), leg centres of mass
    beyond the longest leg, the body's centre of mass far outside the platform.

    Parameters
    ----------
    g, legs, body : Geometry, Legs, Body
        A platform's ``geometry``, ``legs`` and ``platform`` (``gsfric.platform.description``).
    """
    for name, joints in (("geometry.base_joints", g.base_joints),
                         ("geometry.platform_joints", g.platform_joints)):
        far = float(np.linalg.norm(joints, axis=1).max())
        if far > MAX_JOINT_DISTANCE:
            warnings.warn(f"{name}: a joint is {far:.4g} m from the origin (more than "
                          f"{MAX_JOINT_DISTANCE:g} m); lengths must be in m, not mm",
                          GsfricWarning, stacklevel=4)
    radius = float(np.linalg.norm(g.platform_joints, axis=1).max())
    reach = radius + float(np.linalg.norm(g.base_joints, axis=1).max())
    longest = g.stroke[1] if g.stroke is not None else None
    if longest is not None and legs.model == "rigid":
        for com in ("lower_com", "upper_com"):
            value = getattr(legs, com)
            if value > longest:
                warnings.warn(f"legs.{com}: {value:g} m is longer than the longest leg "
                              f"(geometry.stroke d_max = {longest:g} m): the centre of mass "
                              "lies outside the leg", GsfricWarning, stacklevel=4)
    for name, com in (("platform.com", body.com), ("platform.payload_com", body.payload_com)):
        distance = float(np.linalg.norm(com))
        if reach > 0 and distance > 2 * reach:
            warnings.warn(f"{name}: {distance:.4g} m from the platform frame origin, more "
                          f"than twice the hexapod's size ({reach:.4g} m): a centre of mass "
                          "outside the body (or lengths in mm)?", GsfricWarning, stacklevel=4)


def limits_table(value: object) -> dict[str, object]:
    """Validated ``[limits]``: positive ratings; ``actuator_force`` as (min, max)."""
    if not isinstance(value, Mapping):
        raise InputError(f"limits: expected a table, got {short(value)}")
    result: dict[str, object] = {}
    for key, given in value.items():
        if key not in LIMITS:
            raise InputError(f"limits.{key}: unknown limit{suggest(str(key), LIMITS)}")
        if key == "actuator_force" and isinstance(given, (list, tuple)):
            if len(given) != 2:
                raise InputError(f"limits.actuator_force: expected a number or [min, max], "
                                 f"got {short(given)}")
            lo = as_float(given[0], "limits.actuator_force[0]")
            hi = as_float(given[1], "limits.actuator_force[1]")
            if lo >= hi:
                raise InputError(f"limits.actuator_force: min = {lo:g} must be less than "
                                 f"max = {hi:g}")
            result[key] = (lo, hi)
            continue
        rating = as_float(given, f"limits.{key}", minimum=0.0)
        if rating <= 0:
            raise InputError(f"limits.{key}: must be positive, got {rating:g}")
        result[key] = (-rating, rating) if key == "actuator_force" else rating
    return result
