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
import tomlkit

from gsfric.platform import catalog
from gsfric.platform.description import Platform
from gsfric.platform.values import default_universal_axes

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


def _comment(key: str, notes: Mapping[str, str]) -> str:
    """Unit, meaning and note of a key, ``; ``-separated."""
    unit = catalog.PLATFORM_UNITS.get(key, "")
    return "; ".join(p for p in (unit if unit not in ("", "1") else "", MEANINGS.get(key, ""),
                                 notes.get(key, "")) if p)


def _commented(item, comment: str):
    """The item with ``comment`` after it on its line (none if empty)."""
    if comment:
        item.comment(comment)
        item.trivia.comment_ws = "   "
    return item


def _add(table, key: str, value, notes: Mapping[str, str]) -> None:
    """The key's value into ``table``, a matrix a row per line under its comment."""
    name, comment = key.rpartition(".")[2], _comment(key, notes)
    if key in _ROWS:
        rows = tomlkit.array()
        rows.extend(value)
        table.add(tomlkit.comment(comment))
        table.add(name, rows.multiline(True))
    else:
        table.add(name, _commented(tomlkit.item(value), comment))


def _effect(name: str, params: Mapping[str, float], notes: Mapping[str, str]):
    """An effect's parameters as an inline table ``{ a = 1.0, b = 2.0 }``, their units and
    the note in the comment."""
    inline = tomlkit.inline_table()
    for k, (p, v) in enumerate(params.items()):
        value = tomlkit.item(v)
        value.trivia.indent = " " if k == 0 else ""
        inline.add(p, value)
    inline.add(tomlkit.ws(" "))
    units = ", ".join(f"{p} {u}" for p in params
                      if (u := catalog.unit(f"{name}.{p}")) not in ("", "1"))
    return _commented(inline, "; ".join(p for p in (units, notes.get(f"effects.{name}", ""))
                                        if p))


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
    doc = tomlkit.document()
    _add(doc, "gravity", data["gravity"], notes)
    for section in ("geometry", "platform", "legs", "friction"):
        table = tomlkit.table()
        for key, value in data[section].items():
            _add(table, f"{section}.{key}", value, notes)
        doc.add(tomlkit.nl())
        doc.add(section, table)
    effects = _commented(tomlkit.table(), "" if data["effects"] else
                         "none; `gsfric effects` lists the catalog")
    for name, params in data["effects"].items():
        effects.add(name, _effect(name, params, notes))
    doc.add(tomlkit.nl())
    doc.add("effects", effects)
    if data.get("limits"):
        limits = _commented(tomlkit.table(), "ratings `gsfric sweep` checks the loads against")
        for k, v in data["limits"].items():
            limits.add(k, v)
        doc.add(tomlkit.nl())
        doc.add("limits", limits)
    # the header's lines as they are (tomlkit before 0.15 writes an empty comment as "# ")
    lines = [f"# {h}" if h else "#" for h in header]
    return ("\n".join(lines) + "\n\n" if lines else "") + tomlkit.dumps(doc)
