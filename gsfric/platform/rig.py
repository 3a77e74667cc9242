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
  d_min / 10, its centre half-way along it from its joint: m (3 a^2 + l^2)/12 across,
  m a^2/2 along (a the radius, l the length);
* bushings (coupled friction): at 0.5 d_min and 0.7 d_min from C_i; the other friction
  coefficients are the reference platform's.

The derived values move with the sizes they come from (a longer stroke moves the bushings and
changes the leg parts' inertias): ``Rig.derived()`` gives them (``RigValues``), ``gsfric
platform --show`` prints them, and a rig TOML may give any of them explicitly
(``platform_inertia``, ``lower_com``, ``lower_inertia``, ``upper_com``, ``upper_inertia``,
``bushing_offset``, ``bushing_spacing``): a value given is used as it is, in place of the
derived one.

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
    # optional, each in place of its derived value:
    # platform_inertia = [Ixx, Iyy, Izz]  kg m^2, principal moments about the centre of mass
    # lower_com = 0.8, upper_com = 0.6    m, each part's centre of mass from its joint
    # lower_inertia = [Ix, Iy, Iz]        kg m^2, about its centre of mass, z along the leg
    # upper_inertia = [Ix, Iy, Iz]        kg m^2
    # bushing_offset = 1.5                m, first bushing from C_i
    # bushing_spacing = 0.6               m, between the two bushings

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
from gsfric.platform.description import (
    FRICTION_MODELS,
    Body,
    Friction,
    Geometry,
    Legs,
    Platform,
)
from gsfric.platform.text import commented_toml
from gsfric.platform.values import check_principal_moments

DERIVED = {
    "home_height": "legs at mid-stroke, platform level",
    "platform_inertia": "a uniform disc of radius platform_radius: m r^2/4, m r^2/4, m r^2/2",
    "lower_com": "half of d_min from C_i",
    "upper_com": "half of d_min from E_i",
    "lower_inertia": "a solid cylinder of length d_min, diameter d_min/10",
    "upper_inertia": "a solid cylinder of length d_min, diameter d_min/10",
    "bushing_offset": "0.5 d_min",
    "bushing_spacing": "0.2 d_min",
}
"""How ``Rig.derived`` derives each value a rig may leave out, by its key; the friction
coefficients are the reference platform's."""

PAIR_CENTRES = {"base": 0.0, "platform": 60.0}
"""Angle (degrees) of the first pair's centre on each circle; the others at +120 and +240."""

LEG_SLENDERNESS = 10.0
"""Length over diameter of the cylinders that stand for the leg parts."""

BUSHINGS = (0.5, 0.2)
"""First bushing's distance from C_i and the spacing of the two, as fractions of d_min."""

MAX_LENGTH = 1000.0
"""The longest radius or leg a rig may state, m: hundreds of times the largest hexapods (a few
metres), so any larger value is a unit or typing error; it keeps every product of the sizes
finite (1e200 m would overflow the legs' lengths to inf)."""

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
    platform_inertia : (float, float, float) or None
        Principal moments of inertia of the platform about its centre of mass, platform
        frame axes, kg m^2; None: derived (``DERIVED``).
    lower_com, upper_com : float or None
        Centre of mass of each leg's lower part from C_i and of its upper part from E_i,
        along the leg, m; None: derived.
    lower_inertia, upper_inertia : (float, float, float) or None
        Principal moments of inertia of each leg part about its centre of mass, in the leg's
        body frame (z along the leg), kg m^2; None: derived.
    bushing_offset, bushing_spacing : float or None
        Distance of the first bushing from C_i and between the two bushings (coupled
        friction), m; None: derived.
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
    platform_inertia: tuple[float, float, float] | None = None
    lower_com: float | None = None
    lower_inertia: tuple[float, float, float] | None = None
    upper_com: float | None = None
    upper_inertia: tuple[float, float, float] | None = None
    bushing_offset: float | None = None
    bushing_spacing: float | None = None

    def __post_init__(self) -> None:
        for name in ("base_radius", "platform_radius"):
            value = as_float(getattr(self, name), name)
            if not 0 < value <= MAX_LENGTH:
                raise InputError(f"{name}: must be a positive length in m, at most "
                                 f"{MAX_LENGTH:g} m, got {value:g}")
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
            if self.home_height > MAX_LENGTH:
                raise InputError(f"home_height: must be at most {MAX_LENGTH:g} m, got "
                                 f"{self.home_height:g} m")
        for name in ("platform_inertia", "lower_inertia", "upper_inertia"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _moments(getattr(self, name), name))
        for name in ("lower_com", "upper_com", "bushing_offset", "bushing_spacing"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _distance(getattr(self, name), name,
                                                         self.stroke[1]))
        self._check_home()

    # -- reading --------------------------------------------------------------------------

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> Rig:
        """A rig from a mapping of its fields; ``InputError`` ``{source}: {key}: {problem}``."""
        try:
            if not isinstance(data, Mapping):
                raise InputError(f"expected a table of keys, got {short(data)}")
            names = tuple(f.name for f in dataclasses.fields(cls))
            if {"geometry", "platform"} <= set(data):
                raise InputError("a platform file ([geometry], [platform]), not a rig's sizes: "
                                 "a command that reads a platform takes it with --platform")
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

    def derived(self) -> RigValues:
        """The values of the expanded platform that the sizes do not state: the ones given
        in the rig as they are, the others derived from the sizes (``DERIVED``)."""
        m, r = self.platform_mass, self.platform_radius
        d_min = self.stroke[0]
        offset, spacing = BUSHINGS
        derived = {
            "platform_inertia": (m * r * r / 4, m * r * r / 4, m * r * r / 2),
            "lower_com": d_min / 2, "upper_com": d_min / 2,
            "lower_inertia": _rod(self.lower_mass, d_min),
            "upper_inertia": _rod(self.upper_mass, d_min),
            "bushing_offset": offset * d_min, "bushing_spacing": spacing * d_min,
        }
        given = tuple(k for k in derived if getattr(self, k) is not None)
        values = {k: getattr(self, k) if k in given else v for k, v in derived.items()}
        return RigValues(home_height=self.home, home_legs=float(self.home_legs().mean()),
                         given=given + (("home_height",) if self.home_height is not None
                                        else ()),
                         **{k: tuple(float(x) for x in v) if isinstance(v, tuple) else float(v)
                            for k, v in values.items()})

    def platform(self) -> Platform:
        """The full platform: the sizes with the values of ``derived()``."""
        base, top = self.joints()
        v = self.derived()
        return Platform(
            geometry=Geometry(base_joints=base, platform_joints=top, stroke=self.stroke),
            platform=Body(mass=self.platform_mass, inertia=np.diag(v.platform_inertia),
                          payload_mass=self.payload_mass),
            legs=Legs(model="rigid", weight=True,
                      lower_mass=self.lower_mass, lower_com=v.lower_com,
                      lower_inertia=np.diag(v.lower_inertia),
                      upper_mass=self.upper_mass, upper_com=v.upper_com,
                      upper_inertia=np.diag(v.upper_inertia)),
            friction=Friction(model=self.friction_model, bushing_offset=v.bushing_offset,
                              bushing_spacing=v.bushing_spacing,
                              **{**REFERENCE_FRICTION,
                                 **({"prismatic_seal": 0.0}
                                    if self.friction_model == "paper" else {})}))


@dataclass(frozen=True)
class RigValues:
    """The values of a rig's platform that its sizes do not state (``Rig.derived``).

    Attributes
    ----------
    home_height : float
        Platform frame above the base frame at the home pose, m.
    home_legs : float
        Mean leg length at the home pose, m.
    platform_inertia : (float, float, float)
        Principal moments of the platform about its centre of mass, kg m^2.
    lower_com, upper_com : float
        Centre of mass of the lower part from C_i, of the upper part from E_i, m.
    lower_inertia, upper_inertia : (float, float, float)
        Principal moments of the leg parts about their centres of mass, leg body frame (z
        along the leg), kg m^2.
    bushing_offset, bushing_spacing : float
        First bushing's distance from C_i and the distance between the two, m.
    given : tuple of str
        The keys given in the rig (the others are derived, ``DERIVED``).
    """

    home_height: float
    home_legs: float
    platform_inertia: tuple[float, float, float]
    lower_com: float
    upper_com: float
    lower_inertia: tuple[float, float, float]
    upper_inertia: tuple[float, float, float]
    bushing_offset: float
    bushing_spacing: float
    given: tuple[str, ...] = ()

    def lines(self) -> list[str]:
        """One line per value with its unit and where it comes from (given, or how it is
        derived)."""
        def source(key: str) -> str:
            return "given" if key in self.given else f"derived: {DERIVED[key]}"

        def moments(v) -> str:
            return ", ".join(f"{x:.6g}" for x in v) + " kg m^2"

        a, b = self.bushing_offset, self.bushing_offset + self.bushing_spacing
        return [
            (f"home_height {self.home_height:.6g} m, legs {self.home_legs:.6g} m long at home "
             f"({source('home_height')})"),
            (f"bushings at {a:.6g} m and {b:.6g} m from C_i: bushing_offset {a:.6g} m "
             f"({source('bushing_offset')}), bushing_spacing {self.bushing_spacing:.6g} m "
             f"({source('bushing_spacing')})"),
            f"platform_inertia {moments(self.platform_inertia)} ({source('platform_inertia')})",
            (f"lower_com {self.lower_com:.6g} m from C_i ({source('lower_com')}), "
             f"upper_com {self.upper_com:.6g} m from E_i ({source('upper_com')})"),
            f"lower_inertia {moments(self.lower_inertia)} ({source('lower_inertia')})",
            f"upper_inertia {moments(self.upper_inertia)} ({source('upper_inertia')})",
        ]


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
    if hi > MAX_LENGTH:
        raise InputError(f"stroke: d_max must be at most {MAX_LENGTH:g} m, got {hi:g} m")
    if not 0 < lo < hi:
        raise InputError(f"stroke: expected 0 < d_min < d_max, got [{lo:g}, {hi:g}] m")
    return (lo, hi)


def _circle(radius: float, centre_deg: float, half_angle: float) -> np.ndarray:
    """Six points on a circle in pairs around ``centre_deg + 120 k`` degrees, (6, 3), m."""
    angles = [math.radians(centre_deg + 120.0 * k) + s * half_angle
              for k in range(3) for s in (-1.0, 1.0)]
    a = np.array(angles)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.zeros(6)])


