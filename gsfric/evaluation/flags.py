"""The step flags: their bits and limits, and their settings for the compiled code.

Step flags (bits of ``Result.flag``; 0 = sound step):

* 1 ``FLAG_NONFINITE``: a non-finite input or output value (outputs set to NaN);
* 2 ``FLAG_STROKE``: a leg length outside ``geometry.stroke``;
* 4 ``FLAG_SINGULAR``: the platform's 6x6 force Jacobian (columns ``(u_i, (E_i - p) x u_i)``)
  is near singular: its singularity measure ``h`` (output ``h``, derive/conditioning.py: the
  volume spanned by the legs' unit wrenches, moments in units of the platform's size, relative
  to orthogonal ones) is below ``SINGULAR_LIMIT = 2 / COND_LIMIT``. Unflagged steps are
  guaranteed a condition number below ``COND_LIMIT`` for that Jacobian with its moment rows
  divided by the platform's size and its columns scaled to unit length;
* 8 ``FLAG_UNIVERSAL``: a leg within ``UNIVERSAL_LIMIT`` of the direction of its universal
  joint's first axis (``1 - (u.a1)^2 < UNIVERSAL_LIMIT``), where the joint's torsion moment is
  undefined;
* 16 ``FLAG_COUPLING``: the coupled friction model's fixed point has not converged: the axial
  forces changed by more than ``COUPLING_TOLERANCE * (1 N + |F0|)`` over the last of its
  iterations (joint friction so large that it nearly locks the mechanism; docs/explanation/friction.md);
* 32 ``FLAG_ROTATION``: the state's rotation block is not a rotation (an entry of
  ``|T^T T - I|`` above ``gsfric.trajectory.ROTATION_TOL``, or ``det T < 0``): the step's only
  flag, its outputs NaN. ``Motion`` refuses such a matrix, so an evaluation never has one;
  the control loop's calls, which take raw states and return no flags, run the same test in C
  with ``rotation_spec`` and raise ``InputError`` naming the step; a controller's call to the
  library of ``gsfric export`` cannot raise, and flags it.

Every flag is computed in C in the same pass as the outputs (``compiled/batch.c``) with the
settings of ``flag_spec`` (tests/helpers.py has an independent NumPy version for the tests).

``check_flagged`` refuses a record whose steps are mostly flagged, naming the flag and its
cause in the platform (``flag_cause``).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from gsfric.compiled.functions import FlagSpec
from gsfric.compiled.state import state_layout
from gsfric.errors import InputError
from gsfric.platform.description import Platform
from gsfric.platform.usable import FIXES, MOSTLY, home_height
from gsfric.trajectory import ROTATION_TOL

FLAG_NONFINITE = 1
FLAG_STROKE = 2
FLAG_SINGULAR = 4
FLAG_UNIVERSAL = 8
FLAG_COUPLING = 16
FLAG_ROTATION = 32
FLAG_NAMES = {FLAG_NONFINITE: "non-finite value", FLAG_STROKE: "leg length outside the stroke",
              FLAG_SINGULAR: "near-singular platform Jacobian",
              FLAG_UNIVERSAL: "leg near its universal joint's first axis",
              FLAG_COUPLING: "coupled friction solve not converged",
              FLAG_ROTATION: "rotation block of the state not a rotation matrix"}
FLAG_BITS = {"NONFINITE": FLAG_NONFINITE, "STROKE": FLAG_STROKE, "SINGULAR": FLAG_SINGULAR,
             "UNIVERSAL": FLAG_UNIVERSAL, "COUPLING": FLAG_COUPLING, "ROTATION": FLAG_ROTATION}
"""Each flag's name (``FLAG_<name>`` here, in compiled/batch.c and, with the library's
prefix, in the library of ``gsfric export``) and bit."""
COUPLING_TOLERANCE = 1e-6
COND_LIMIT = 1e6
SINGULAR_LIMIT = 2.0 / COND_LIMIT
UNIVERSAL_LIMIT = 1e-4


def flag_spec(outputs, stroke: tuple[float, float] | None) -> FlagSpec:
    """The settings of the step flags computed in C (``gsfric_flags`` in ``batch.c``).

    Parameters
    ----------
    outputs : sequence of (name, size, shape)
        The outputs of the function that computes the flags (``CompiledFunction.outputs``):
        the flags read ``D``, ``s2``, ``h`` and, when there, ``coupling_change`` and ``F0``.
    stroke : (float, float) or None
        The legs' length range, m (``geometry.stroke``); None: no stroke flag.
    """
    index = {name: k for k, (name, _, _) in enumerate(outputs)}
    lo, hi = stroke if stroke is not None else (0.0, 0.0)
    states = state_layout()
    return FlagSpec(index["D"], index["s2"], index["h"], stroke is not None, lo, hi,
                    UNIVERSAL_LIMIT, SINGULAR_LIMIT, states.size,
                    index.get("coupling_change", -1), index.get("F0", -1), COUPLING_TOLERANCE,
                    states.rotation.start, ROTATION_TOL)


@functools.lru_cache(maxsize=None)
def rotation_spec() -> FlagSpec:
    """The settings of ``FLAG_ROTATION``'s test alone (no output read, no other flag): the
    ``check`` of the compiled calls that return no flags (``CompiledFunction``), so that the
    control loop's calls refuse the states ``evaluate`` would flag. Shared, read only."""
    states = state_layout()
    return FlagSpec(-1, -1, -1, 0, 0.0, 0.0, UNIVERSAL_LIMIT, SINGULAR_LIMIT, states.size,
                    -1, -1, COUPLING_TOLERANCE, states.rotation.start, ROTATION_TOL)


