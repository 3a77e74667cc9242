"""Logs written by other programs: column maps, units, angle conventions and time counters
(``LogFormat``), and the reading of their columns into SI arrays (``ColumnReader``)."""

from __future__ import annotations


import difflib
import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from gsfric._checks import short, suggest
from gsfric.errors import DataWarning, GsfricWarning, IgnoredColumnsWarning, InputError
from gsfric.io.files import read_toml
from gsfric.io.frames import LogFrame
from gsfric.io.tables import numeric_columns
from gsfric.signal.rotations import quaternion_from_euler, quaternion_from_rpy
from gsfric.trajectory import check_sampling_rate

TIME_POSITION = ("t", "x", "y", "z")


EULER = ("alpha", "beta", "gamma")


QUATERNION = ("qw", "qx", "qy", "qz")


FORCES = tuple(f"F{i}" for i in range(1, 7))


LENGTHS = tuple(f"D{i}" for i in range(1, 7))


RPY = ("roll", "pitch", "yaw")


KNOWN = TIME_POSITION + EULER + QUATERNION + RPY + FORCES + LENGTHS
"""Every input column gsfric reads; others are ignored (or carried through, ``LogFormat.keep``)."""

VELOCITY = ("vx", "vy", "vz")


OMEGA = ("omega_x", "omega_y", "omega_z")


ACCELERATION = ("ax", "ay", "az")


ANGULAR_ACCELERATION = ("alpha_x", "alpha_y", "alpha_z")


RATES = {"velocity": VELOCITY, "omega": OMEGA, "acceleration": ACCELERATION,
         "alpha": ANGULAR_ACCELERATION}
"""The log's own rates (base frame), by ``Motion`` attribute: read only when the column map
names them (``LogFormat.columns``), each group of three all or none."""

RATE_KEYS = VELOCITY + OMEGA + ACCELERATION + ANGULAR_ACCELERATION

ORIENTATION_TOLERANCE = 1e-3
"""Largest angle, rad, between the rotations of two orientation sets of one row (quaternion and
ZXZ or roll/pitch/yaw angles) that are taken to agree: angles written with four decimals in
degrees differ by 1e-6 rad, a wrong column or convention by far more than 1e-3 rad."""

WRAP_STEPS = 100
"""A decrease of an integer time counter is a wrap around its modulus when the step across it
(count + modulus - previous count) is at most this many typical (median) steps; any other
decrease is a reset (a controller reboot) and an error."""

UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6},
    "angle": {"rad": 1.0, "deg": np.pi / 180.0, "mrad": 1e-3},
    "force": {"N": 1.0, "kN": 1e3},
    "quaternion": {"1": 1.0},
    "speed": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3},
    "angular speed": {"rad/s": 1.0, "deg/s": np.pi / 180.0},
    "acceleration": {"m/s^2": 1.0, "cm/s^2": 1e-2, "mm/s^2": 1e-3, "g": 9.80665},
    "angular acceleration": {"rad/s^2": 1.0, "deg/s^2": np.pi / 180.0},
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
    if name in VELOCITY:
        return "speed"
    if name in OMEGA:
        return "angular speed"
    if name in ACCELERATION:
        return "acceleration"
    if name in ANGULAR_ACCELERATION:
        return "angular acceleration"
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
        if key.strip() in out:
            raise InputError(f"{what}: {key.strip()!r} given twice ({out[key.strip()]!r} and "
                             f"{value.strip()!r}); give each name once")
        out[key.strip()] = value.strip()
    return out


SHOWN_IGNORED = 5
"""Ignored columns a warning names (the rest are counted): the names a user maps or keeps."""


