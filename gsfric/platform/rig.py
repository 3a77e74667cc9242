"""A platform from the sizes a rig's user knows: the "rig" description.

A ``Rig`` holds a handful of sizes (joint circles, the half-angle between paired joints, home
height, stroke, masses); ``Rig.platform()`` expands them into a full ``Platform`` with derived
values, each stated in ``DERIVED`` (and in the comments of ``rig_platform_toml``):

* joints: pairs centred at 0, 120, 240 degrees on the base circle and at 60, 180, 300 degrees
  on the platform circle, ``half_angle`` either side of each centre, joined as in
  ``gsfric.models.reference_geometry`` (the legs cross over); z = 0 in both frames;
* home height: when not given, the height at which every leg is at mid-stroke (level platform);
* platform inertia: a uniform disc of the platform radius;
* leg parts: each a uniform solid cylinder of length d_min (the shortest leg) and diameter
  d_min / 10, its centre half-way along it from its joint;
* bushings (coupled friction): at 0.5 d_min and 0.7 d_min from C_i; the other friction
  coefficients are the reference platform's.

A rig TOML holds the ``Rig`` fields as top-level keys (SI units, angles in rad)::

    base_radius = 2.0            # m
    base_half_angle = 0.1309     # rad (7.5 deg)
    platform_radius = 1.4        # m
    platform_half_angle = 0.2618 # rad (15 deg)
    stroke = [3.0, 4.6]          # m, shortest and longest leg
    platform_mass = 800.0        # kg
    lower_mass = 60.0            # kg
    upper_mass = 25.0            # kg
    # optional: home_height (m), payload_mass (kg), friction_model ("coupled" or "paper")

>>> from gsfric.platform.rig import Rig
>>> rig = Rig(base_radius=0.5, base_half_angle=0.26, platform_radius=0.3,
...           platform_half_angle=0.26, stroke=(0.5, 1.1), platform_mass=10.0,
...           lower_mass=2.6, upper_mass=0.7)
>>> round(float(rig.platform().geometry.stroke[1]), 3)
1.1
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import tomlkit

from gsfric._checks import as_float, short, suggest
from gsfric.errors import InputError
from gsfric.io.files import read_toml
from gsfric.platform.description import FRICTION_MODELS, Body, Friction, Geometry, Legs, Platform
from gsfric.platform.text import commented_toml

DERIVED = {
    "home_height": "the height of the platform frame above the base frame at which every "
                   "leg is at mid-stroke (level platform), when not given",
    "platform.inertia": "a uniform disc of radius platform_radius: m r^2/4, m r^2/4, m r^2/2",
    "legs": "each part a uniform solid cylinder of length d_min and diameter d_min/10, its "
            "centre half-way along it from its joint: m (3 a^2 + l^2)/12 across, m a^2/2 along",
    "friction": "bushings at 0.5 d_min and 0.7 d_min from C_i; the reference platform's "
                "coefficients",
}
"""How ``Rig.platform`` derives what a rig does not give, by the key it fills."""

PAIR_CENTRES = {"base": 0.0, "platform": 60.0}
"""Angle (degrees) of the first pair's centre on each circle; the others at +120 and +240."""

LEG_SLENDERNESS = 10.0
"""Length over diameter of the cylinders that stand for the leg parts."""

BUSHINGS = (0.5, 0.2)
"""First bushing's distance from C_i and the spacing of the two, as fractions of d_min."""

REFERENCE_FRICTION = dict(joint_viscous=0.02, joint_coulomb=0.04, joint_radius=0.05,
                          prismatic_viscous=0.02, prismatic_coulomb=0.1, prismatic_seal=2.0)
"""The friction coefficients of a rig's platform (``gsfric.models.reference_platform``'s)."""