def _index_list(idx: np.ndarray, limit: int = 10) -> str:
    shown = ", ".join(str(i) for i in idx[:limit])
    return shown + (f", ... ({idx.size - limit} more)" if idx.size > limit else "")


def flag_message(flag: np.ndarray) -> str | None:
    """One line on the flagged steps of ``flag`` (how many, which kinds, which steps), or None
    when no step is flagged."""
    bad = np.flatnonzero(flag)
    if not bad.size:
        return None
    kinds = sorted({FLAG_NAMES[b] for b in FLAG_NAMES if np.any(flag & b)})
    return (f"{bad.size} of {flag.shape[0]} steps flagged ({'; '.join(kinds)}): steps "
            f"{_index_list(bad)}")


def flag_counts(flag: np.ndarray) -> dict[int, int]:
    """Steps of ``flag`` (N,) carrying each flag: bit -> count (every bit of ``FLAG_NAMES``)."""
    return {bit: int(np.count_nonzero(flag & bit)) for bit in FLAG_NAMES}


HUGE = 1e150
"""A platform number above this in magnitude overflows the model's products (a mass times an
acceleration times a length, the squares of the inertia's terms) beyond the largest double,
1.8e308: the outputs of every step are infinite or NaN."""


def check_flagged(platform: Platform, counts: dict[int, int], flagged: int, steps: int,
                  where: str = "") -> None:
    """Raise ``InputError`` when more than ``MOSTLY`` of the ``steps`` are flagged by the model
    (``flagged`` of them; ``counts``: steps per flag, ``flag_counts``): no statistic of the
    rest can stand for the record. The message names the flag most steps carry and the cause:
    the platform's key behind it (``flag_cause``), or the poses."""
    if not steps or flagged <= MOSTLY * steps:
        return
    bit = max(sorted(counts), key=lambda b: counts[b])
    name = next(k for k, b in FLAG_BITS.items() if b == bit)
    prefix = f"{where}: " if where else ""
    raise InputError(f"{prefix}{flagged} of {steps} steps are flagged by the model, "
                     f"{counts[bit]} of them FLAG_{name} ({FLAG_NAMES[bit]}): "
                     f"{flag_cause(platform, bit)}")