@dataclass(frozen=True)
class LogFormat:
    """How to read a log whose column names, units or angles are not gsfric's own.

    Parameters
    ----------
    columns : mapping of str to str
        gsfric's column name (``t, x, y, z``, ``alpha, beta, gamma``, ``qw..qz``,
        ``roll, pitch, yaw``, ``F1..F6``, ``D1..D6``) to the log's column name. Unmapped names
        are looked up as they are. The log's own rates, base frame, are read only when
        mapped here (``RATES``; each group of three all or none): ``vx, vy, vz`` (velocity),
        ``omega_x..omega_z`` (angular velocity), ``ax, ay, az`` (acceleration),
        ``alpha_x..alpha_z`` (angular acceleration); the motion then takes them instead of
        differentiating the poses (an acceleration not given is the smoothed derivative of the
        velocity given).
    units : mapping of str to str
        gsfric's column name to the unit of the log's column: ``s, ms, us, ns`` (t);
        ``m, cm, mm, um`` (x, y, z, D1..D6); ``rad, deg, mrad`` (angles); ``N, kN`` (F1..F6);
        ``m/s, cm/s, mm/s``; ``rad/s, deg/s``; ``m/s^2, cm/s^2, mm/s^2, g``;
        ``rad/s^2, deg/s^2``. Values are converted to SI on reading; unlisted columns are in
        SI already.
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
    axes : sequence of three str, or str
        The controller's frame onto the platform's (``gsfric.io.frames.LogFrame``): for the
        platform's x, y, z, the log's signed axis, e.g. ``"x,-y,-z"``. Default ``"x,y,z"``.
    offset : mapping of str to float
        Pose offset applied after ``axes``: ``x, y, z``, m, added to the position, and
        ``roll, pitch, yaw``, rad (convention ``angles``), a rotation of the log's frame
        (``LogFrame``). E.g. ``{"z": 1.1}`` for a heave that is zero at the home pose.
    force_noise : float or sequence of 6 floats, optional
        The load cells' noise (standard deviation in N, whatever the units of F1..F6: the
        sensor's specification), one value or one per leg: ``gsfric discover`` compares its
        residual with it (``--force-noise`` on the command line wins).
    angles_option : bool
        ``angles`` came from the command line (``--angles``): a log without roll, pitch, yaw
        columns (and without an offset rotation) then refuses it rather than ignore it.

    The TOML form (``LogFormat.from_toml``; ``gsfric simulate --column-map FILE.toml``)::

        angles = "xyz"
        keep = ["temperature"]
        axes = ["x", "-y", "-z"]
        [offset]
        z = 1.1
        force_noise = 0.05
        [columns]
        t = "C2H time (us)"
        x = "pos_x"
        [units]
        t = "us"
        x = "mm"

    Examples
    --------
    >>> import gsfric
    >>> log = gsfric.LogFormat(columns={"t": "time (us)", "x": "pos_x"}, units={"t": "us", "x": "mm"})
    >>> log.units["x"]
    'mm'
    """

    columns: Mapping[str, str] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    angles: str = "xyz"
    wrap: int | None = None
    keep: tuple[str, ...] = ()
    axes: Any = ("x", "y", "z")
    offset: Mapping[str, float] = field(default_factory=dict)
    force_noise: float | tuple[float, ...] | None = None
    angles_option: bool = False

    def __post_init__(self) -> None:
        columns = {str(k): str(v) for k, v in dict(self.columns).items()}
        units = {str(k): str(v) for k, v in dict(self.units).items()}
        for key in list(columns) + list(units):
            if key not in KNOWN + RATE_KEYS:
                raise InputError(f"column map: unknown gsfric column {short(key)}"
                                 f"{suggest(key, KNOWN + RATE_KEYS)}")
        for group in RATES.values():
            given = [k for k in group if k in columns]
            if given and len(given) < 3:
                missing = next(k for k in group if k not in columns)
                raise InputError(f"column map: {missing!r} missing (columns "
                                 f"{', '.join(group)} go together)")
        seen: dict[str, str] = {}
        for key, source in columns.items():
            if source in seen:
                raise InputError(f"column map: column {source!r} is mapped to both "
                                 f"{seen[source]!r} and {key!r}")
            seen[source] = key
        for key, unit in units.items():
            quantity = _quantity(key)
            choices = UNITS[quantity]
            if unit not in choices and len(choices) == 1:
                raise InputError(f"units: {key!r} is a {quantity} without a unit: leave it "
                                 "out of [units]")
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
        keep = (self.keep,) if isinstance(self.keep, str) else self.keep
        if not isinstance(keep, (list, tuple)) or not all(isinstance(k, str) for k in keep):
            raise InputError(f"keep: expected a column name or a list of them, got "
                             f"{short(self.keep)}")
        keep = tuple(keep)
        frame = LogFrame(self.axes, self.offset)
        object.__setattr__(self, "force_noise", _force_noise(self.force_noise))
        object.__setattr__(self, "columns", columns)
        object.__setattr__(self, "units", units)
        object.__setattr__(self, "keep", keep)
        object.__setattr__(self, "axes", frame.axes)
        object.__setattr__(self, "offset", dict(frame.offset))

    @property
    def frame(self) -> LogFrame:
        """The map of the log's frame onto the platform's (``axes`` and ``offset``)."""
        return LogFrame(self.axes, self.offset)

    @property
    def rates(self) -> dict[str, tuple[str, str, str]]:
        """The rate groups (``RATES``) the column map names: Motion attribute -> columns."""
        return {name: group for name, group in RATES.items() if group[0] in self.columns}

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str]) -> LogFormat:
        """Read a TOML file with ``[columns]``, ``[units]``, ``angles``, ``wrap``, ``keep``,
        ``axes``, ``[offset]``."""
        return cls.from_mapping(read_toml(path), str(path))

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "column map") -> LogFormat:
        allowed = ("columns", "units", "angles", "wrap", "keep", "axes", "offset",
                   "force_noise")
        for key in data:
            if key not in allowed:
                raise InputError(f"{where}: unknown key {short(key)}{suggest(key, allowed)}")
        for key in ("columns", "units", "offset"):
            if not isinstance(data.get(key, {}), dict):
                raise InputError(f"{where}: [{key}] must be a table of name = \"value\"")
        try:
            return cls(columns=data.get("columns", {}), units=data.get("units", {}),
                       angles=data.get("angles", "xyz"), wrap=data.get("wrap"),
                       keep=data.get("keep", ()), axes=data.get("axes", ("x", "y", "z")),
                       offset=data.get("offset", {}), force_noise=data.get("force_noise"))
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
                data = dict(read_toml(column_map))
            else:
                data["columns"] = _pairs(column_map, "--column-map")
        where = str(column_map) if data and column_map and str(column_map).lower().endswith(
            ".toml") else "column map"
        if units is not None:
            given = _pairs(units, "--units")
            twice = [k for k in given if k in data.get("units", {})]
            if twice:
                raise InputError(f"--units: {twice[0]!r} given twice (also in {column_map}); "
                                 "give each unit once")
            data["units"] = {**data.get("units", {}), **given}
        if angles is not None:
            data["angles"] = angles
        if keep is not None:
            data["keep"] = [k.strip() for k in keep.split(",") if k.strip()]
        fmt = cls.from_mapping(data, where)
        return fmt if angles is None else replace(fmt, angles_option=True)


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