def _rod(mass: float, length: float) -> tuple[float, float, float]:
    """Principal moments, kg m^2, of a solid cylinder of ``length`` and diameter length/10
    about its centre: across, across, along its axis (z)."""
    a = length / LEG_SLENDERNESS / 2
    across = mass * (3 * a * a + length * length) / 12
    return (across, across, mass * a * a / 2)


def _moments(value: object, name: str) -> tuple[float, float, float]:
    """Three principal moments of inertia, kg m^2, each >= 0."""
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 3:
        raise InputError(f"{name}: expected the three principal moments [x, y, z] in kg m^2, "
                         f"got {short(value)}")
    moments = tuple(as_float(v, f"{name}[{k}]", minimum=0.0) for k, v in enumerate(value))
    check_principal_moments(moments, name, stacklevel=5)
    return moments


def _distance(value: object, name: str, longest: float) -> float:
    """A positive distance along a leg, m, at most the longest leg."""
    value = as_float(value, name)
    if not 0.0 < value <= longest:
        raise InputError(f"{name}: expected a distance along the leg in (0, {longest:g}] m "
                         f"(the longest leg), got {value:g}")
    return value


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
    "platform_inertia": ("kg m^2", "platform's principal moments; leave out to derive"),
    "lower_com": ("m", "lower part's centre of mass from C_i; leave out to derive"),
    "lower_inertia": ("kg m^2", "lower part's principal moments (z along); leave out to derive"),
    "upper_com": ("m", "upper part's centre of mass from E_i; leave out to derive"),
    "upper_inertia": ("kg m^2", "upper part's principal moments; leave out to derive"),
    "bushing_offset": ("m", "first bushing from C_i; leave out to derive"),
    "bushing_spacing": ("m", "between the two bushings; leave out to derive"),
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
    derived = dataclasses.asdict(rig.derived())
    for f in dataclasses.fields(rig):
        unit, meaning = RIG_KEYS[f.name]
        value = getattr(rig, f.name)
        note = f"{unit}, {meaning}" if unit else meaning
        if unit == "rad":
            note += f" ({math.degrees(value):.4g} deg)"
        if value is None:
            now = derived[f.name]
            now = ", ".join(f"{v:.6g}" for v in now) if isinstance(now, tuple) else f"{now:.6g}"
            doc.add(tomlkit.comment(f"{f.name} =    # {note} (derived: {now})"))
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
        if value is None or f.name == "friction_model" or f.name in DERIVED:
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
    where = f" ({source})" if source else ""
    header = [(f"A gsfric platform expanded from the sizes of a rig{where} by "
               "`gsfric platform --template`; SI units, angles in rad."),
              *_sizes(rig),
              (f"Home pose: level platform at z = {rig.home:.6g} m, legs {d.mean():.6g} m long "
               f"(stroke {rig.stroke[0]:g}..{rig.stroke[1]:g} m)."),
              "Read with `gsfric simulate --platform FILE` or gsfric.Platform.from_toml(FILE)."]
    values = rig.derived()
    header += ["Values the sizes do not state (give them in the rig file to override):",
               *(f"  {line}" for line in values.lines())]
    places = {"platform_inertia": "platform.inertia", "lower_com": "legs.lower_com",
              "lower_inertia": "legs.lower_inertia", "upper_com": "legs.upper_com",
              "upper_inertia": "legs.upper_inertia", "bushing_offset": "friction.bushing_offset",
              "bushing_spacing": "friction.bushing_spacing"}
    notes = {place: "given in the rig" if key in values.given else f"derived: {DERIVED[key]}"
             for key, place in places.items()}
    return commented_toml(rig.platform(), header=header, notes=notes)
