"""The hexapod's description: geometry, inertia, leg model, friction and optional effects.

A ``Platform`` is built from a TOML file (``Platform.from_toml``), from a dictionary of the same
layout (``Platform.from_dict``) or directly from its parts, and written back with ``to_toml``;
reading what ``to_toml`` wrote gives an equal ``Platform`` (floats round-trip exactly).

Units are SI: m, kg, kg m^2, N, s. The TOML layout (docs/reference/platform-file.md)::

    gravity = 9.81
    [geometry]       base_joints, platform_joints, universal_axes (optional), stroke (optional)
    [platform]       mass, inertia, com, payload_mass, payload_inertia, payload_com
    [legs]           model, weight, lower_mass, lower_com, lower_inertia,
                     upper_mass, upper_com, upper_inertia
    [friction]       joint_viscous, joint_coulomb, joint_radius, prismatic_viscous,
                     prismatic_coulomb, model, bushing_offset, bushing_spacing, prismatic_seal
    [effects]        name = { parameter = value, ... }
    [limits]         optional ratings for ``gsfric sweep``'s check (see ``LIMITS``)

Every problem raises an ``InputError`` with a one-line message naming the file and the dotted
key, e.g. ``platform.toml: geometry.base_joints: expected an array of shape (6, 3), got (5, 3)``.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import tomli_w

from gsfric._checks import as_array, as_float, as_path, fields_equal, short, suggest
from gsfric.errors import InputError, InputTypeError
from gsfric.io.files import atomic_write, read_toml
from gsfric.platform import catalog
from gsfric.platform.values import (
    check_plausible,
    default_universal_axes,
    inertia_tensor,
    limits_table,
    stroke_range,
    unit_axes,
)

LEG_MODELS = ("rigid", "paper")
"""Leg models: ``rigid`` (centres of mass at fixed distances from C_i and E_i) and ``paper``
(centres at 0.25 d and 0.75 d from C_i, d the leg length)."""

FRICTION_MODELS = ("paper", "coupled")
"""Friction models (``[friction] model``): the paper's post-hoc evaluation, and the coupled model
in which friction loads the mechanism (docs/explanation/friction.md)."""

PAPER_LEG_FRACTION = 0.25
"""Fraction of the leg length at which the paper model places the lower and upper centres."""

DEFAULT_GRAVITY = 9.81

MAX_GRAVITY = 100.0
"""The largest gravity accepted, m/s^2: ten times the Earth's, beyond any load case of a rig
(larger values are a unit or typing error, and 1e308 overflows every force)."""

_set = object.__setattr__


def _diag(value: float) -> tuple[tuple[float, ...], ...]:
    return ((value, 0.0, 0.0), (0.0, value, 0.0), (0.0, 0.0, value))


@dataclass(frozen=True, eq=False)
class Geometry:
    """Where the joints are.

    Attributes
    ----------
    base_joints : ndarray, shape (6, 3)
        Centres C_i of the universal joints, base frame, m.
    platform_joints : ndarray, shape (6, 3)
        Centres E_i of the spherical joints, platform frame, m.
    universal_axes : ndarray, shape (6, 3)
        First (base-fixed) axis a_1 of each universal joint, base frame, unit vectors (given
        axes are normalized). Default: ``default_universal_axes(base_joints)``.
    stroke : tuple (d_min, d_max) or None
        Admissible leg lengths, m; None for no limit.
    """

    base_joints: np.ndarray
    platform_joints: np.ndarray
    universal_axes: np.ndarray | None = None
    stroke: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        base = as_array(self.base_joints, (6, 3), "geometry.base_joints")
        top = as_array(self.platform_joints, (6, 3), "geometry.platform_joints")
        if self.universal_axes is None:
            axes = default_universal_axes(base)
            axes.setflags(write=False)
        else:
            axes = unit_axes(self.universal_axes, "geometry.universal_axes")
        _set(self, "base_joints", base)
        _set(self, "platform_joints", top)
        _set(self, "universal_axes", axes)
        _set(self, "stroke", stroke_range(self.stroke))

    __eq__ = fields_equal
    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class Body:
    """The moving platform and its payload (TOML section ``[platform]``).

    Attributes
    ----------
    mass : float
        Platform mass, kg.
    inertia : ndarray, shape (3, 3)
        Platform inertia about its centre of mass, platform frame, kg m^2.
    com : ndarray, shape (3,)
        Platform centre of mass, platform frame, m. Default 0.
    payload_mass : float
        Payload mass, kg. Default 0.
    payload_inertia : ndarray, shape (3, 3)
        Payload inertia about its centre of mass, platform frame, kg m^2. Default 0.
    payload_com : ndarray, shape (3,)
        Payload centre of mass, platform frame, m. Default 0.
    """

    mass: float
    inertia: np.ndarray
    com: np.ndarray = (0.0, 0.0, 0.0)  # type: ignore[assignment]
    payload_mass: float = 0.0
    payload_inertia: np.ndarray = _diag(0.0)  # type: ignore[assignment]
    payload_com: np.ndarray = (0.0, 0.0, 0.0)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        _set(self, "mass", as_float(self.mass, "platform.mass", minimum=0.0))
        _set(self, "inertia", inertia_tensor(self.inertia, "platform.inertia"))
        _set(self, "com", as_array(self.com, (3,), "platform.com"))
        _set(self, "payload_mass",
             as_float(self.payload_mass, "platform.payload_mass", minimum=0.0))
        _set(self, "payload_inertia",
             inertia_tensor(self.payload_inertia, "platform.payload_inertia"))
        _set(self, "payload_com", as_array(self.payload_com, (3,), "platform.payload_com"))

    __eq__ = fields_equal
    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class Legs:
    """The two rigid parts of each leg (TOML section ``[legs]``).

    The lower part (zone 4) turns with the universal joint at C_i, the upper part (zone 2)
    slides along it and ends in the spherical joint E_i. Inertias are about each part's centre
    of mass in the leg's body frame: z from C_i to E_i, x along the universal joint's second axis.

    Attributes
    ----------
    model : {"rigid", "paper"}
        ``rigid``: centres at ``lower_com`` from C_i and ``upper_com`` from E_i along the leg.
        ``paper``: centres at 0.25 d and 0.75 d from C_i (the ``*_com`` values are not used).
    weight : bool
        False leaves the legs' weight out, as the paper's printed (11)-(16) do.
    lower_mass, upper_mass : float
        kg. Default 0.5.
    lower_com, upper_com : float
        m, distance of each centre from C_i (lower) and from E_i (upper). Default 0.2.
    lower_inertia, upper_inertia : ndarray, shape (3, 3)
        kg m^2. Default diag(0.035).
    """

    model: str = "rigid"
    weight: bool = True
    lower_mass: float = 0.5
    lower_com: float = 0.2
    lower_inertia: np.ndarray = _diag(0.035)  # type: ignore[assignment]
    upper_mass: float = 0.5
    upper_com: float = 0.2
    upper_inertia: np.ndarray = _diag(0.035)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if not isinstance(self.model, str) or self.model not in LEG_MODELS:
            hint = suggest(self.model, LEG_MODELS) if isinstance(self.model, str) else ""
            raise InputError(f"legs.model: unknown leg model {short(self.model)}{hint}; "
                             "expected 'rigid' or 'paper'")
        if not isinstance(self.weight, (bool, np.bool_)):
            raise InputError(f"legs.weight: expected true or false, got {short(self.weight)}")
        _set(self, "weight", bool(self.weight))
        for part in ("lower", "upper"):
            mass, com, inertia = f"{part}_mass", f"{part}_com", f"{part}_inertia"
            _set(self, mass, as_float(getattr(self, mass), f"legs.{mass}", minimum=0.0))
            _set(self, com, as_float(getattr(self, com), f"legs.{com}"))
            if getattr(self, com) < 0:
                joint = "C_i" if part == "lower" else "E_i"
                raise InputError(f"legs.{com}: {getattr(self, com):g} m puts the {part} part's "
                                 f"centre of mass beyond its joint {joint}, outside the leg; "
                                 f"give its distance from {joint} along the leg, >= 0 m")
            _set(self, inertia, inertia_tensor(getattr(self, inertia), f"legs.{inertia}"))

    def com_placement(self) -> tuple[float, float, float, float]:
        """``(lower_com, lower_frac, upper_com, upper_frac)`` as the model uses them.

        Lower centre: ``C + (lower_com + lower_frac d) u``; upper centre:
        ``E - (upper_com + upper_frac d) u`` (d the leg length, u the unit vector from C to E).
        Rigid model: fractions 0. Paper model: offsets 0, fractions 0.25.
        """
        if self.model == "paper":
            return (0.0, PAPER_LEG_FRACTION, 0.0, PAPER_LEG_FRACTION)
        return (self.lower_com, 0.0, self.upper_com, 0.0)

    __eq__ = fields_equal
    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class Friction:
    """Friction coefficients of the paper's (33)-(35) (TOML section ``[friction]``).

    Attributes
    ----------
    joint_viscous : float
        c_s of the spherical and universal joints, N m s/rad. Default 0.02.
    joint_coulomb : float
        mu of the spherical and universal joints. Default 0.04.
    joint_radius : float
        r, the joints' friction radius, m. Default 0.05.
    prismatic_viscous : float
        Viscous coefficient of the prismatic joints, N s/m. Default 0.02.
    prismatic_coulomb : float
        mu of the prismatic joints: at the transverse force R_3 in the paper model, at each
        bushing in the coupled model. Default 0.04.
    model : {"paper", "coupled"}
        ``"paper"``: the paper's post-hoc (33)-(35), nothing fed back; ``"coupled"``: friction
        loads the mechanism (solved at every step), prismatic friction from two bushings,
        universal joints per bearing axis (docs/explanation/friction.md). Default ``"paper"``: the meaning
        of every file written before the key existed.
    bushing_offset : float
        Distance of the first bushing from C_i along the leg, m (coupled model). Default 0.25.
    bushing_spacing : float
        Distance between the two bushings, m, > 0 (coupled model). Default 0.1.
    prismatic_seal : float
        Coulomb force of the prismatic joint's seals, N (both models). Default 0.
    """

    joint_viscous: float = 0.02
    joint_coulomb: float = 0.04
    joint_radius: float = 0.05
    prismatic_viscous: float = 0.02
    prismatic_coulomb: float = 0.04
    model: str = "paper"
    bushing_offset: float = 0.25
    bushing_spacing: float = 0.1
    prismatic_seal: float = 0.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            if f.name == "model":
                if self.model not in FRICTION_MODELS:
                    raise InputError(f"friction.model: expected one of "
                                     f"{', '.join(map(repr, FRICTION_MODELS))}, got "
                                     f"{short(self.model)}")
                continue
            value = as_float(getattr(self, f.name), f"friction.{f.name}", minimum=0.0)
            _set(self, f.name, value)
        if self.bushing_spacing <= 0.0:
            raise InputError(f"friction.bushing_spacing: expected a positive distance, got "
                             f"{self.bushing_spacing!r}")

    __eq__ = fields_equal
    __hash__ = None  # type: ignore[assignment]


def _effects_catalog() -> Mapping[str, Mapping[str, float]]:
    """``gsfric.platform.catalog.EFFECTS``: effect name -> {parameter name: default}."""
    return catalog.EFFECTS


def _effects(value: object) -> dict[str, dict[str, float]]:
    """Validated effects, every parameter filled in (catalog default when not given)."""
    if not isinstance(value, Mapping):
        raise InputError(f"effects: expected a table, got {short(value)}")
    if not value:
        return {}
    known = _effects_catalog()
    result: dict[str, dict[str, float]] = {}
    for name, params in value.items():
        if name not in known:
            raise InputError(f"effects.{name}: unknown effect{suggest(str(name), known)}")
        if not isinstance(params, Mapping):
            raise InputError(f"effects.{name}: expected a table of parameters, "
                             f"e.g. {name} = {{}}, got {short(params)}")
        defaults = known[name]
        for key in params:
            if key not in defaults:
                raise InputError(f"effects.{name}.{key}: unknown parameter"
                                 f"{suggest(str(key), defaults)}")
        result[name] = {
            key: as_float(params.get(key, default), f"effects.{name}.{key}")
            for key, default in defaults.items()
        }
    return result


@dataclass(frozen=True, eq=False, kw_only=True)
class Platform:
    """A Gough-Stewart platform: everything the mechanics needs besides the motion.

    Attributes
    ----------
    gravity : float
        m/s^2, acting along -z of the base frame. Default 9.81.
    geometry : Geometry
    platform : Body
    legs : Legs
    friction : Friction
    effects : dict[str, dict[str, float]]
        Optional effects switched on, name -> parameters (every parameter present), validated
        against ``gsfric.platform.catalog.EFFECTS``.
    limits : dict[str, float | tuple[float, float]]
        Optional ratings (TOML ``[limits]``, keys in ``LIMITS``) that ``gsfric sweep`` checks
        the load envelopes against; ``actuator_force`` is kept as (min, max), N.

    Instances are immutable; derive variants with ``replace``, ``with_geometry``, ``with_body``,
    ``with_legs``, ``with_friction``, ``with_effects``, ``with_effect`` and ``without_effects``.

    Raises
    ------
    InputTypeError
        A value of the wrong type (a string for a number or an array), naming the key.
    InputError
        A wrong shape, a NaN or infinite value, an integer beyond 64 bits, a value out of its
        range (gravity from 0 to ``MAX_GRAVITY`` m/s^2, masses >= 0, ...), an unknown effect;
        one line naming the dotted key. The constructors and ``with_*`` methods raise the
        same.

    Examples
    --------
    >>> import gsfric
    >>> platform = gsfric.reference_platform()
    >>> heavier = platform.with_body(payload_mass=8.0)
    >>> heavier.platform.payload_mass, platform.platform.payload_mass
    (8.0, 3.0)
    """

    gravity: float = DEFAULT_GRAVITY
    geometry: Geometry
    platform: Body
    legs: Legs = field(default_factory=Legs)
    friction: Friction = field(default_factory=Friction)
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    limits: dict[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _set(self, "gravity", as_float(self.gravity, "gravity", minimum=0.0))
        if self.gravity > MAX_GRAVITY:
            raise InputError(f"gravity: {self.gravity:g} m/s^2 is beyond the valid range 0 to "
                             f"{MAX_GRAVITY:g} m/s^2")
        for name, kind in (("geometry", Geometry), ("platform", Body), ("legs", Legs),
                           ("friction", Friction)):
            if not isinstance(getattr(self, name), kind):
                raise InputError(f"{name}: expected a {kind.__name__}, "
                                 f"got {type(getattr(self, name)).__name__}")
        _set(self, "effects", _effects(self.effects))
        _set(self, "limits", limits_table(self.limits))
        check_plausible(self.geometry, self.legs, self.platform)

    __eq__ = fields_equal
    __hash__ = None  # type: ignore[assignment]

    # -- building -------------------------------------------------------------------------

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> Platform:
        """Build a platform from a dictionary with the TOML file's layout.

        Parameters
        ----------
        data : mapping
            Top-level keys ``gravity``, ``geometry``, ``platform``, ``legs``, ``friction``,
            ``effects``; ``geometry`` and ``platform`` are required.
        source : str
            Name used at the start of error messages (the file name).

        Raises
        ------
        InputError
            One line: ``{source}: {dotted key}: {problem}``.
        """
        try:
            return _from_dict(data)
        except InputError as error:
            raise type(error)(f"{source}: {error}") from None

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str]) -> Platform:
        """Read a platform TOML file (layout in docs/reference/platform-file.md).

        Raises
        ------
        InputTypeError
            ``path`` is not a str or os.PathLike.
        InputError
            Any problem of the file, in one line naming the file and the key (a missing or
            unknown key, a wrong type, a NaN or infinite value, an integer beyond 64 bits).
        """
        path = as_path(path, "platform file")
        data = read_toml(path)
        return cls.from_dict(data, source=str(path))

    # -- writing --------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The TOML layout as plain Python values (floats, lists, dicts, str, bool)."""
        g, b, legs = self.geometry, self.platform, self.legs
        geometry: dict[str, Any] = {
            "base_joints": g.base_joints.tolist(),
            "platform_joints": g.platform_joints.tolist(),
            "universal_axes": g.universal_axes.tolist(),
        }
        if g.stroke is not None:
            geometry["stroke"] = list(g.stroke)
        limits = {key: list(value) if isinstance(value, tuple) else value
                  for key, value in self.limits.items()}
        return {
            "gravity": self.gravity,
            "geometry": geometry,
            "platform": {
                "mass": b.mass,
                "inertia": b.inertia.tolist(),
                "com": b.com.tolist(),
                "payload_mass": b.payload_mass,
                "payload_inertia": b.payload_inertia.tolist(),
                "payload_com": b.payload_com.tolist(),
            },
            "legs": {
                "model": legs.model,
                "weight": legs.weight,
                "lower_mass": legs.lower_mass,
                "lower_com": legs.lower_com,
                "lower_inertia": legs.lower_inertia.tolist(),
                "upper_mass": legs.upper_mass,
                "upper_com": legs.upper_com,
                "upper_inertia": legs.upper_inertia.tolist(),
            },
            "friction": dataclasses.asdict(self.friction),
            "effects": {name: dict(params) for name, params in self.effects.items()},
            **({"limits": limits} if limits else {}),
        }

    def to_toml(self, path: str | os.PathLike[str]) -> None:
        """Write the platform as TOML, atomically; ``from_toml`` reads back an equal platform."""
        text = tomli_w.dumps(self.to_dict())
        path = as_path(path, "path")
        with atomic_write(path, "w") as handle:
            handle.write(text)

    # -- variants -------------------------------------------------------------------------

    def replace(self, **changes: Any) -> Platform:
        """A copy with top-level fields replaced (``dataclasses.replace``), validated again."""
        return dataclasses.replace(self, **changes)

    def with_geometry(self, **changes: Any) -> Platform:
        """A copy with fields of ``geometry`` replaced, e.g. ``stroke=(0.5, 0.9)``."""
        return self.replace(geometry=dataclasses.replace(self.geometry, **changes))

    def with_body(self, **changes: Any) -> Platform:
        """A copy with fields of ``platform`` (the Body) replaced, e.g. ``payload_mass=5``."""
        return self.replace(platform=dataclasses.replace(self.platform, **changes))

    def with_legs(self, **changes: Any) -> Platform:
        """A copy with fields of ``legs`` replaced, e.g. ``weight=False``."""
        return self.replace(legs=dataclasses.replace(self.legs, **changes))

    def with_friction(self, **changes: Any) -> Platform:
        """A copy with fields of ``friction`` replaced, e.g. ``joint_coulomb=0.1``."""
        return self.replace(friction=dataclasses.replace(self.friction, **changes))

    def with_effects(self, effects: Mapping[str, Mapping[str, float]]) -> Platform:
        """A copy whose effects are exactly ``effects`` (missing parameters take defaults).

        Raises
        ------
        InputTypeError
            ``effects`` is not a mapping.
        InputError
            An unknown effect or parameter, a bad value.
        """
        if not isinstance(effects, Mapping) or not all(
                isinstance(p, Mapping) for p in effects.values()):
            raise InputTypeError(f"effects: expected a dict of effect name -> dict of "
                                 f"parameters, got {short(effects)}")
        return self.replace(effects={name: dict(params) for name, params in effects.items()})

    def with_effect(self, name: str, **parameters: float) -> Platform:
        """A copy with effect ``name`` switched on or updated; other effects are kept.

        Parameters not given keep their current value, or take the catalog default.
        """
        effects = {key: dict(params) for key, params in self.effects.items()}
        effects[name] = {**effects.get(name, {}), **parameters}
        return self.replace(effects=effects)

    def without_effects(self, *names: str) -> Platform:
        """A copy without the named effects (without any effect when no name is given)."""
        for name in names:
            if name not in self.effects:
                raise InputError(f"effects.{name}: not switched on{suggest(name, self.effects)}")
        keep = {k: v for k, v in self.effects.items() if names and k not in names}
        return self.replace(effects=keep)

    def leg_lengths(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """Leg lengths ``|p + R e_i - c_i|`` (N, 6), m, of platform positions (N, 3), m, and
        orientations (N, 3, 3) in the base frame (e_i, c_i the platform's and the base's
        joints)."""
        e = np.asarray(self.geometry.platform_joints, float)
        c = np.asarray(self.geometry.base_joints, float)
        rotation = np.asarray(rotation, float)
        squares = np.zeros((len(rotation), len(e)))   # summed as np.linalg.norm sums them
        with np.errstate(over="ignore"):   # a pose beyond 1e154 m: an infinite length
            for k in range(3):             # coordinate k, (N, 6), in place
                d = rotation[:, k, 0, None] * e[:, 0]
                d += rotation[:, k, 1, None] * e[:, 1]
                d += rotation[:, k, 2, None] * e[:, 2]
                d += position[:, k, None]
                d -= c[:, k]
                d *= d
                squares += d
        return np.sqrt(squares, out=squares)


_SECTIONS: dict[str, type] = {"geometry": Geometry, "platform": Body, "legs": Legs,
                              "friction": Friction}
_REQUIRED = {
    "geometry": ("base_joints", "platform_joints"),
    "platform": ("mass", "inertia"),
}
_TOP_KEYS = ("gravity", *_SECTIONS, "effects", "limits")


def _check_keys(table: Mapping[str, Any], allowed: tuple[str, ...], prefix: str) -> None:
    for key in table:
        if key not in allowed:
            raise InputError(f"{prefix}{key}: unknown key{suggest(str(key), allowed)}")


def _from_dict(data: object) -> Platform:
    if not isinstance(data, Mapping):
        raise InputError(f"expected a table of keys, got {short(data)}")
    _check_keys(data, _TOP_KEYS, "")
    parts: dict[str, Any] = {}
    for section, kind in _SECTIONS.items():
        table = data.get(section, {} if section not in _REQUIRED else None)
        if table is None:
            raise InputError(f"{section}: missing section [{section}]")
        if not isinstance(table, Mapping):
            raise InputError(f"{section}: expected a table [{section}], got {short(table)}")
        allowed = tuple(f.name for f in dataclasses.fields(kind))
        _check_keys(table, allowed, f"{section}.")
        for key in _REQUIRED.get(section, ()):
            if key not in table:
                raise InputError(f"{section}.{key}: missing")
        parts[section] = kind(**table)
    return Platform(gravity=data.get("gravity", DEFAULT_GRAVITY),
                    effects=data.get("effects", {}), limits=data.get("limits", {}), **parts)
