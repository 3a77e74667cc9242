"""What a log's column names say: the quantity, the axis and the unit each name suggests.

A name is read as words and a unit: ``"Surge vel [mm/s]"`` is the words ``surge, vel`` and the
unit ``mm/s``; ``"pos_x"`` the words ``pos, x``; ``"Act3 [N]"`` the words ``act, 3`` and ``N``.
The words give a ``Role`` (``kind`` and ``axis``): the kinds are the gsfric inputs a log format
maps (``gsfric.io.logs``): time, position, angle (roll, pitch, yaw), euler (ZXZ alpha, beta,
gamma), quaternion, velocity, acceleration, omega, alpha (angular acceleration) and force.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from gsfric.io.logs import UNITS

TIME_WORDS = frozenset({"t", "time", "timestamp", "stamp", "stamps", "counter", "tick", "ticks",
                        "clock", "timer", "sec", "seconds", "usec", "msec"})
"""Words of a time column's name."""

AXIS_WORDS = {
    "position": {"x": ("x", "surge", "px", "longitudinal"), "y": ("y", "sway", "py", "lateral"),
                 "z": ("z", "heave", "pz", "vertical")},
    "angle": {"roll": ("roll", "rx", "phi"), "pitch": ("pitch", "ry", "theta"),
              "yaw": ("yaw", "rz", "psi", "heading")},
    "euler": {"alpha": ("alpha",), "beta": ("beta",), "gamma": ("gamma",)},
    "quaternion": {"qw": ("qw", "q0"), "qx": ("qx", "q1"), "qy": ("qy", "q2"),
                   "qz": ("qz", "q3")},
}
"""Words that name each axis of a pose quantity (gsfric's name -> the words)."""

VELOCITY_WORDS = frozenset({"vel", "velocity", "speed", "rate", "dot", "v"})
ACCELERATION_WORDS = frozenset({"acc", "accel", "acceleration", "a"})
FORCE_WORDS = frozenset({"act", "actuator", "force", "load", "cell", "loadcell", "f", "leg"})
DOWN_WORDS = frozenset({"down", "ned", "downward"})
"""Words that say a frame's z axis points down."""

VEHICLE_WORDS = frozenset({"surge", "sway", "heave"})
"""The vehicle names of the translations: in the vehicle convention (SAE J670, SNAME for ships,
most motion-simulator controllers) surge is forward, sway to the right and heave down."""

SHORT_RATES = {f"v{a}": ("velocity", a) for a in "xyz"} | {
    f"a{a}": ("acceleration", a) for a in "xyz"} | {
    f"w{a}": ("omega", a) for a in "xyz"} | {f"omega{a}": ("omega", a) for a in "xyz"}
"""One-word rate names: vx, ax, wx, omegax."""

UNIT_ALIASES = {
    "µs": "us", "μs": "us", "usec": "us", "microseconds": "us", "micros": "us",
    "msec": "ms", "milliseconds": "ms", "sec": "s", "seconds": "s", "nsec": "ns",
    "millimetres": "mm", "millimeters": "mm", "meters": "m", "metres": "m",
    "degrees": "deg", "degree": "deg", "°": "deg", "radians": "rad", "rad/sec": "rad/s",
    "deg/sec": "deg/s", "°/s": "deg/s", "mm/s2": "mm/s^2", "m/s2": "m/s^2", "m/s²": "m/s^2",
    "mm/s²": "mm/s^2", "deg/s2": "deg/s^2", "rad/s2": "rad/s^2", "deg/s²": "deg/s^2",
    "rad/s²": "rad/s^2", "kn": "kN", "n": "N",
}
"""Spellings of units in column names, as ``gsfric.io.logs.UNITS`` spells them."""

KNOWN_UNITS = {unit: quantity for quantity, units in UNITS.items() for unit in units}
"""Every unit a log format accepts -> its quantity."""

RATE_QUANTITY = {"speed": "velocity", "acceleration": "acceleration",
                 "angular speed": "omega", "angular acceleration": "alpha"}
"""Quantity of a unit -> the rate kind it says a column is."""

OMEGA_AXES = {"roll": "x", "pitch": "y", "yaw": "z"}
"""The axis of an angular rate named after an angle."""

