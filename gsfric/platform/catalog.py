"""The catalog of optional effects (names, parameters, defaults, units), read from the manifest.

derive/effects.py is the one list of every effect; derive/build.py writes it into
generated/manifest.json, from which this module reads it. ``EFFECTS`` maps effect name ->
{parameter: default}; ``describe()`` gives the full entries. Two kinds of effect (an entry's
``kind``):

* **generated** (``GENERATED_EFFECTS``): terms of the mechanics (friction, loads), defined with
  their symbolic form in derive/effects.py; they are inputs ``Q`` of the compiled functions.
* **sensor** (``SENSOR_EFFECTS``): errors of the measuring chain, applied by the runtime (this
  module) as a transform of the model's actuator forces F (N, 6) along a motion of times t:

  - ``force_scale`` (``g1..g6``, 1): a gain error of each load cell,
    ``F_i -> (1 + g_i) F_i``;
  - ``time_offset`` (``delay``, s): the force channels lag the pose channels by ``delay``,
    ``F(t) -> F(t - delay)`` (linear interpolation of the model's forces; the first samples
    hold the first value).

  Their Jacobians follow directly: ``d/dg_i = F_i(t - delay)`` and
  ``d/d delay = -dF/dt (t - delay)`` (see ``sensor_jacobian``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gsfric.compiled.manifest import manifest

GENERATED = "generated"
"""``kind`` of an effect whose parameters are inputs Q of the compiled functions."""

SENSOR = "sensor"
"""``kind`` of an effect that the runtime applies to the model's forces (not in Q)."""


def describe() -> list[dict]:
    """Every effect: name, description, term, kind, parameters (name, default, unit,
    description); generated ones first, in the order of Q."""
    return [dict(e) for e in manifest()["effects"]]


def markdown_table() -> str:
    """The reference's table of effects (docs/reference/effects.md, between its markers)."""
    lines = ["| effect | what | term | parameters (default, unit) |", "|---|---|---|---|"]
    for e in describe():
        what = e["description"] + (" (sensor effect)" if e["kind"] == SENSOR else "")
        params = "; ".join(f"`{p['name']}` ({p['default']:g}, {p['unit']}): {p['description']}"
                           for p in e["parameters"])
        lines.append(f"| `{e['name']}` | {what} | `{e['term']}` | {params} |")
    return "\n".join(lines)


def _of_kind(kind: str) -> dict[str, dict[str, float]]:
    """Effects of one ``kind``: name -> {parameter: default}, in catalog order."""
    return {e["name"]: {p["name"]: float(p["default"]) for p in e["parameters"]}
            for e in manifest()["effects"] if e["kind"] == kind}


def parameter_names() -> list[str]:
    """Flat names ``effect.parameter`` of the generated effects: the order of the vector Q."""
    return [f"{e}.{p}" for e, params in _of_kind(GENERATED).items() for p in params]


def sensor_parameters(effects: Mapping[str, Mapping[str, float]]) -> tuple[np.ndarray, float]:
    """Gains (6,) and delay (s) of a platform's ``effects`` (defaults where not switched on)."""
    sensor = _of_kind(SENSOR)
    scale = effects.get("force_scale", {})
    gains = np.array([float(scale.get(p, d)) for p, d in sensor["force_scale"].items()])
    (name, default), = sensor["time_offset"].items()
    delay = float(effects.get("time_offset", {}).get(name, default))
    return gains, delay


def shift(t: np.ndarray, F: np.ndarray, delay: float) -> np.ndarray:
    """Forces ``F`` (N, k) sampled at ``t`` (N,) (s) as read ``delay`` s later: ``F(t - delay)``
    by linear interpolation, held at the record's ends."""
    if delay == 0.0:
        return F
    out = np.empty_like(F)
    for i in range(F.shape[1]):
        out[:, i] = np.interp(t - delay, t, F[:, i])
    return out


def apply_sensor(t: np.ndarray, F: np.ndarray, gains: np.ndarray, delay: float) -> np.ndarray:
    """The forces a load cell with gain errors and a delay reads, (N, 6) N.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Sample times, s (increasing).
    F : ndarray, shape (N, 6)
        The model's actuator forces, N.
    gains : ndarray, shape (6,)
        ``force_scale`` g1..g6.
    delay : float
        ``time_offset`` delay, s.
    """
    return shift(np.asarray(t, float), np.asarray(F, float), float(delay)) * (1.0 + gains)


