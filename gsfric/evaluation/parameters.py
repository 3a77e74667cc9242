"""The platform packed into the generated functions' inputs: parameters P, effects Q.

The blocks and their places come from the manifest (``layout(function, input)``); the
regularisation speeds and the prismatic joint's point are the model's fixed parameters. A
platform is packed once (platforms are immutable) and shared by its Evaluators
(``packed``). ``model_function`` picks the generated function derived with the platform's
friction model fixed.
"""

from __future__ import annotations

import functools
import math
import weakref

import numpy as np

from gsfric.compiled.manifest import function, layout, manifest
from gsfric.errors import GsfricError
from gsfric.platform.catalog import GENERATED_EFFECTS
from gsfric.platform.description import Platform

JOINT_EPS = 1e-4       # rad/s, regularisation of the joints' sign function
PRISMATIC_EPS = 1e-5   # m/s, regularisation of the prismatic sign function
PRISMATIC_POINT = 0.5  # prismatic joint point, fraction of D from C_i (the paper's zone 3)

MODEL_FUNCTIONS = {"coupled": "coupled", "paper": "posthoc"}
"""Suffix of the generated functions derived with the platform's friction model fixed
(derive/build.py, ``FIXED_MODELS``): the paper's model then has no fixed-point iterations."""


@functools.lru_cache(maxsize=None)
def model_function(name: str, model: str | None) -> str:
    """The generated function to run for ``name`` ("eval", "actuator") on a platform whose
    friction model is ``model`` ("coupled", "paper"; None: read from P at every step): the
    function derived with that model fixed, or the generic one."""
    suffix = MODEL_FUNCTIONS.get(model)
    if suffix is None:
        return name
    try:
        function(f"{name}_{suffix}")
    except GsfricError:  # generated/ without the fixed-model functions
        return name
    return f"{name}_{suffix}"


def uniform_model(P: np.ndarray) -> str | None:
    """The friction model of every row of a per-step parameter input P (N, size), or None
    when the rows differ."""
    _, slots = _slots("eval", "P")
    column = next(start for name, start, _ in slots if name == "friction_model")
    values = np.asarray(P)[..., column]
    first = float(values.flat[0]) if values.size else 1.0
    if first not in (0.0, 1.0) or np.any(values != first):
        return None
    return "coupled" if first == 1.0 else "paper"


@functools.lru_cache(maxsize=None)
def _slots(function_name: str, input_name: str) -> tuple:
    """(size, ((name, start, stop), ...)) of an input's layout."""
    blocks = layout(function_name, input_name)
    slots = tuple((b["name"], b["offset"], b["offset"] + math.prod(b["shape"])) for b in blocks)
    return max(stop for _, _, stop in slots), slots


def _pack(slots: tuple, values: dict) -> np.ndarray:
    """The named values laid out in one input vector (zeros in any gap of the layout)."""
    size, where = slots
    out = np.zeros(size)
    for name, start, stop in where:
        out[start:stop] = np.ravel(values[name])
    return out


def parameter_values(platform: Platform) -> dict[str, object]:
    """The platform as the named blocks of the parameter input P (see the manifest's layout)."""
    g, b, legs, fr = platform.geometry, platform.platform, platform.legs, platform.friction
    l4, k4, l2, k2 = legs.com_placement()
    return dict(
        gravity=platform.gravity, base_joints=g.base_joints, platform_joints=g.platform_joints,
        universal_axes=g.universal_axes, platform_mass=b.mass, platform_inertia=b.inertia,
        platform_com=b.com, payload_mass=b.payload_mass, payload_inertia=b.payload_inertia,
        payload_com=b.payload_com, lower_mass=legs.lower_mass, lower_com=l4, lower_frac=k4,
        lower_inertia=legs.lower_inertia, upper_mass=legs.upper_mass, upper_com=l2,
        upper_frac=k2, upper_inertia=legs.upper_inertia, leg_weight=float(legs.weight),
        prismatic_point=PRISMATIC_POINT, joint_viscous=fr.joint_viscous,
        joint_coulomb=fr.joint_coulomb, joint_radius=fr.joint_radius,
        prismatic_viscous=fr.prismatic_viscous, prismatic_coulomb=fr.prismatic_coulomb,
        joint_eps=JOINT_EPS, prismatic_eps=PRISMATIC_EPS,
        friction_model=float(fr.model == "coupled"), bushing_offset=fr.bushing_offset,
        bushing_spacing=fr.bushing_spacing, prismatic_seal=fr.prismatic_seal)


def parameter_vector(platform: Platform) -> np.ndarray:
    """The platform packed into the generated functions' parameter input P."""
    return pack_parameters(parameter_values(platform))


def pack_parameters(values: dict[str, object]) -> np.ndarray:
    """Named blocks (``parameter_values``' keys) packed into one parameter input P, without
    the checks of a ``Platform``: for parameter studies that step a value past what a
    platform file accepts (a finite-difference step of an identification)."""
    return _pack(_slots("eval", "P"), values)


def effect_vector(platform: Platform) -> np.ndarray:
    """The platform's effects packed into the effect-parameter input Q (defaults elsewhere).

    Sensor effects (``gsfric.catalog.SENSOR_EFFECTS``) are not inputs of the compiled code:
    ``Evaluator.evaluate`` applies them to F.
    """

    values = []
    for name, params in GENERATED_EFFECTS.items():
        given = platform.effects.get(name, {})
        values += [float(given.get(p, default)) for p, default in params.items()]
    return np.array(values)


_PACKED: dict[int, tuple] = {}


def packed(platform: Platform) -> tuple[np.ndarray, np.ndarray, dict]:
    """P and Q of a platform, read-only, packed once per platform object (platforms are
    immutable) and shared by its Evaluators; and a dict, shared too, of the control loop's
    bound calls on them (filled on first use: building one costs more than a call)."""
    hit = _PACKED.get(id(platform))
    if hit is not None and hit[0]() is platform:
        return hit[1], hit[2], hit[3]
    P, Q = parameter_vector(platform), effect_vector(platform)
    P.flags.writeable = False
    Q.flags.writeable = False
    key = id(platform)
    try:
        ref = weakref.ref(platform, lambda _, key=key: _PACKED.pop(key, None))
    except TypeError:  # not weakly referable: not cached
        return P, Q, {}
    calls: dict = {}
    _PACKED[key] = (ref, P, Q, calls)
    return P, Q, calls


def jacobian_parameters() -> list[str]:
    """Names of the Jacobian's parameters: friction coefficients, masses, then every effect's."""

    return list(manifest()["jacobian_parameters"])