@dataclass(frozen=True, kw_only=True)
class Rig:
    """The sizes of a hexapod that its user knows.

    Attributes
    ----------
    base_radius, platform_radius : float
        Radius of the circle of the universal joints C_i (base frame) and of the spherical
        joints E_i (platform frame), m.
    base_half_angle, platform_half_angle : float
        Half the angle between the two joints of a pair, seen from the circle's centre, rad,
        in (0, pi/6): a pair's joints closer together than the pairs.
    stroke : (float, float)
        Shortest and longest leg length (between joint centres), m.
    platform_mass : float
        Moving platform, kg.
    lower_mass, upper_mass : float
        Each leg's lower part (moves with the universal joint) and upper part (moves with the
        spherical joint end), kg.
    home_height : float or None
        Height of the platform frame's origin above the base frame's at the home pose, m;
        None: the height at which every leg is at mid-stroke.
    payload_mass : float
        kg, at the platform frame's origin. Default 0.
    friction_model : {"coupled", "paper"}
        Default "coupled".
    """

    base_radius: float
    base_half_angle: float
    platform_radius: float
    platform_half_angle: float
    stroke: tuple[float, float]
    platform_mass: float
    lower_mass: float
    upper_mass: float
    home_height: float | None = None
    payload_mass: float = 0.0
    friction_model: str = "coupled"

    def __post_init__(self) -> None:
        for name in ("base_radius", "platform_radius"):
            value = as_float(getattr(self, name), name)
            if value <= 0:
                raise InputError(f"{name}: must be a positive length in m, got {value:g}")
            object.__setattr__(self, name, value)
        for name in ("base_half_angle", "platform_half_angle"):
            value = as_float(getattr(self, name), name)
            if not 0 < value < math.pi / 6:
                raise InputError(f"{name}: must lie in (0, pi/6) rad (0-30 deg: the joints of "
                                 f"a pair closer than the pairs), got "
                                 f"{value:g} rad ({math.degrees(value):.4g} deg); angles are "
                                 "in rad")
            object.__setattr__(self, name, value)
        for name in ("platform_mass", "lower_mass", "upper_mass", "payload_mass"):
            object.__setattr__(self, name, as_float(getattr(self, name), name, minimum=0.0))
        object.__setattr__(self, "stroke", _stroke(self.stroke))
        if self.friction_model not in FRICTION_MODELS:
            raise InputError(f"friction_model: expected one of "
                             f"{', '.join(map(repr, FRICTION_MODELS))}, got "
                             f"{short(self.friction_model)}")
        if self.home_height is not None:
            object.__setattr__(self, "home_height",
                               as_float(self.home_height, "home_height", minimum=0.0))
        self._check_home()

    # -- reading --------------------------------------------------------------------------

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> Rig:
        """A rig from a mapping of its fields; ``InputError`` ``{source}: {key}: {problem}``."""
        try:
            if not isinstance(data, Mapping):
                raise InputError(f"expected a table of keys, got {short(data)}")
            names = tuple(f.name for f in dataclasses.fields(cls))
            for key in data:
                if key not in names:
                    raise InputError(f"{key}: unknown key{suggest(str(key), names)}")
            for f in dataclasses.fields(cls):
                if f.default is dataclasses.MISSING and f.name not in data:
                    raise InputError(f"{f.name}: missing")
            return cls(**data)
        except InputError as error:
            raise InputError(f"{source}: {error}") from None

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str]) -> Rig:
        """Read a rig TOML file (keys: the ``Rig`` fields); ``InputError`` on any problem."""
        path = Path(path)
        data = read_toml(path)
        return cls.from_dict(data, source=str(path))

    @classmethod
    def from_platform(cls, platform: Platform, home_height: float | None = None) -> Rig:
        """The sizes of a platform laid out as a rig's (radii, half-angles, stroke, masses).

        Raises ``InputError`` when it has no stroke; the inverse of ``platform`` on its
        geometry and masses."""
        g = platform.geometry
        if g.stroke is None:
            raise InputError("geometry.stroke: missing; a rig needs the stroke")
        return cls(base_radius=_radius(g.base_joints),
                   base_half_angle=_half_angle(g.base_joints),
                   platform_radius=_radius(g.platform_joints),
                   platform_half_angle=_half_angle(g.platform_joints), stroke=g.stroke,
                   platform_mass=platform.platform.mass, lower_mass=platform.legs.lower_mass,
                   upper_mass=platform.legs.upper_mass, home_height=home_height,
                   payload_mass=platform.platform.payload_mass,
                   friction_model=platform.friction.model)

    # -- expanding ------------------------------------------------------------------------

    def joints(self) -> tuple[np.ndarray, np.ndarray]:
        """Base joints C_i (6, 3) and platform joints E_i (6, 3), m (leg i joins row i)."""
        base = _circle(self.base_radius, PAIR_CENTRES["base"], self.base_half_angle)
        top = _circle(self.platform_radius, PAIR_CENTRES["platform"], self.platform_half_angle)
        return base, np.roll(top, 1, axis=0)

    def home_legs(self, height: float | None = None) -> np.ndarray:
        """Leg lengths (6,), m, with the level platform at ``height`` (default: the home)."""
        base, top = self.joints()
        z = self.home if height is None else height
        return np.linalg.norm(top + np.array([0.0, 0.0, z]) - base, axis=1)

    @property
    def home(self) -> float:
        """The home height, m: ``home_height`` or the height of mid-stroke legs."""
        return self.home_height if self.home_height is not None else _mid_stroke_height(self)

    def _check_home(self) -> None:
        d = self.home_legs()
        lo, hi = self.stroke
        if d.min() < lo or d.max() > hi:
            if self.home_height is None:
                raise InputError(f"stroke: [{lo:g}, {hi:g}] m cannot reach the base and "
                                 f"platform circles (level legs are {d.max():.4g} m long); "
                                 "lengthen the stroke or bring the radii closer")
            bad = float(d.max() if d.max() > hi else d.min())
            raise InputError(f"home_height: {self.home_height:g} m puts the legs at "
                             f"{bad:.4g} m, outside the stroke [{lo:g}, {hi:g}] m; "
                             f"leave it out for mid-stroke ({_mid_stroke_height(self):.4g} m)")

    def platform(self) -> Platform:
        """The full platform (``DERIVED`` says how each value is derived)."""
        base, top = self.joints()
        m, r = self.platform_mass, self.platform_radius
        d_min = self.stroke[0]
        offset, spacing = BUSHINGS
        return Platform(
            geometry=Geometry(base_joints=base, platform_joints=top, stroke=self.stroke),
            platform=Body(mass=m, inertia=np.diag([m * r * r / 4, m * r * r / 4, m * r * r / 2]),
                          payload_mass=self.payload_mass),
            legs=Legs(model="rigid", weight=True,
                      lower_mass=self.lower_mass, lower_com=d_min / 2,
                      lower_inertia=_rod(self.lower_mass, d_min),
                      upper_mass=self.upper_mass, upper_com=d_min / 2,
                      upper_inertia=_rod(self.upper_mass, d_min)),
            friction=Friction(model=self.friction_model, bushing_offset=offset * d_min,
                              bushing_spacing=spacing * d_min,
                              **{**REFERENCE_FRICTION,
                                 **({"prismatic_seal": 0.0}
                                    if self.friction_model == "paper" else {})}))


