"""A controller's frame mapped onto the platform's: signed axis order, then a pose offset.

A log's poses are given in the controller's own base frame. ``LogFrame`` maps them onto the
platform's base frame in two steps: the log's axes, reordered and signed (``axes``), then a
rotation and a shift (``offset``). With M the signed permutation of ``axes`` (3, 3), R0 the
rotation of the offset's ``roll, pitch, yaw`` (in the log's angle convention) and o its
``x, y, z``:

* position ``p = R0 M p_log + o``;
* orientation ``R = R0 M R_log M^T`` (a proper rotation for either sign of det M);
* velocity and acceleration ``v = R0 M v_log``; angular velocity and acceleration
  ``omega = det(M) R0 M omega_log`` (an axial vector).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from gsfric._checks import short, suggest
from gsfric.errors import InputError
from gsfric.signal.rotations import quaternion_from_rpy, quaternion_multiply

AXES = ("x", "y", "z")


OFFSET_KEYS = ("x", "y", "z", "roll", "pitch", "yaw")
"""Keys of a pose offset: a shift, m, and a rotation, rad (in the log's angle convention)."""


def _signed_axes(value: object) -> tuple[str, str, str]:
    """``"x,-y,-z"`` or ``["x", "-y", "-z"]`` as a checked tuple of three signed axes."""
    items = value.split(",") if isinstance(value, str) else value
    if not isinstance(items, Sequence) or isinstance(items, str):
        raise InputError(f"axes: expected three signed axes such as 'x,-y,-z', got "
                         f"{short(value)}")
    axes = tuple(str(item).strip().replace("+", "") for item in items)
    if len(axes) != 3 or any(a.lstrip("-") not in AXES for a in axes):
        raise InputError(f"axes: expected three signed axes such as 'x,-y,-z', got "
                         f"{short(value)}")
    names = [a.lstrip("-") for a in axes]
    if len(set(names)) != 3:
        repeated = next(n for n in names if names.count(n) > 1)
        raise InputError(f"axes: the log's axis {repeated!r} is used twice in {short(value)}")
    return axes  # type: ignore[return-value]


def _offset(value: object) -> dict[str, float]:
    if not isinstance(value, Mapping):
        raise InputError(f"offset: expected a table of x, y, z (m) and roll, pitch, yaw (rad), "
                         f"got {short(value)}")
    out = {}
    for key, number in value.items():
        if key not in OFFSET_KEYS:
            raise InputError(f"offset: unknown key {short(key)}{suggest(key, OFFSET_KEYS)}")
        if isinstance(number, bool) or not isinstance(number, (int, float, np.number)) \
                or not np.isfinite(number):
            raise InputError(f"offset.{key}: expected a finite number, got {short(number)}")
        if key in ("roll", "pitch", "yaw") and abs(number) > 2 * np.pi:
            raise InputError(f"offset.{key}: {number:g} rad is more than a turn: degrees? "
                             f"give it in rad ({np.radians(number):.6g})")
        out[str(key)] = float(number)
    return out


@dataclass(frozen=True)
class LogFrame:
    """The map from a log's base frame to the platform's.

    Parameters
    ----------
    axes : sequence of three str, or str
        For the platform's x, y and z in turn, the log's axis it is, with a sign: e.g.
        ``("x", "-y", "-z")`` for a controller whose y and z point the other way (z down),
        ``("y", "x", "-z")`` for north-east-down. Default ``("x", "y", "z")``.
    offset : mapping of str to float
        ``x, y, z``, m, added to the position after the axes (e.g. ``z = 1.1`` when the log's
        heave is zero at the home pose 1.1 m above the base joints), and ``roll, pitch, yaw``,
        rad, a rotation applied after the axes (the log's angle convention). Missing keys
        are 0.
    """

    axes: tuple[str, str, str] = AXES
    offset: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "axes", _signed_axes(self.axes))
        object.__setattr__(self, "offset", _offset(self.offset))

    @property
    def identity(self) -> bool:
        """Whether the map changes nothing."""
        return self.axes == AXES and not any(self.offset.values())

    def matrix(self) -> np.ndarray:
        """M (3, 3): the signed permutation of ``axes`` (platform axis i = row i)."""
        m = np.zeros((3, 3))
        for i, axis in enumerate(self.axes):
            m[i, AXES.index(axis.lstrip("-"))] = -1.0 if axis.startswith("-") else 1.0
        return m

    def _rotation_offset(self, convention: str) -> np.ndarray | None:
        angles = [self.offset.get(k, 0.0) for k in ("roll", "pitch", "yaw")]
        if not any(angles):
            return None
        return quaternion_from_rpy(np.array([angles]), convention)[0]

    def position(self, p: np.ndarray, convention: str) -> np.ndarray:
        """Positions (N, 3), m, in the platform's base frame."""
        out = self.vector(p, convention)
        shift = np.array([self.offset.get(k, 0.0) for k in AXES])
        return out + shift if shift.any() else out

    def vector(self, v: np.ndarray, convention: str, axial: bool = False) -> np.ndarray:
        """Vectors (N, 3) (velocities, accelerations; ``axial`` for angular ones) in the
        platform's base frame."""
        m = self.matrix()
        if axial:
            m = m * np.linalg.det(m)
        out = v @ m.T
        q0 = self._rotation_offset(convention)
        if q0 is not None:
            out = _rotate(q0, out)
        return out

    def quaternion(self, q: np.ndarray, convention: str) -> np.ndarray:
        """Orientation quaternions (N, 4) ``(qw, qx, qy, qz)`` in the platform's base frame."""
        m = self.matrix()
        vector = q[:, 1:] @ (m * np.linalg.det(m)).T
        out = np.concatenate([q[:, :1], vector], axis=1)
        q0 = self._rotation_offset(convention)
        if q0 is not None:
            out = quaternion_multiply(np.broadcast_to(q0, out.shape), out)
        return out


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The vectors v (N, 3) rotated by the unit quaternion q (4,)."""
    w, u = q[0], q[1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)
