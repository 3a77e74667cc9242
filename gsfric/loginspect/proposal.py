"""``inspect_log``: a proposed log format and rig for a log, with what was assumed.

From the column map (``gsfric.loginspect.columns``) it goes on to the controller's frame (which
way z points), the angle convention, the rest pose (the longest still stretch), whether the
heave is zero at home and the home height, the workspace in the platform's frame, and a stroke
that contains the motion's legs. ``LogInspection.log_format_toml`` and ``rig_toml`` are the
commented files ``gsfric log inspect`` writes.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tomlkit

from gsfric._checks import as_path, short
from gsfric.errors import InputError, InputTypeError
from gsfric.io.frames import LogFrame
from gsfric.io.logs import RPY_CONVENTIONS, LogFormat
from gsfric.io.tables import read_table
from gsfric.loginspect import columns as C
from gsfric.loginspect import values as V
from gsfric.loginspect.names import VEHICLE_WORDS
from gsfric.models import platform_from, reference_platform
from gsfric.platform.description import Platform
from gsfric.platform.rig import Rig, rig_toml
from gsfric.platform.usable import home_height
from gsfric.signal.rotations import (
    quaternion_from_euler,
    quaternion_from_rpy,
    rotation_from_quaternion,
    rpy_from_rotation,
    unit_quaternions,
)

STROKE_MARGIN = 0.1
"""Share of the legs' travel over the log added below and above it for a proposed stroke: one
log is one motion, and a stroke that just holds it would flag the next one going a little
further."""

REFERENCE_REACH = 0.1
"""Half-extent, m, of the translations the reference platform (stroke 0.5-1.1 m) holds around
its home with room to turn: its reference motions stay within 0.06 m. Without the rig's sizes,
the reference is scaled by the log's half-extent over this."""

ROUND = 4
"""Significant digits of the proposed lengths (home height, stroke): a tenth of a mm on a
metre-sized rig, below any rig drawing's tolerance."""


@dataclass(frozen=True)
class Rest:
    """The longest still stretch of a log.

    Attributes
    ----------
    rows : (int, int)
        First and last data row (1-based, as in the file).
    seconds : float
        Its length, s.
    pose : ndarray, shape (6,)
        Mean x, y, z (m) and roll, pitch, yaw or the first three angles (rad) over it, in the
        log's own frame (SI units).
    """

    rows: tuple[int, int]
    seconds: float
    pose: np.ndarray


@dataclass(frozen=True)
class LogInspection:
    """What ``inspect_log`` proposes for a log.

    Attributes
    ----------
    path : Path
        The log.
    log_format : LogFormat
        The proposed log format (columns, units, angles, wrap, axes, offset).
    rig : Rig
        A rig whose home height and stroke contain the motion.
    assumptions : tuple of Assumption
        What was assumed, each with its evidence, in the order found.
    rest : Rest or None
        The longest still stretch (None when the log never rests ``REST_SECONDS``).
    extent : ndarray, shape (2, 6)
        Smallest (row 0) and largest (row 1) x, y, z (m) and roll, pitch, yaw (rad, "xyz":
        R = Rz(yaw) Ry(pitch) Rx(roll)) of the poses in the platform's frame.
    legs : (float, float)
        Shortest and longest leg over the log, m, on the rig.
    ignored : tuple of str
        The log's columns the format does not map.
    """

    path: Path
    log_format: LogFormat
    rig: Rig
    assumptions: tuple[C.Assumption, ...]
    rest: Rest | None
    extent: np.ndarray
    legs: tuple[float, float]
    ignored: tuple[str, ...]

    def lines(self) -> list[str]:
        """The assumptions, one line each."""
        return [a.line() for a in self.assumptions]

    def log_format_toml(self) -> str:
        """The log format as a commented TOML (``LogFormat.from_toml`` reads it back)."""
        return format_text(self)

    def rig_toml(self) -> str:
        """The rig as a commented rig TOML to edit (``Rig.from_toml`` reads it back)."""
        header = [f"Proposed by `gsfric log inspect` for {self.path.name}: the home height",
                  f"and the stroke contain the log's motion (legs {self.legs[0]:.4g}-"
                  + f"{self.legs[1]:.4g} m over the log).",
                  "Replace the radii, half-angles and masses by your rig's, then check the",
                  "home height and the stroke against its drawings."]
        return "".join(f"# {line}\n" for line in header) + rig_toml(self.rig)


