"""The catalog of optional effects (names, parameters, defaults, units), from the manifest.

``EFFECTS`` maps effect name -> {parameter: default}; ``describe()`` gives the full entries.
The catalog itself is defined, with its symbolic terms, in derive/effects.py.
"""

from __future__ import annotations

from gsfric.manifest import manifest


def describe() -> list[dict]:
    """Effects as listed in the manifest: name, description, parameters (name, default, unit)."""
    return manifest()["effects"]


def _defaults() -> dict[str, dict[str, float]]:
    return {e["name"]: {p["name"]: float(p["default"]) for p in e["parameters"]}
            for e in describe()}


def parameter_names() -> list[str]:
    """Flat names ``effect.parameter``, the order of the effect-parameter vector Q."""
    return [f"{e['name']}.{p['name']}" for e in describe() for p in e["parameters"]]


def __getattr__(name):
    if name == "EFFECTS":
        return _defaults()
    raise AttributeError(name)
