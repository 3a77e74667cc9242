"""Logs written by other programs: column maps, units, angle conventions and time counters
(``LogFormat``), and the reading of their columns into SI arrays (``ColumnReader``)."""

from __future__ import annotations

import difflib
import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import tomllib

from gsfric._checks import short, suggest
from gsfric.errors import GsfricWarning, InputError
from gsfric.io.tables import numeric_columns
from gsfric.signal.rotations import quaternion_from_rpy

TIME_POSITION = ("t", "x", "y", "z")


EULER = ("alpha", "beta", "gamma")


QUATERNION = ("qw", "qx", "qy", "qz")


FORCES = tuple(f"F{i}" for i in range(1, 7))


LENGTHS = tuple(f"D{i}" for i in range(1, 7))


RPY = ("roll", "pitch", "yaw")


KNOWN = TIME_POSITION + EULER + QUATERNION + RPY + FORCES + LENGTHS
"""Every input column gsfric reads; others are ignored (or carried through, ``LogFormat.keep``)."""

UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6},
    "angle": {"rad": 1.0, "deg": np.pi / 180.0, "mrad": 1e-3},
    "force": {"N": 1.0, "kN": 1e3},
    "quaternion": {"1": 1.0},
}
"""Accepted units per quantity and their factor to SI."""

RPY_CONVENTIONS = {"xyz": "extrinsic x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll)",
                   "XYZ": "intrinsic X, Y, Z: R = Rx(roll) Ry(pitch) Rz(yaw)"}


def _quantity(name: str) -> str:
    if name == "t":
        return "time"
    if name in ("x", "y", "z") or name in LENGTHS:
        return "length"
    if name in EULER or name in RPY:
        return "angle"
    if name in FORCES:
        return "force"
    return "quaternion"


def _pairs(text: str, what: str) -> dict[str, str]:
    """``"a=b,c=d"`` as {a: b, c: d}; InputError naming ``what`` on a malformed item."""
    out: dict[str, str] = {}
    for item in (part.strip() for part in str(text).split(",")):
        if not item:
            continue
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise InputError(f"{what}: expected name=value, got {short(item)}")
        out[key.strip()] = value.strip()
    return out