def inspect_log(path: str | os.PathLike[str], *, platform: Platform | None = None,
                rig: Rig | None = None, time: str | None = None,
                axes: str | None = None) -> LogInspection:
    """Propose a log format and a rig for a controller's log.

    Parameters
    ----------
    path : path-like
        The log, CSV or Parquet.
    platform : Platform or path-like, optional
        The rig's platform (or its TOML file, ``gsfric.models.platform_from``): its geometry and stroke give the home height (mid-stroke) and the
        legs. Default: ``rig``'s, or the reference platform's sizes scaled to the log.
    rig : Rig, optional
        The rig's sizes (``gsfric.platform.rig``), instead of ``platform``.
    time : str, optional
        The time column (default: found by name and values).
    axes : str, optional
        The controller's frame as the log format's ``axes`` (e.g. "x,-y,-z"), instead of the
        one the names suggest.

    Raises
    ------
    InputError
        One line naming the file and the column or row: an empty file, no numeric column, no
        time-like column, no position or orientation columns; both ``platform`` and ``rig``.
    InputTypeError
        ``path`` not a path, ``rig`` not a ``Rig``.
    """
    path = as_path(path, "path")
    if platform is not None and rig is not None:
        raise InputError("give platform or rig, not both")
    platform = platform_from(platform) if platform is not None else None
    if rig is not None and not isinstance(rig, Rig):
        raise InputTypeError(f"rig: expected a gsfric.platform.rig.Rig (Rig.from_toml), got "
                             f"{short(rig)}")
    table = read_table(path)
    data = C.numeric_frame(path, table)
    roles = C.roles_of(data)
    cmap = C.ColumnMap()
    clock = C.time_column(path, data, roles, time, cmap)
    stroke = platform.geometry.stroke if platform is not None else \
        rig.stroke if rig is not None else None
    longest = None if stroke is None else stroke[1]
    position, kind, angles, convention, velocity, omega = _poses(path, data, roles, clock.t,
                                                                 cmap, V.mm_reach(longest))
    C.force_columns(data, roles, cmap)
    frame_axes = _frame(roles, cmap, axes)
    rest = _rest(clock.t, position, angles, kind, V.still_samples(velocity, omega), cmap)
    sizes, model, home = _model(platform, rig, position, cmap)
    offset = _home(position, frame_axes, rest, home, cmap)
    fmt = LogFormat(columns=cmap.columns, units=cmap.units, angles=convention or "xyz",
                    wrap=clock.wrap, axes=frame_axes, offset=offset)
    p, rotation = _platform_poses(fmt, position, angles, kind)
    extent = _extent(p, rotation, cmap)
    legs = model.leg_lengths(p, rotation)
    span = (float(legs.min()), float(legs.max()))
    final = _stroke(model, sizes, span, offset.get("z"), cmap)
    ignored = tuple(str(c) for c in table.columns if str(c) not in cmap.used)
    if ignored:
        cmap.assume("ignored", ", ".join(map(repr, ignored)),
                    "not a time, pose, rate or force by name; left out of the log format")
    return LogInspection(path, fmt, final, tuple(cmap.assumptions), rest, extent, span, ignored)


def _poses(path, data, roles, t, cmap: C.ColumnMap, mm_reach: float):
    """Position (N, 3), m, and orientation angles (N, 3 or 4) in SI in the log's frame; the
    orientation kind; the roll/pitch/yaw convention (None for others); the velocity and the
    angular velocity (N, 3 each, SI, the log's frame). Also maps the log's own rates."""
    columns = C.group(data, roles, "position")
    if columns is None:
        missing = [a for a in "xyz" if not any(roles[c].kind == "position" and roles[c].axis == a
                                               for c in data)]
        raise InputError(f"{path}: no position column for {', '.join(missing)} (names like x, "
                         "surge, pos_x; or map the columns by hand: docs/howto/read-a-log.md)")
    position, _ = C.pose_units(path, data, roles, columns, "position", cmap, mm_reach)
    for kind in ("angle", "quaternion", "euler"):
        group = C.group(data, roles, kind)
        if group is not None:
            break
    else:
        raise InputError(f"{path}: no orientation columns (roll, pitch, yaw; alpha, beta, "
                         "gamma; or qw, qx, qy, qz by name)")
    angles, _ = C.pose_units(path, data, roles, group, kind, cmap)
    convention = None
    if kind == "angle":
        convention, (omega, alpha) = _convention(data, roles, t, angles, cmap)
    else:
        omega, alpha = V.turning(t, _quaternions(angles, kind, "xyz"))
    _, velocity, acceleration = V.derivatives(t, position)
    C.rate_columns(data, roles, {"velocity": velocity, "acceleration": acceleration,
                                 "omega": omega, "alpha": alpha}, cmap)
    return position, kind, angles, convention, velocity, omega