class ColumnReader:
    """Reads a log's blocks of rows into gsfric's columns, in SI units.

    One reader per file, fed its blocks in order (it keeps the state of a wrapping time
    counter and the rows it left out). ``check`` validates the header once; ``read`` converts
    a block.

    A dropout row (every value read but the time zero, and the time not advancing, as a
    controller writes when it stops: its counter drops to 0) is left out with a
    ``DataWarning`` naming it; the other rows are read as if it were not there. A second
    orientation set (ZXZ angles or roll, pitch, yaw beside the quaternion) is read too and
    must give the same rotation to ``ORIENTATION_TOLERANCE``.

    Attributes
    ----------
    orientation : tuple of str
        The orientation columns of the converted blocks: ``QUATERNION`` (also for roll, pitch,
        yaw, converted, and for any orientation mapped by ``LogFormat.axes`` or ``offset``)
        or ``EULER``.
    forces : bool
        The log has F1..F6.
    keep : tuple of str
        Log columns carried through (``LogFormat.keep``).
    dropped : list of int
        0-based data rows of the file left out so far (dropout rows).
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
        self.dropped: list[int] = []
        self._others: list[tuple[str, ...]] = []
        self._last: int | None = None
        self._offset = 0
        self._largest = 0
        self._typical: float | None = None
        self._last_raw = -np.inf
        self._rate_checked = False
        self._warned_radians = False

    def check(self, names: list[str]) -> tuple[str, ...]:
        """Validate the header (stripped names); return ``orientation``. Warns of ignored columns."""
        path, fmt = self.path, self.format
        source = _sources(path, fmt, names)
        ignored = [n for n in names if n not in source.values() and n not in fmt.keep]

        def missing(key: str, why: str) -> InputError:
            return _missing(path, ignored, key, why)

        angles, others = _orientation(path, source, missing)
        if fmt.angles_option and angles is not RPY and RPY not in others and not any(
                fmt.offset.get(k) for k in RPY):
            raise InputError(f"--angles: {path} has no roll, pitch, yaw columns (its "
                             f"orientation is {', '.join(angles)}), and no offset rotation: "
                             "the convention applies to nothing; leave --angles out")
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
            count = f"{len(ignored)} column{'s' if len(ignored) > 1 else ''}"
            named = ", ".join(map(repr, ignored[:SHOWN_IGNORED]))
            if len(ignored) > SHOWN_IGNORED:
                named += f" and {len(ignored) - SHOWN_IGNORED} more (simulate --verbose)"
            warnings.warn(IgnoredColumnsWarning(
                f"{path}: {count} ignored (not gsfric inputs: {named}; map them with "
                "--column-map, or carry them to simulate's output with --keep-columns; in "
                "Python: the warning's names, LogFormat columns, keep)", tuple(ignored)),
                stacklevel=3)
        self.source = source
        self.forces = len(forces) == 6
        self.keep = fmt.keep
        self._angles = angles
        self._others = others
        self.orientation = QUATERNION if angles is RPY or not fmt.frame.identity else angles
        return self.orientation

    def file_row(self, index: int) -> int:
        """The 0-based data row of the file of the ``index``-th row read (0-based, dropout
        rows not counted)."""
        row = int(index)
        for dropped in self.dropped:
            if dropped <= row:
                row += 1
        return row

    def read(self, frame, first_row: int = 0) -> dict[str, np.ndarray]:
        """The block's columns as gsfric's, SI units.

        ``frame``: the block's columns by stripped name (NumPy arrays, or Series for columns
        that are not plain numbers). Keys: ``t, x, y, z``, the orientation columns, F1..F6 and
        D1..D6 where present, the mapped rate columns (``RATES``), and ``keep:NAME`` for each
        column carried through (values as in the file). Dropout rows are left out.
        ``first_row``: the 0-based data row of the frame's first row in the file.
        """
        keys = list(self.source)
        raw = numeric_columns(self.path, [frame[self.source[k]] for k in keys],
                              [self.source[k] for k in keys], first_row)
        out = {key: raw[self.source[key]] for key in keys}
        rows = np.arange(first_row, first_row + len(out["t"]))
        kept = self._dropouts(out, rows)
        if kept is not None:
            out = {key: values[kept] for key, values in out.items()}
            rows = rows[kept]
        counter = frame[self.source["t"]]
        if counter.dtype.kind in "iu":
            counts = np.asarray(counter)
            out["t"] = self._unwrap(counts if kept is None else counts[kept], rows)
        for key in keys:
            unit = self.format.units.get(key)
            if unit is not None and unit != "1":
                out[key] = out[key] * UNITS[_quantity(key)][unit]
        if not self._rate_checked and len(out["t"]) > 1:
            self._rate_checked = True
            unit = self.format.units.get("t", "s")
            try:
                check_sampling_rate(out["t"], f"time column {self.source['t']!r}", unit,
                                    UNITS["time"][unit])
            except InputError as error:
                raise InputError(f"{self.path}: {error}") from None
        self._orientations(out, rows)
        self._map_frame(out)
        for column in self.keep:
            values = np.asarray(frame[column])
            out[f"keep:{column}"] = values if kept is None else values[kept]
        return out

    def _dropouts(self, out: dict[str, np.ndarray], rows: np.ndarray) -> np.ndarray | None:
        """The rows to keep (bool, or None for all): a row whose every value but the time is
        zero and whose time does not advance (a counter dropped to 0) is a dropout, left out with a
        ``DataWarning``. (Zeros at advancing times are kept: a home pose in a controller's
        frame.)"""
        values = [v for k, v in out.items() if k != "t"]
        if not values or not len(rows):
            return None
        t = out["t"]
        previous = np.concatenate([[self._last_raw], t[:-1]])
        stopped = ~(t > previous)
        zero = np.all(np.stack(values, axis=1) == 0, axis=1) & stopped
        self._last_raw = t[~zero][-1] if (~zero).any() else self._last_raw
        if not zero.any():
            return None
        dropped = rows[zero]
        self.dropped.extend(int(r) for r in dropped)
        shown = ", ".join(str(int(r) + 1) for r in dropped[:10])
        more = f" and {len(dropped) - 10} more" if len(dropped) > 10 else ""
        word = "rows" if len(dropped) > 1 else "row"
        warnings.warn(f"{self.path}: {word} {shown}{more}: every value is 0 and the time "
                      "stops (a dropout row): left out", DataWarning, stacklevel=4)
        return ~zero

    def _orientations(self, out: dict[str, np.ndarray], rows: np.ndarray) -> None:
        """Roll, pitch, yaw converted to quaternions; the second orientation sets checked
        against the one used, then dropped."""
        if self._angles is RPY:
            angles = np.stack([out.pop(k) for k in RPY], axis=1)
            if not self._warned_radians and "roll" not in self.format.units and len(angles) \
                    and np.abs(angles).max() > 2 * np.pi:
                self._warned_radians = True
                warnings.warn(f"{self.path}: roll, pitch, yaw look like degrees (above 2*pi); "
                              "give their unit with --units roll=deg,pitch=deg,yaw=deg",
                              GsfricWarning, stacklevel=4)
            q = quaternion_from_rpy(angles, self.format.angles)
            for k, key in enumerate(QUATERNION):
                out[key] = q[:, k]
        if not self._others:
            return
        used = self._quaternion(out, self._angles if self._angles is not RPY else QUATERNION)
        for group in self._others:
            other = self._quaternion(out, group)
            for key in group:
                out.pop(key)
            with np.errstate(all="ignore"):
                dots = np.abs(np.sum(used * other, axis=1)) / (
                    np.linalg.norm(used, axis=1) * np.linalg.norm(other, axis=1))
                angle = 2.0 * np.arccos(np.clip(dots, 0.0, 1.0))
            bad = np.flatnonzero(~(angle <= ORIENTATION_TOLERANCE))
            if len(bad):
                i = int(bad[0])
                raise InputError(
                    f"{self.path}: row {int(rows[i]) + 1}: the orientation columns disagree: "
                    f"{', '.join(group)} and {', '.join(self._used_names())} give rotations "
                    f"{float(angle[i]):.3g} rad apart (tolerance {ORIENTATION_TOLERANCE:g} "
                    f"rad; {len(bad)} of {len(angle)} rows disagree); remove one set from "
                    "the file, or map the right columns with --column-map")

    def _used_names(self) -> tuple[str, ...]:
        return self._angles

    def _quaternion(self, out: dict[str, np.ndarray], group: tuple[str, ...]) -> np.ndarray:
        """The rotation of each row as a quaternion (n, 4), from one orientation set."""
        values = np.stack([out[k] for k in group], axis=1)
        if group == QUATERNION:
            return values
        if group == EULER:
            return quaternion_from_euler(*values.T)
        return quaternion_from_rpy(values, self.format.angles)

    def _map_frame(self, out: dict[str, np.ndarray]) -> None:
        """Poses and rates mapped from the log's frame onto the platform's (``LogFormat``'s
        ``axes`` and ``offset``)."""
        frame = self.format.frame
        if frame.identity:
            return
        convention = self.format.angles
        position = frame.position(np.stack([out[k] for k in TIME_POSITION[1:]], axis=1),
                                  convention)
        for k, key in enumerate(TIME_POSITION[1:]):
            out[key] = position[:, k]
        q = frame.quaternion(self._quaternion(out, EULER if self._angles is EULER
                                              else QUATERNION), convention)
        for key in EULER:
            out.pop(key, None)
        for k, key in enumerate(QUATERNION):
            out[key] = q[:, k]
        for name, group in RATES.items():
            if group[0] in out:
                mapped = frame.vector(np.stack([out[k] for k in group], axis=1), convention,
                                      axial=name in ("omega", "alpha"))
                for k, key in enumerate(group):
                    out[key] = mapped[:, k]

    def _unwrap(self, counts: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """An integer time counter made increasing across its wrap-arounds (as float), in the
        counter's unit; ``rows`` the 0-based data rows of the counts. A decrease that is not a
        wrap (``WRAP_STEPS``) is an error: a reset."""
        counts = counts.astype(np.int64) if counts.dtype.kind == "u" and counts.max(
            initial=0) < 2**63 else counts
        if len(counts) == 0:
            return counts.astype(float)
        self._largest = max(self._largest, int(counts.max()))
        modulus = self.format.wrap or next(
            (m for m in (2**16, 2**32, 2**64) if self._largest < m), 2**64)
        joined = counts if self._last is None else np.concatenate([[self._last], counts])
        steps = np.diff(joined.astype(float))
        positive = steps[steps > 0]
        if positive.size:
            self._typical = float(np.median(positive))
        wraps = steps < 0
        for i in np.flatnonzero(wraps):
            self._check_wrap(joined, i, modulus, rows)
        offsets = np.cumsum(wraps) * float(modulus)
        if self._last is not None:
            values = counts.astype(float) + self._offset + offsets
        else:
            values = counts.astype(float) + self._offset + np.concatenate([[0.0], offsets])
        shift = 0 if self._last is None else 1
        for i in np.flatnonzero(wraps):
            warnings.warn(f"{self.path}: row {int(rows[i + 1 - shift]) + 1}: time counter "
                          f"{self.source['t']!r} wraps around (modulus {modulus}); unwrapped",
                          GsfricWarning, stacklevel=5)
        self._offset = values[-1] - float(counts[-1])
        self._last = int(counts[-1])
        return values

    def _check_wrap(self, joined: np.ndarray, i: int, modulus: int, rows: np.ndarray) -> None:
        """Raise ``InputError`` unless the decrease from ``joined[i]`` to ``joined[i + 1]`` is
        a wrap around ``modulus``."""
        before, after = int(joined[i]), int(joined[i + 1])
        across = after + modulus - before
        typical = self._typical
        if typical is None:
            if before - after > modulus / 2:
                return
        elif 0 < across <= WRAP_STEPS * typical:
            return
        shift = 0 if self._last is None else 1
        row = int(rows[i + 1 - shift]) + 1
        unit = self.format.units.get("t", "s")
        factor = UNITS["time"].get(unit, 1.0)
        t_after = (after + self._offset) * factor
        t_before = (before + self._offset) * factor
        usual = f" against the usual {typical:g}" if typical is not None else ""
        raise InputError(f"{self.path}: row {row}: t = {t_after!r} is less than t = "
                         f"{t_before!r} in row {row - 1}; t must increase: the time counter "
                         f"{self.source['t']!r} drops from {before} to {after}, a reset (a "
                         f"controller reboot?), not a wrap at {modulus} (a step of {across} "
                         f"counts{usual}); split the log at row {row}")


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
    for key in RATE_KEYS:
        if key in fmt.columns:
            source[key] = fmt.columns[key]
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


def _orientation(path: Path, source: dict[str, str], missing
                 ) -> tuple[tuple[str, ...], list[tuple[str, ...]]]:
    """The orientation columns used (``QUATERNION``, ``EULER`` or ``RPY``, in this order of
    preference) and the other complete sets, read to be checked against it. Time and position
    checked first."""
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
    others = [group for group in (EULER, QUATERNION, RPY) if group is not angles and has[group]]
    return angles, others