@dataclass(frozen=True)
class LogFormat:
    """How to read a log whose column names, units or angles are not gsfric's own.

    Parameters
    ----------
    columns : mapping of str to str
        gsfric's column name (``t, x, y, z``, ``alpha, beta, gamma``, ``qw..qz``,
        ``roll, pitch, yaw``, ``F1..F6``, ``D1..D6``) to the log's column name. Unmapped names
        are looked up as they are.
    units : mapping of str to str
        gsfric's column name to the unit of the log's column: ``s, ms, us, ns`` (t);
        ``m, cm, mm, um`` (x, y, z, D1..D6); ``rad, deg, mrad`` (angles); ``N, kN`` (F1..F6).
        Values are converted to SI on reading; unlisted columns are in SI already.
    angles : {"xyz", "XYZ"}
        Convention of ``roll, pitch, yaw`` (rotation from platform frame to base frame, as
        SciPy's ``Rotation.from_euler`` names it): "xyz" extrinsic about the base axes x, then
        y, then z, R = Rz(yaw) Ry(pitch) Rx(roll) (the usual vehicle/motion-platform
        convention, the default); "XYZ" intrinsic, R = Rx(roll) Ry(pitch) Rz(yaw).
    wrap : int, optional
        Modulus of an integer time counter that wraps around (e.g. 2**32 for a uint32
        microsecond counter). Default: 2**16, 2**32 or 2**64, the smallest above the largest
        count read. A decrease of more than half the modulus is unwrapped (with a warning);
        any other decrease is an error.
    keep : sequence of str
        Log columns carried through unchanged to ``simulate``'s output (others are ignored).
    force_noise : float or sequence of 6 floats, optional
        The load cells' noise (standard deviation in N, whatever the units of F1..F6: the
        sensor's specification), one value or one per leg: ``gsfric discover`` compares its
        residual with it (``--force-noise`` on the command line wins).

    The TOML form (``LogFormat.from_toml``; ``gsfric simulate --column-map FILE.toml``)::

        angles = "xyz"
        keep = ["temperature"]
        force_noise = 0.05
        [columns]
        t = "C2H time (us)"
        x = "pos_x"
        [units]
        t = "us"
        x = "mm"
    """

    columns: Mapping[str, str] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    angles: str = "xyz"
    wrap: int | None = None
    keep: tuple[str, ...] = ()
    force_noise: float | tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        columns = {str(k): str(v) for k, v in dict(self.columns).items()}
        units = {str(k): str(v) for k, v in dict(self.units).items()}
        for key in list(columns) + list(units):
            if key not in KNOWN:
                raise InputError(f"column map: unknown gsfric column {short(key)}"
                                 f"{suggest(key, KNOWN)}")
        seen: dict[str, str] = {}
        for key, source in columns.items():
            if source in seen:
                raise InputError(f"column map: column {source!r} is mapped to both "
                                 f"{seen[source]!r} and {key!r}")
            seen[source] = key
        for key, unit in units.items():
            choices = UNITS[_quantity(key)]
            if unit not in choices:
                raise InputError(f"units: {key!r} in {unit!r}: use one of "
                                 f"{', '.join(choices)}")
        if self.angles not in RPY_CONVENTIONS:
            raise InputError(f"angles: unknown convention {short(self.angles)}; use 'xyz' "
                             "(extrinsic) or 'XYZ' (intrinsic)")
        wrap = self.wrap
        if wrap is not None and (isinstance(wrap, bool) or not isinstance(wrap, (int, np.integer))
                                 or wrap < 2):
            raise InputError(f"wrap: must be an integer >= 2, got {short(wrap)}")
        keep = (self.keep,) if isinstance(self.keep, str) else tuple(map(str, self.keep))
        object.__setattr__(self, "force_noise", _force_noise(self.force_noise))
        object.__setattr__(self, "columns", columns)
        object.__setattr__(self, "units", units)
        object.__setattr__(self, "keep", keep)

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str]) -> LogFormat:
        """Read a TOML file with ``[columns]``, ``[units]``, ``angles``, ``wrap``, ``keep``."""
        return cls.from_mapping(_read_toml(path), str(path))

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "column map") -> LogFormat:
        allowed = ("columns", "units", "angles", "wrap", "keep", "force_noise")
        for key in data:
            if key not in allowed:
                raise InputError(f"{where}: unknown key {short(key)}{suggest(key, allowed)}")
        for key in ("columns", "units"):
            if not isinstance(data.get(key, {}), dict):
                raise InputError(f"{where}: [{key}] must be a table of name = \"value\"")
        try:
            return cls(columns=data.get("columns", {}), units=data.get("units", {}),
                       angles=data.get("angles", "xyz"), wrap=data.get("wrap"),
                       keep=tuple(data.get("keep", ())), force_noise=data.get("force_noise"))
        except InputError as error:
            raise InputError(f"{where}: {error}") from None

    @classmethod
    def from_options(cls, column_map: str | None = None, units: str | None = None,
                     angles: str | None = None, keep: str | None = None) -> LogFormat | None:
        """The command line's form: ``--column-map`` (a .toml file or ``t=col,x=col``),
        ``--units t=us,x=mm``, ``--angles``, ``--keep-columns a,b``; None when all are None."""
        if column_map is None and units is None and angles is None and keep is None:
            return None
        data: dict[str, Any] = {}
        if column_map is not None:
            if str(column_map).lower().endswith(".toml"):
                data = dict(_read_toml(column_map))
            else:
                data["columns"] = _pairs(column_map, "--column-map")
        where = str(column_map) if data and column_map and str(column_map).lower().endswith(
            ".toml") else "column map"
        if units is not None:
            data["units"] = {**data.get("units", {}), **_pairs(units, "--units")}
        if angles is not None:
            data["angles"] = angles
        if keep is not None:
            data["keep"] = [k.strip() for k in keep.split(",") if k.strip()]
        return cls.from_mapping(data, where)


def _force_noise(value) -> tuple[float, ...] | None:
    """``force_noise`` as six standard deviations, N (None: not given); InputError for
    anything but one positive number or six."""
    if value is None:
        return None
    values = list(value) if isinstance(value, (list, tuple)) else [value]
    if len(values) not in (1, 6) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            and v > 0 for v in values):
        raise InputError(f"force_noise: one number > 0 (N) or six, one per leg, got "
                         f"{short(value)}")
    return tuple(float(v) for v in values) * (6 if len(values) == 1 else 1)