def _convention(data, roles, t, angles, cmap: C.ColumnMap):
    """The roll/pitch/yaw convention, and the log frame's angular velocity and acceleration
    under it: the one whose angular velocity matches the log's own angular rates best, if it
    has them, else xyz."""
    rates = {r.axis: c for c, r in roles.items() if r.kind == "omega"}
    gap = math.degrees(V.convention_gap(angles))
    if set(rates) != {"x", "y", "z"}:
        cmap.assume("angles", f"xyz ({RPY_CONVENTIONS['xyz']})",
                    "the usual convention of roll, pitch, yaw; no angular rate columns to "
                    f"tell it from XYZ, which differs by at most {gap:.3g} deg on this log")
        return "xyz", V.turning(t, quaternion_from_rpy(angles, "xyz"))
    scores = {}
    for convention in RPY_CONVENTIONS:
        rates_of = V.turning(t, quaternion_from_rpy(angles, convention))
        scores[convention] = (min(V.match_rate(data[rates[a]].astype(float), rates_of[0][:, k],
                                               "angular speed").correlation
                                  for k, a in enumerate("xyz")), rates_of)
    best = max(scores, key=lambda c: scores[c][0])
    other = next(c for c in scores if c != best)
    cmap.assume("angles", f"{best} ({RPY_CONVENTIONS[best]})",
                f"the log's angular rates match its angular velocity with correlation "
                f"{scores[best][0]:.4f} against {scores[other][0]:.4f} for {other}; the two "
                f"differ by at most {gap:.3g} deg on this log")
    return best, scores[best][1]


def _frame(roles, cmap: C.ColumnMap, given: str | None) -> tuple[str, str, str]:
    """The log format's ``axes``: given, or z down when the names say so."""
    if given is not None:
        frame = LogFrame(given)
        cmap.assume("frame", f"axes {','.join(frame.axes)}", "given with --axes")
        return frame.axes
    position = [r for r in roles.values() if r.kind in ("position", "velocity", "acceleration")]
    down = [r for r in position if r.says_down]
    vehicle = [r for r in position if VEHICLE_WORDS & set(r.words)]
    if down or vehicle:
        why = ("a name says z points down" if down else
               "surge, sway, heave are the vehicle convention's names (SAE J670, SNAME): x "
               "forward, y right, z down")
        cmap.assume("frame", "axes x,-y,-z: the log's z points down, its y to the right",
                     f"{why}; the platform's frame is z up; give --axes x,y,z if the heave "
                     "is up")
        return ("x", "-y", "-z")
    cmap.assume("frame", "axes x,y,z: the log's frame is the platform's, z up",
                "x, y, z names without a down; give --axes x,-y,-z for a z-down controller")
    return ("x", "y", "z")


def _rest(t, position, angles, kind, still, cmap: C.ColumnMap) -> Rest | None:
    """The longest stretch of ``still`` samples (N,), at least ``REST_SECONDS`` long."""
    turn = angles if kind != "quaternion" else angles[:, 1:]
    start, stop = V.longest_run(still)
    seconds = float(t[stop - 1] - t[start]) if stop > start else 0.0
    if seconds < V.REST_SECONDS:
        cmap.assume("rest", "none", f"no still stretch of {V.REST_SECONDS:g} s")
        return None
    pose = np.concatenate([position[start:stop].mean(axis=0), turn[start:stop].mean(axis=0)])
    rest = Rest((start + 1, stop), seconds, pose)
    shown = ", ".join(f"{v * 1e3:.4g} mm" for v in pose[:3])
    turned = ", ".join(f"{math.degrees(v):.3g} deg" for v in pose[3:])
    cmap.assume("rest", f"rows {start + 1}-{stop} ({seconds:.3g} s): position {shown}, "
                f"angles {turned}",
                f"the longest still stretch (speeds below {100 * V.REST_SHARE:g} % of the "
                "log's)")
    return rest