_UNIT = re.compile(r"^(?P<base>.*?)\s*[\[(](?P<unit>[^\])]*)[\])]\s*$")
_CAMEL = re.compile(r"(?<=[a-z])(?=[A-Z])|(?<=[A-Za-z])(?=[0-9])|(?<=[0-9])(?=[A-Za-z])")


@dataclass(frozen=True)
class Role:
    """What a column's name says it holds.

    Attributes
    ----------
    kind : str
        "time", "position", "angle", "euler", "quaternion", "velocity", "acceleration",
        "omega", "alpha", "force" or "" (nothing gsfric reads).
    axis : str
        For a pose: gsfric's name (x, y, z; roll, pitch, yaw; alpha..; qw..); for a rate the
        axis (x, y, z); for a force the leg (1..6); "" otherwise.
    unit : str or None
        The unit the name gives, spelled as a log format spells it, or None.
    words : tuple of str
        The name's words, lower case.
    """

    kind: str
    axis: str
    unit: str | None
    words: tuple[str, ...]

    @property
    def says_down(self) -> bool:
        """Whether the name says its frame's z points down."""
        return bool(DOWN_WORDS & set(self.words))


def split_name(name: str) -> tuple[tuple[str, ...], str | None]:
    """A column name's words (lower case) and its unit (``UNITS`` spelling, or None)."""
    text = str(name).strip()
    unit = None
    match = _UNIT.match(text)
    if match:
        text, unit = match["base"], _unit(match["unit"])
    words = [w.lower() for part in re.split(r"[^0-9A-Za-z]+", text) if part
             for w in _CAMEL.split(part) if w]
    if unit is None and len(words) > 1 and _unit(words[-1]) in KNOWN_UNITS \
            and words[-1] not in ("m", "n", "g") and not words[-1].isdigit():
        unit = _unit(words.pop())              # "pos_x_mm", "time_us"; not F1's leg "1"
    return tuple(words), unit


def _unit(text: str) -> str | None:
    text = text.strip().replace(" ", "")
    text = UNIT_ALIASES.get(text, UNIT_ALIASES.get(text.lower(), text))
    if text in KNOWN_UNITS:
        return text
    lowered = {u.lower(): u for u in KNOWN_UNITS}
    return lowered.get(text.lower())


def role(name: str) -> Role:
    """The ``Role`` a column's name suggests (kind "" when it names nothing gsfric reads)."""
    words, unit = split_name(name)
    kind, axis = _kind(words, unit)
    return Role(kind, axis, unit, words)


def _kind(words: tuple[str, ...], unit: str | None) -> tuple[str, str]:
    quantity = KNOWN_UNITS.get(unit or "")
    found = set(words)
    if quantity == "force" or (FORCE_WORDS & found and quantity in (None, "force")):
        leg = [w for w in words if w in "123456" and len(w) == 1]
        if leg and (quantity == "force" or FORCE_WORDS & found):
            return "force", leg[0]
    if quantity == "time" or (TIME_WORDS & found and quantity is None and len(words) <= 3):
        return "time", ""
    for word in words:
        if word in SHORT_RATES:
            return SHORT_RATES[word]
    rate = RATE_QUANTITY.get(quantity or "") or _rate_words(found)
    for kind in ("position", "angle", "euler", "quaternion"):
        for axis, names in AXIS_WORDS[kind].items():
            if found & set(names):
                return _rate_kind(kind, axis, rate)
    return "", ""


def _rate_words(found: set[str]) -> str | None:
    """The rate a name's words say: velocity, acceleration, omega, alpha (angular
    acceleration, "alpha" with an axis: ``alpha_x``), or None."""
    angular = "angular" in found or "omega" in found
    if "alpha" in found and found & {"x", "y", "z"}:
        return "alpha"
    if VELOCITY_WORDS & found or "omega" in found:
        return "omega" if angular else "velocity"
    if ACCELERATION_WORDS & found:
        return "alpha" if angular else "acceleration"
    return None


def _rate_kind(kind: str, axis: str, rate: str | None) -> tuple[str, str]:
    """The kind of a column named after a pose axis, with the rate its words or unit say."""
    if rate is None:
        return kind, axis
    if kind == "position":
        return rate, axis
    if kind == "angle":
        angular = "omega" if rate in ("velocity", "omega") else "alpha"
        return angular, OMEGA_AXES[axis]
    return "", ""