def _read_toml(path) -> dict:
    path = Path(path)
    try:
        with open(path, "rb") as handle:
            return tomllib.load(handle)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{path}: not valid TOML ({error})") from None


class ColumnReader:
    """Reads a log's blocks of rows into gsfric's columns, in SI units.

    One reader per file, fed its blocks in order (it keeps the state of a wrapping time
    counter). ``check`` validates the header once; ``read`` converts a block.

    Attributes
    ----------
    orientation : tuple of str
        The orientation columns of the converted blocks: ``QUATERNION`` (also for roll, pitch,
        yaw, converted) or ``EULER``.
    forces : bool
        The log has F1..F6.
    keep : tuple of str
        Log columns carried through (``LogFormat.keep``).
    """

    def __init__(self, path: str | os.PathLike[str], log_format: LogFormat | None = None,
                 measured: bool = False) -> None:
        self.path = Path(path)
        self.format = log_format or LogFormat()
        self.measured = measured
        self.source: dict[str, str] = {}
        self.orientation: tuple[str, ...] = ()
        self.forces = False
        self.keep: tuple[str, ...] = ()
        self._last: int | None = None
        self._offset = 0
        self._largest = 0
        self._wraps: list[int] = []
        self._warned_radians = False

    def check(self, names: list[str]) -> tuple[str, ...]:
        """Validate the header (stripped names); return ``orientation``. Warns of ignored columns."""
        path, fmt = self.path, self.format
        source = _sources(path, fmt, names)
        ignored = [n for n in names if n not in source.values() and n not in fmt.keep]

        def missing(key: str, why: str) -> InputError:
            return _missing(path, ignored, key, why)

        angles = _orientation(path, source, missing)
        forces = [n for n in FORCES if n in source]
        if (self.measured or forces) and len(forces) < 6:
            raise missing(next(n for n in FORCES if n not in source),
                          " (measured data need F1..F6)")
        lengths = [n for n in LENGTHS if n in source]
        if lengths and len(lengths) < 6:
            raise missing(next(n for n in LENGTHS if n not in source),
                          " (give all of D1..D6 or none)")
        for key in fmt.units:
            if key not in source:
                raise InputError(f"{path}: units given for {key!r}, which the file does not have")
        if ignored:
            shown = ", ".join(repr(n) for n in ignored[:8])
            more = f" and {len(ignored) - 8} more" if len(ignored) > 8 else ""
            warnings.warn(f"{path}: ignored columns {shown}{more} (not gsfric inputs; map them "
                          "with --column-map or carry them to the output with --keep-columns; "
                          "in Python: LogFormat columns, keep)",
                          GsfricWarning, stacklevel=3)
        self.source = source
        self.forces = len(forces) == 6
        self.keep = fmt.keep
        self._angles = angles
        self.orientation = QUATERNION if angles is RPY else angles
        return self.orientation

    def read(self, frame, first_row: int = 0) -> dict[str, np.ndarray]:
        """The block's columns (a DataFrame with the stripped header) as gsfric's, SI units.

        Keys: ``t, x, y, z``, the orientation columns, F1..F6 and D1..D6 where present, and
        ``keep:NAME`` for each column carried through (values as in the file).
        """
        keys = list(self.source)
        raw = numeric_columns(self.path, frame[[self.source[k] for k in keys]],
                              [self.source[k] for k in keys], first_row)
        out: dict[str, np.ndarray] = {}
        for key in keys:
            values = raw[self.source[key]]
            if key == "t" and frame[self.source["t"]].dtype.kind in "iu":
                values = self._unwrap(frame[self.source["t"]].to_numpy(), first_row)
            unit = self.format.units.get(key)
            if unit is not None and unit != "1":
                values = values * UNITS[_quantity(key)][unit]
            out[key] = values
        if self._angles is RPY:
            angles = np.stack([out.pop(k) for k in RPY], axis=1)
            if not self._warned_radians and "roll" not in self.format.units and len(angles) \
                    and np.abs(angles).max() > 2 * np.pi:
                self._warned_radians = True
                warnings.warn(f"{self.path}: roll, pitch, yaw look like degrees (above 2*pi); "
                              "give their unit with --units roll=deg,pitch=deg,yaw=deg",
                              GsfricWarning, stacklevel=3)
            q = quaternion_from_rpy(angles, self.format.angles)
            for k, key in enumerate(QUATERNION):
                out[key] = q[:, k]
        for column in self.keep:
            out[f"keep:{column}"] = frame[column].to_numpy()
        return out

    def _unwrap(self, counts: np.ndarray, first_row: int) -> np.ndarray:
        """An integer time counter made increasing across its wrap-arounds (as float)."""
        counts = counts.astype(np.int64) if counts.dtype.kind == "u" and counts.max(
            initial=0) < 2**63 else counts
        if len(counts) == 0:
            return counts.astype(float)
        self._largest = max(self._largest, int(counts.max()))
        modulus = self.format.wrap or next(
            (m for m in (2**16, 2**32, 2**64) if self._largest < m), 2**64)
        joined = counts if self._last is None else np.concatenate([[self._last], counts])
        steps = np.diff(joined.astype(float))
        wraps = steps < -modulus / 2
        offsets = np.cumsum(wraps) * float(modulus)
        if self._last is not None:
            values = counts.astype(float) + self._offset + offsets
        else:
            values = counts.astype(float) + self._offset + np.concatenate([[0.0], offsets])
        rows = np.flatnonzero(wraps) + first_row + (1 if self._last is None else 0)
        for row in rows:
            warnings.warn(f"{self.path}: row {row + 1}: time counter {self.source['t']!r} wraps "
                          f"around (modulus {modulus}); unwrapped", GsfricWarning, stacklevel=4)
        self._offset = values[-1] - float(counts[-1])
        self._last = int(counts[-1])
        return values