def _model(platform, rig, position, cmap: C.ColumnMap
           ) -> tuple[Rig | None, Platform, float | None]:
    """The rig's sizes, platform and home height (m): given, or the reference platform's
    scaled to the log."""
    if rig is not None:
        cmap.assume("rig", "the rig given (--rig)", "its sizes give the legs; its "
                    "home_height, or else mid-stroke, the home height")
        return rig, rig.platform(), rig.home
    if platform is not None:
        try:
            sizes = Rig.from_platform(platform) if platform.geometry.stroke is not None else None
        except InputError as error:
            raise InputError(f"--platform: its joints are not laid out as a rig's (three pairs "
                             f"on two circles), which the proposal is made of: {error}") from None
        cmap.assume("rig", "the platform given (--platform)", "its joints give the legs, "
                    "its mid-stroke the home height")
        return sizes, platform, home_height(platform)
    reach = float(np.max(np.ptp(position, axis=0)) / 2)
    scale = max(1.0, reach / REFERENCE_REACH)
    base = Rig.from_platform(reference_platform())
    sizes = dataclasses.replace(
        base, base_radius=base.base_radius * scale, platform_radius=base.platform_radius * scale,
        stroke=(base.stroke[0] * scale, base.stroke[1] * scale),
        platform_mass=base.platform_mass * scale**3, lower_mass=base.lower_mass * scale**3,
        upper_mass=base.upper_mass * scale**3, payload_mass=base.payload_mass * scale**3)
    what = "the reference platform's sizes" + (f" scaled by {scale:.3g}" if scale > 1 else "")
    cmap.assume("rig", what,
                f"no --platform or --rig; the log reaches {reach:.3g} m from its middle, the "
                f"reference holds {REFERENCE_REACH:g} m; replace the sizes by your rig's "
                "(rig.toml) and run again with --rig")
    return sizes, sizes.platform(), sizes.home


def _home(position, axes, rest, home, cmap: C.ColumnMap) -> dict[str, float]:
    """The ``[offset]``: a home height for a heave that is zero at home, else none."""
    sign = -1.0 if axes[2].startswith("-") else 1.0
    column = "xyz".index(axes[2].lstrip("-"))
    heave = sign * position[:, column]
    if heave.min() > 0:
        cmap.assume("home", "no z offset: the log's heights are above the base joints",
                    f"heave from {heave.min():.4g} to {heave.max():.4g} m, above 0 at every row")
        return {}
    if home is None:
        raise InputError("the log's heave is zero at home, and the platform has no stroke to "
                         "tell its home height: give --rig, or a platform with a stroke")
    home = _rounded(home)
    at_rest = (f"the rest's heave is {sign * rest.pose[column] * 1e3:.3g} mm"
               if rest is not None else "no rest to check it against")
    cmap.assume("home", f"the heave is zero at home: offset z = {home:.6g} m, the rig's "
                "home height (mid-stroke unless the rig gives it)",
                f"heave from {heave.min():.4g} to {heave.max():.4g} m goes to or below 0, so it "
                f"is measured from home; {at_rest}")
    return {"z": home}


def _quaternions(angles, kind: str, convention: str) -> np.ndarray:
    """Unit quaternions (N, 4) of the orientation columns (N, 3 or 4) of ``kind``."""
    if kind == "angle":
        return quaternion_from_rpy(angles, convention)
    if kind == "euler":
        return quaternion_from_euler(*angles.T)
    return unit_quaternions(angles)[0]


def _platform_poses(fmt: LogFormat, position, angles, kind):
    """Positions (N, 3), m, and rotations (N, 3, 3) in the platform's frame."""
    q = _quaternions(angles, kind, fmt.angles)
    frame = fmt.frame
    return (frame.position(position, fmt.angles),
            rotation_from_quaternion(frame.quaternion(q, fmt.angles)))


def _extent(p, rotation, cmap: C.ColumnMap) -> np.ndarray:
    """Smallest and largest position (m) and roll, pitch, yaw (rad, xyz) in the platform's
    frame, (2, 6)."""
    poses = np.concatenate([p, rpy_from_rotation(rotation)], axis=1)
    extent = np.stack([poses.min(axis=0), poses.max(axis=0)])
    shown = ", ".join(f"{n} {extent[0, k]:.4g}..{extent[1, k]:.4g} m"
                      for k, n in enumerate("xyz"))
    degrees = np.degrees(extent[:, 3:])
    turned = ", ".join(f"{n} {degrees[0, k]:.3g}..{degrees[1, k]:.3g} deg"
                       for k, n in enumerate(("roll", "pitch", "yaw")))
    cmap.assume("workspace", f"{shown}; {turned}",
                "the poses in the platform's frame (z up, base joints at z = 0)")
    return extent


