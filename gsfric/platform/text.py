"""A platform as a commented, compact TOML text: grouped tables, units in comments.

``commented_toml(platform)`` writes every number of a ``Platform`` (floats in their shortest
exact form, so ``Platform.from_dict(tomllib.loads(text))`` equals the platform), a joint or a
matrix row per line, the unit and meaning of each key in a comment, an optional header (where
the file came from) and an optional note per key (e.g. what a value was changed from).

>>> from gsfric.models import reference_platform
>>> from gsfric.platform.text import commented_toml
>>> text = commented_toml(reference_platform(), header=["the reference platform"])
>>> text.splitlines()[0]
'# the reference platform'
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from gsfric.platform import catalog
from gsfric.platform.description import Platform, default_universal_axes

MEANINGS: dict[str, str] = {
    "gravity": "along -z of the base frame",
    "geometry.base_joints": "C_i, the universal joints, base frame, one row per leg 1..6",
    "geometry.platform_joints": "E_i, the spherical joints, platform frame; leg i joins C_i "
                                "and E_i",
    "geometry.universal_axes": "first (base-fixed) axis of each universal joint, base frame",
    "geometry.stroke": "shortest and longest leg (steps outside are flagged)",
    "platform.mass": "the moving platform",
    "platform.inertia": "about its centre of mass, platform frame",
    "platform.com": "its centre of mass, platform frame",
    "platform.payload_mass": "the payload",
    "platform.payload_inertia": "about the payload's centre of mass, platform frame",
    "platform.payload_com": "the payload's centre of mass, platform frame",
    "legs.model": '"rigid", or "paper": zone centres at 0.25 D and 0.75 D from C_i',
    "legs.weight": "false leaves the legs' weight out, as the printed (11)-(16) do",
    "legs.lower_mass": "lower part, moves with the universal joint",
    "legs.lower_com": "from C_i along the leg (rigid model)",
    "legs.lower_inertia": "about its centre, leg body frame (z along the leg)",
    "legs.upper_mass": "upper part, moves with the spherical joint end",
    "legs.upper_com": "from E_i along the leg (rigid model)",
    "legs.upper_inertia": "about its centre, leg body frame",
    "friction.joint_viscous": "c_s, spherical and universal joints",
    "friction.joint_coulomb": "mu, spherical and universal joints",
    "friction.joint_radius": "r, the joints' friction radius",
    "friction.prismatic_viscous": "prismatic joints",
    "friction.prismatic_coulomb": "mu of the prismatic joints",
    "friction.model": '"paper": post-hoc, (35) with R_3; "coupled": friction loads the '
                      "actuators",
    "friction.bushing_offset": "first bushing from C_i (coupled model)",
    "friction.bushing_spacing": "between the two bushings (coupled model)",
    "friction.prismatic_seal": "seal friction of the prismatic joints",
}
"""What each key of the platform TOML means (its unit: ``catalog.PLATFORM_UNITS``)."""

_ROWS = ("geometry.base_joints", "geometry.platform_joints", "geometry.universal_axes")


def _number(x: float) -> str:
    """The shortest text that reads back as exactly ``x``."""
    return repr(float(x))


def _value(v) -> str:
    """A TOML value on one line."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return _number(v)


def _comment(key: str, notes: Mapping[str, str]) -> str:
    """Unit, meaning and note of a key, ``; ``-separated."""
    unit = catalog.PLATFORM_UNITS.get(key, "")
    return "; ".join(p for p in (unit if unit not in ("", "1") else "", MEANINGS.get(key, ""),
                                 notes.get(key, "")) if p)


def _line(key: str, value, notes: Mapping[str, str]) -> list[str]:
    name, comment = key.rpartition(".")[2], _comment(key, notes)
    if key in _ROWS:
        return ([f"# {comment}", f"{name} = ["]
                + [f"    {_value(row)}," for row in value] + ["]"])
    return [f"{name} = {_value(value)}" + (f"   # {comment}" if comment else "")]


def _effect_comment(name: str, params: Mapping[str, float], notes: Mapping[str, str]) -> str:
    units = ", ".join(f"{p} {u}" for p in params
                      if (u := catalog.unit(f"{name}.{p}")) not in ("", "1"))
    parts = [p for p in (units, notes.get(f"effects.{name}", "")) if p]
    return "   # " + "; ".join(parts) if parts else ""


def commented_toml(platform: Platform, header: Iterable[str] = (),
                   notes: Mapping[str, str] | None = None) -> str:
    """The platform as a commented TOML text that reads back as an equal platform.

    Parameters
    ----------
    platform : Platform
    header : iterable of str
        Lines for the comment at the top (e.g. where the file came from).
    notes : mapping, optional
        Dotted key (``friction.prismatic_viscous``, ``effects.stribeck``) -> a remark added to
        that key's comment (e.g. ``"refitted; was 0.02"``).

    Returns
    -------
    str
        The TOML text; ``universal_axes`` only where they differ from the default.
    """
    notes = dict(notes or {})
    data = platform.to_dict()
    g = platform.geometry
    if np.array_equal(g.universal_axes, default_universal_axes(g.base_joints)):
        del data["geometry"]["universal_axes"]
    lines = [f"# {h}" if h else "#" for h in header]
    lines += ["" if lines else None, *_line("gravity", data["gravity"], notes)]
    lines = [x for x in lines if x is not None]
    for section in ("geometry", "platform", "legs", "friction"):
        lines += ["", f"[{section}]"]
        for key, value in data[section].items():
            lines += _line(f"{section}.{key}", value, notes)
    lines += ["", "[effects]" + ("" if data["effects"] else
                                 "   # none; `gsfric effects` lists the catalog")]
    for name, params in data["effects"].items():
        lines.append(f"{name} = {_value(params)}{_effect_comment(name, params, notes)}")
    if data.get("limits"):
        lines += ["", "[limits]   # ratings `gsfric sweep` checks the loads against"]
        lines += [f"{k} = {_value(v)}" for k, v in data["limits"].items()]
    return "\n".join(lines) + "\n"