def sensor_jacobian(t: np.ndarray, F: np.ndarray, gains: np.ndarray, delay: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives of ``apply_sensor`` with respect to the gains and the delay.

    Returns
    -------
    d_gains : ndarray, shape (N, 6, 6)
        ``d F_out / d g_j``: the shifted F_j on leg j, zero elsewhere.
    d_delay : ndarray, shape (N, 6)
        ``d F_out / d delay = -(1 + g) dF/dt (t - delay)``.
    """
    t = np.asarray(t, float)
    shifted = shift(t, np.asarray(F, float), float(delay))
    d_gains = np.zeros(shifted.shape + (6,))
    for j in range(6):
        d_gains[:, j, j] = shifted[:, j]
    d_delay = -np.gradient(shifted, t, axis=0) * (1.0 + gains)
    return d_gains, d_delay



def __getattr__(name):
    """``EFFECTS`` (every effect), ``GENERATED_EFFECTS`` and ``SENSOR_EFFECTS``: name ->
    {parameter: default}, read from the manifest on first use."""
    if name == "EFFECTS":
        return {**_of_kind(GENERATED), **_of_kind(SENSOR)}
    if name == "GENERATED_EFFECTS":
        return _of_kind(GENERATED)
    if name == "SENSOR_EFFECTS":
        return _of_kind(SENSOR)
    raise AttributeError(name)


PLATFORM_UNITS: dict[str, str] = {
    "gravity": "m/s^2",
    "geometry.base_joints": "m", "geometry.platform_joints": "m",
    "geometry.universal_axes": "1", "geometry.stroke": "m",
    "platform.mass": "kg", "platform.inertia": "kg m^2", "platform.com": "m",
    "platform.payload_mass": "kg", "platform.payload_inertia": "kg m^2",
    "platform.payload_com": "m",
    "legs.lower_mass": "kg", "legs.lower_com": "m", "legs.lower_inertia": "kg m^2",
    "legs.upper_mass": "kg", "legs.upper_com": "m", "legs.upper_inertia": "kg m^2",
    "friction.joint_viscous": "N m s/rad", "friction.joint_coulomb": "1",
    "friction.joint_radius": "m", "friction.prismatic_viscous": "N s/m",
    "friction.prismatic_coulomb": "1", "friction.bushing_offset": "m",
    "friction.bushing_spacing": "m", "friction.prismatic_seal": "N",
}
"""Units of the platform's own numbers, by dotted TOML key."""

_REFIT_SECTIONS = {"payload_mass": "platform", "prismatic_viscous": "friction",
                   "prismatic_coulomb": "friction", "prismatic_seal": "friction",
                   "joint_viscous": "friction", "joint_coulomb": "friction"}


def unit(name: str) -> str:
    """The unit of a parameter: ``effect.parameter`` (catalog), a dotted platform key
    (``friction.prismatic_viscous``) or a bare refitted key (``payload_mass``); "" if unknown.

    Examples
    --------
    >>> from gsfric.platform.catalog import unit
    >>> unit("stribeck.velocity"), unit("payload_mass")
    ('m/s', 'kg')
    """
    if name in PLATFORM_UNITS:
        return PLATFORM_UNITS[name]
    if name in _REFIT_SECTIONS:
        return PLATFORM_UNITS[f"{_REFIT_SECTIONS[name]}.{name}"]
    effect, _, parameter = name.partition(".")
    for entry in describe():
        if entry["name"] == effect:
            for p in entry["parameters"]:
                if p["name"] == parameter:
                    return p["unit"]
    return ""


def with_unit(value: float, unit_: str, digits: int = 4) -> str:
    """``value`` with its unit for a reader: ``12.3 N``, ``4.1 ms`` (a time below 1 s in ms),
    ``0.04`` (unit "1")."""
    if unit_ == "s" and abs(value) < 1.0:
        return f"{value * 1e3:.{digits}g} ms"
    return f"{value:.{digits}g}" + ("" if unit_ in ("", "1") else f" {unit_}")