def _stroke(model: Platform, sizes: Rig | None, span, home, cmap: C.ColumnMap) -> Rig:
    """The rig with a stroke that contains the legs' ``span`` (and the home pose's legs)."""
    stroke = model.geometry.stroke
    if sizes is None:
        sizes = Rig.from_platform(dataclasses.replace(
            model, geometry=dataclasses.replace(model.geometry, stroke=(span[0] * 0.9,
                                                                        span[1] * 1.1))))
    lo, hi = span
    if home is not None:
        level = sizes.home_legs(home)
        lo, hi = min(lo, float(level.min())), max(hi, float(level.max()))
    if stroke is not None and stroke[0] <= lo and hi <= stroke[1]:
        cmap.assume("stroke", f"{stroke[0]:.4g}-{stroke[1]:.4g} m, the rig's",
                    f"it contains the legs over the log, {span[0]:.4g}-{span[1]:.4g} m")
        proposed = tuple(stroke)
    else:
        margin = STROKE_MARGIN * (hi - lo)
        proposed = (_rounded(lo - margin), _rounded(hi + margin))
        was = f"the rig's {stroke[0]:.4g}-{stroke[1]:.4g} m does not" if stroke else "none given"
        cmap.assume("stroke", f"{proposed[0]:.4g}-{proposed[1]:.4g} m, proposed",
                    f"the legs over the log are {span[0]:.4g}-{span[1]:.4g} m ({was}); "
                    f"{100 * STROKE_MARGIN:g} % of their travel added either side")
    return dataclasses.replace(sizes, stroke=proposed,
                               home_height=None if home is None else _rounded(home))


def _rounded(value: float) -> float:
    """``value`` to ``ROUND`` significant digits."""
    return float(f"{value:.{ROUND}g}")


def format_text(inspection: LogInspection) -> str:
    """The proposed log format as TOML, each key with what it rests on in a comment."""
    fmt = inspection.log_format
    topics = {a.topic: a for a in inspection.assumptions}
    doc = tomlkit.document()
    name = inspection.path.name
    for line in (f"How to read {name}: proposed by `gsfric log inspect`; check every line.",
                 f"Use: gsfric simulate --trajectory {name} --column-map log_format.toml",
                 "     --platform platform.toml --out forces.csv",
                 "See docs/howto/read-a-log.md for the keys."):
        doc.add(tomlkit.comment(line))
    doc.add(tomlkit.nl())
    _item(doc, "angles", fmt.angles, topics.get("angles"))
    _item(doc, "axes", list(fmt.axes), topics.get("frame"))
    if fmt.wrap is not None:
        _item(doc, "wrap", int(fmt.wrap), topics.get("wrap"))
    if fmt.offset:
        table = tomlkit.table()
        _item(table, "z", float(fmt.offset["z"]), None, "m, the home height: " +
              "the log's heave is zero at home")
        doc.add("offset", table)
    columns = tomlkit.table()
    for key, column in fmt.columns.items():
        _item(columns, key, column, None, _column_note(key, topics))
    doc.add("columns", columns)
    if fmt.units:
        units = tomlkit.table()
        for key, unit in fmt.units.items():
            units.add(key, unit)
        doc.add("units", units)
    if inspection.ignored:
        doc.add(tomlkit.nl())
        doc.add(tomlkit.comment("not mapped: " + ", ".join(inspection.ignored)))
    return tomlkit.dumps(doc)


def _column_note(key: str, topics) -> str | None:
    topic = {"t": "time", "x": "position", "vx": "velocity", "ax": "acceleration",
             "roll": "orientation", "alpha": "orientation", "qw": "orientation",
             "omega_x": "omega", "alpha_x": "alpha", "F1": "forces"}.get(key)
    found = topics.get(topic)
    return None if found is None else found.evidence


def _item(container, key, value, assumption: C.Assumption | None, note: str | None = None):
    item = tomlkit.item(value)
    text = note if note is not None else (assumption.evidence if assumption else None)
    if text:
        item.comment(text)
    container.add(key, item)