def _mid_stroke_height(rig: Rig) -> float:
    """Height, m, of the level platform at which every leg is at mid-stroke."""
    base, top = rig.joints()
    flat = float(np.linalg.norm(top[0, :2] - base[0, :2]))
    mid = 0.5 * (rig.stroke[0] + rig.stroke[1])
    return math.sqrt(max(mid * mid - flat * flat, 0.0))


def _stroke(value: object) -> tuple[float, float]:
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 2:
        raise InputError(f"stroke: expected [d_min, d_max] in m, got {short(value)}")
    lo = as_float(value[0], "stroke[0]", minimum=0.0)
    hi = as_float(value[1], "stroke[1]")
    if not 0 < lo < hi:
        raise InputError(f"stroke: expected 0 < d_min < d_max, got [{lo:g}, {hi:g}] m")
    return (lo, hi)


def _circle(radius: float, centre_deg: float, half_angle: float) -> np.ndarray:
    """Six points on a circle in pairs around ``centre_deg + 120 k`` degrees, (6, 3), m."""
    angles = [math.radians(centre_deg + 120.0 * k) + s * half_angle
              for k in range(3) for s in (-1.0, 1.0)]
    a = np.array(angles)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.zeros(6)])


def _rod(mass: float, length: float) -> np.ndarray:
    """Inertia (3, 3), kg m^2, of a solid cylinder of ``length`` and diameter length/10 about
    its centre, z along its axis."""
    a = length / LEG_SLENDERNESS / 2
    across = mass * (3 * a * a + length * length) / 12
    return np.diag([across, across, mass * a * a / 2])


def _radius(joints: np.ndarray) -> float:
    return float(np.mean(np.linalg.norm(joints[:, :2], axis=1)))