def flag_cause(platform: Platform, bit: int) -> str:
    """What in ``platform`` (its key and value), or in the poses, makes most steps carry the
    flag ``bit``: the end of ``check_flagged``'s message."""
    fr, g = platform.friction, platform.geometry
    legs = _legs_near_axes(platform)
    if bit in (FLAG_COUPLING, FLAG_UNIVERSAL) and legs:
        return (f"geometry.universal_axes: the first axis of the universal joints of legs "
                f"{', '.join(str(i + 1) for i in legs)} is within "
                f"{np.degrees(np.arcsin(np.sqrt(AXIS_NEAR))):.0f} degrees of the leg at the "
                "home pose, where the joint's torsion moment, and with it the friction, has no "
                "bound; the first axis must be across the leg (horizontal, for a base joint)")
    if bit == FLAG_COUPLING:
        return (f"friction.joint_coulomb = {fr.joint_coulomb:g} (with friction.joint_radius = "
                f"{fr.joint_radius:g} m) makes the joints' friction so large that it nearly "
                "locks the mechanism, and the coupled friction solve does not converge; "
                "give the rig's coefficient, or friction.model = \"paper\" "
                "(docs/explanation/friction.md)")
    if bit == FLAG_UNIVERSAL:
        return ("geometry.universal_axes: at these poses the legs come along their universal "
                "joint's first axis, where its torsion moment is undefined; the first axis must "
                f"be across the leg, or the poses are not this platform's: fix with {FIXES}")
    if bit == FLAG_NONFINITE:
        huge = [(key, float(np.max(np.abs(v)))) for key, v in _platform_numbers(platform)
                if np.max(np.abs(v), initial=0.0) > HUGE]
        if huge:
            return (f"platform key {huge[0][0]} = {huge[0][1]:g}: beyond {HUGE:g} the model's "
                    "products overflow (every output infinite or NaN); give it in SI units")
        return f"the values of the poses or of the platform overflow; fix with {FIXES}"
    if bit == FLAG_ROTATION:
        return ("the rotation matrices of the poses are not rotations (scaled, sheared or "
                f"mirrored beyond {ROTATION_TOL:g}): build them from quaternions or angles")
    if bit == FLAG_SINGULAR:
        return ("the platform's force Jacobian is near singular at these poses: "
                "geometry.base_joints and geometry.platform_joints (joints that make the legs "
                f"meet or lie in one plane), or poses that are not this platform's: fix with "
                f"{FIXES}")
    stroke = "" if g.stroke is None else f" (geometry.stroke = [{g.stroke[0]:g}, {g.stroke[1]:g}] m)"
    return f"the poses are not this platform's{stroke}: fix with {FIXES}"


def _platform_numbers(platform: Platform):
    """(TOML key, values as a float array) of every number of ``platform``."""
    yield "gravity", np.asarray(platform.gravity, dtype=float)
    for section in ("geometry", "platform", "legs", "friction"):
        part = getattr(platform, section)
        for field in dataclasses.fields(part):
            value = getattr(part, field.name)
            if value is None or isinstance(value, (str, bool)):
                continue
            try:
                yield f"{section}.{field.name}", np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                continue


AXIS_NEAR = 0.05
"""``1 - (u.a1)^2`` of a leg u and its universal joint's first axis a1 at the home pose below
which the axis is taken as along the leg (13 degrees): the torsion moment grows as 1/sin of
that angle, and a platform built so (axes along the legs instead of across them) gets flagged
over its ordinary motion, the coupled friction solve not converging long before a step comes
within ``UNIVERSAL_LIMIT``."""


def _legs_near_axes(platform: Platform) -> list[int]:
    """The legs (0-based) within ``AXIS_NEAR`` of their universal joint's first axis at the
    home pose (level, at ``home_height``); none without a home pose."""
    height = home_height(platform)
    if height is None:
        return []
    g = platform.geometry
    legs = np.asarray(g.platform_joints, float) + [0.0, 0.0, height] \
        - np.asarray(g.base_joints, float)
    u = legs / np.linalg.norm(legs, axis=1, keepdims=True)
    a = np.asarray(g.universal_axes, float)
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    s2 = 1.0 - np.sum(u * a, axis=1) ** 2
    return [int(i) for i in np.flatnonzero(s2 < AXIS_NEAR)]