def _sources(path: Path, fmt: LogFormat, names: list[str]) -> dict[str, str]:
    """gsfric column -> the log's column, for every known column the log has or maps; the
    column map's and ``keep``'s columns checked against the header ``names``."""
    present = set(names)
    for key, column in fmt.columns.items():
        if column not in present:
            raise InputError(f"{path}: column map {key} = {column!r}: no such column"
                             f"{suggest(column, names)}")
    mapped_sources = set(fmt.columns.values())
    source = {}
    for key in KNOWN:
        column = fmt.columns.get(key, key)
        if key not in fmt.columns and (key not in present or key in mapped_sources):
            continue
        source[key] = column
    for column in fmt.keep:
        if column not in present:
            raise InputError(f"{path}: column {column!r} to keep: no such column"
                             f"{suggest(column, names)}")
    return source


def _missing(path: Path, ignored: list[str], key: str, why: str) -> InputError:
    """The error for a missing column ``key``, naming the closest of the ``ignored`` columns."""
    close = difflib.get_close_matches(key.lower(), [n.lower() for n in ignored], n=1,
                                      cutoff=0.6)
    if close:
        match = next(n for n in ignored if n.lower() == close[0])
        return InputError(f"{path}: missing column {key!r} (is it {match!r}? map it "
                          f"with --column-map {key}={match})")
    return InputError(f"{path}: missing column {key!r}{why}")


def _orientation(path: Path, source: dict[str, str], missing) -> tuple[str, ...]:
    """The orientation columns used (``QUATERNION``, ``EULER`` or ``RPY``, in this order of
    preference); the others are dropped from ``source``. Time and position checked first."""
    for key in TIME_POSITION:
        if key not in source:
            raise missing(key, f" (map the log's column to it with --column-map {key}=NAME)")
    has = {group: [n for n in group if n in source] for group in (EULER, QUATERNION, RPY)}
    for group, found in has.items():
        if found:
            for key in group:
                if key not in source:
                    raise missing(key, f" (columns {', '.join(group)} go together)")
    if not any(has.values()):
        raise InputError(f"{path}: missing orientation: give columns alpha, beta, gamma, "
                         "qw, qx, qy, qz or roll, pitch, yaw")
    angles = QUATERNION if has[QUATERNION] else EULER if has[EULER] else RPY
    for group in (EULER, QUATERNION, RPY):   # other orientation sets: unused, silently
        if group is not angles:
            for key in group:
                source.pop(key, None)
    return angles