def _half_angle(joints: np.ndarray) -> float:
    """Half the smallest angle between two joints, rad (the pairs' half-angle)."""
    a = np.sort(np.arctan2(joints[:, 1], joints[:, 0]) % (2 * math.pi))
    gaps = np.diff(np.append(a, a[0] + 2 * math.pi))
    return float(gaps.min() / 2)


RIG_KEYS = {
    "base_radius": ("m", "circle of the universal joints C_i, base frame"),
    "base_half_angle": ("rad", "half the angle between the two joints of a base pair"),
    "platform_radius": ("m", "circle of the spherical joints E_i, platform frame"),
    "platform_half_angle": ("rad", "half the angle between the two joints of a platform pair"),
    "stroke": ("m", "shortest and longest leg, between joint centres"),
    "platform_mass": ("kg", "the moving platform"),
    "lower_mass": ("kg", "each leg's lower part (cylinder body, motor)"),
    "upper_mass": ("kg", "each leg's upper part (rod, rod end)"),
    "home_height": ("m", "platform frame above base frame at home; leave out for mid-stroke"),
    "payload_mass": ("kg", "at the platform frame's origin"),
    "friction_model": ("", '"coupled" (friction loads the actuators) or "paper"'),
}
"""Unit and meaning of each key of a rig TOML."""


def rig_toml(rig: Rig) -> str:
    """The rig as a commented rig TOML (``Rig.from_toml`` reads back an equal rig)."""
    doc = tomlkit.document()
    for line in ("A gsfric rig: the sizes of a hexapod (SI units, angles in rad).",
                 "Expand it into a full platform with",
                 "  gsfric platform --template --rig rig.toml --out platform.toml"):
        doc.add(tomlkit.comment(line))
    doc.add(tomlkit.nl())
    for f in dataclasses.fields(rig):
        unit, meaning = RIG_KEYS[f.name]
        value = getattr(rig, f.name)
        note = f"{unit}, {meaning}" if unit else meaning
        if unit == "rad":
            note += f" ({math.degrees(value):.4g} deg)"
        if value is None:
            doc.add(tomlkit.comment(f"{f.name} =    # {note}"))
            continue
        item = tomlkit.item(value if isinstance(value, str) else
                            [float(v) for v in value] if isinstance(value, tuple) else
                            float(value))
        item.comment(note)
        item.trivia.comment_ws = "   "
        doc.add(f.name, item)
    return tomlkit.dumps(doc)


def _sizes(rig: Rig) -> list[str]:
    """The rig's sizes with units, three to a line."""
    items = []
    for f in dataclasses.fields(rig):
        value, unit = getattr(rig, f.name), RIG_KEYS[f.name][0]
        if value is None or f.name == "friction_model":
            continue
        text = (f"[{value[0]:.6g}, {value[1]:.6g}]" if isinstance(value, tuple)
                else f"{value:.6g}")
        if unit == "rad":
            text += f" rad ({math.degrees(value):.4g} deg)"
        elif unit:
            text += f" {unit}"
        items.append(f"{f.name} = {text}")
    return ["Sizes: " + ", ".join(items[:3])] + [
        "       " + ", ".join(items[i:i + 3]) for i in range(3, len(items), 3)]


def rig_platform_toml(rig: Rig, source: str = "") -> str:
    """The rig's full platform as a commented TOML: the sizes it came from in the header,
    how each derived value was derived in the comments."""
    d = rig.home_legs()
    header = [f"A gsfric platform expanded from the sizes of a rig{f' ({source})' if source else ''}"
              " by `gsfric platform --template`; SI units, angles in rad.",
              *_sizes(rig),
              f"Home pose: level platform at z = {rig.home:.6g} m, legs {d.mean():.6g} m long "
              f"(stroke {rig.stroke[0]:g}..{rig.stroke[1]:g} m).",
              "Read with `gsfric simulate --platform FILE` or gsfric.Platform.from_toml(FILE)."]
    notes = {"platform.inertia": f"derived: {DERIVED['platform.inertia']}"}
    for key in ("lower_com", "lower_inertia", "upper_com", "upper_inertia"):
        notes[f"legs.{key}"] = "derived: cylinder of length d_min, diameter d_min/10"
    for key in ("bushing_offset", "bushing_spacing"):
        notes[f"friction.{key}"] = "derived: bushings at 0.5 and 0.7 d_min from C_i"
    return commented_toml(rig.platform(), header=header, notes=notes)
