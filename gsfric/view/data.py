"""The data a 3-D view page embeds: the frames quantised and base64-encoded in a JSON object.

Each array is stored as little-endian bytes in base64, with its dtype and shape:

* ``t`` as float32 seconds after ``t0`` (``t0`` itself a JSON number): error at most
  ``2**-24`` of the record's duration;
* ``step`` as int32, ``flag`` as uint8 (the flag bits, ``gsfric.evaluation.flags``), exact;
* ``quaternion`` as int16 ``round(q * 32767)``: error at most ``0.5 / 32767`` per component;
* every other array (``position`` m, ``F``, ``R_E``, ``R_C``, ``Ffr`` N, ``MfrE``, ``MfrC``
  N m, and the curves of the plots, ``curve0``, ``curve1``, ..., in their plot's unit) as
  int16 ``round(x / scale)`` with ``scale = max|x| / 32767`` over the array (its ``scale``
  in the JSON; 1 for an array of zeros): error at most ``scale / 2``, about
  1.5e-5 of the array's largest magnitude. A NaN value (a non-finite step) is ``-32768``.

The plots under the 3-D view are listed in ``plots`` (``Plot``: a title, a unit and curves,
each a quantity per leg drawn as six lines of one dash); by default those of ``F`` and
``Ffr`` (``DEFAULT_PLOTS``). ``captions`` (optional) names each frame: a page of separate
poses (a sweep's worst cases) rather than a motion; ``focus`` (optional) is the leg whose
values each frame shows at once.

``decode`` reads the arrays back (the tests compare them with the Result); the page's script
(``viewer.js``) does the same with typed arrays.
"""

from __future__ import annotations

import base64
import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from gsfric.view.frames import Frames, frame_rate

FORMAT = 2
"""Version of the embedded data's layout."""

INT16_MAX = 32767
NAN_CODE = -32768
"""The int16 code of a NaN value."""

_SCALED = ("position", "F", "R_E", "R_C", "MfrE", "MfrC", "Ffr")
_PER_LEG = ("F", "Ffr", "MfrE", "MfrC", "F_measured")
"""The frames' arrays (M, 6) a plot's curve may name."""
_UNITS = {"t": "s", "position": "m", "quaternion": "", "F": "N", "R_E": "N", "R_C": "N",
          "MfrE": "N m", "MfrC": "N m", "Ffr": "N", "step": "", "flag": ""}


DASHES = ("solid", "dashed", "dotted")
"""The line styles of a plot's curves (each curve's six legs share one)."""


@dataclass(frozen=True)
class Curve:
    """One quantity per leg in a plot under the 3-D view.

    Attributes
    ----------
    label : str
        Its name in the plot's key, e.g. ``"measured"``.
    values : ndarray, shape (M, 6), or str
        Its value for each frame and leg, in the plot's unit; NaN where it has none (not
        drawn). Or the name of one of the frames' own arrays of that shape (``"F"``,
        ``"Ffr"``, ``"MfrE"``, ``"MfrC"``, ``"F_measured"``): drawn from the page's copy,
        not stored twice.
    dash : str
        One of ``DASHES``.
    minus : str, optional
        The name of another of the frames' arrays, subtracted from ``values`` (a name too) by
        the page: a difference drawn without being stored.
    """

    label: str
    values: np.ndarray | str
    dash: str = "solid"
    minus: str | None = None

    def __post_init__(self) -> None:
        if self.dash not in DASHES:
            raise ValueError(f"dash: one of {', '.join(DASHES)}, got {self.dash!r}")
        names = [self.values] if isinstance(self.values, str) else []
        if self.minus is not None:
            if not names:
                raise ValueError(f"{self.label}: minus needs values that name an array too")
            names.append(self.minus)
        if names:
            if not set(names) <= set(_PER_LEG):
                raise ValueError(f"{self.label}: {', '.join(names)} must each name one of "
                                 f"{', '.join(_PER_LEG)}")
        elif np.ndim(self.values) != 2 or np.shape(self.values)[1] != 6:
            raise ValueError(f"{self.label}: values must be (frames, 6), got "
                             f"{np.shape(self.values)}")


@dataclass(frozen=True)
class Plot:
    """A plot under the 3-D view: curves over time with a cursor at the current frame.

    Attributes
    ----------
    title : str
        Shown above it, with the unit, e.g. ``"actuator force F (+ push, - pull)"``.
    unit : str
        Of every curve, e.g. ``"N"``.
    curves : tuple of Curve
        Drawn in the leg colours, each curve in its dash.
    """

    title: str
    unit: str
    curves: tuple[Curve, ...]


DEFAULT_PLOTS = (Plot("actuator force F (+ push, \u2212 pull)", "N", (Curve("F", "F"),)),
                 Plot("prismatic friction Ffr", "N", (Curve("Ffr", "Ffr"),)))
"""The plots of an evaluation's view: ``F`` and the prismatic friction ``Ffr`` per leg."""


def _entry(values: np.ndarray, dtype: str, scale: float | None = None) -> dict:
    raw = np.ascontiguousarray(values, dtype=np.dtype(dtype).newbyteorder("<"))
    entry = {"dtype": dtype, "shape": list(values.shape),
             "data": base64.b64encode(raw.tobytes()).decode("ascii")}
    if scale is not None:
        entry["scale"] = scale
    return entry


def quantise(values: np.ndarray, scale: float | None = None) -> dict:
    """``values`` (any shape) as an int16 entry: ``round(x / scale)``, NaN as ``NAN_CODE``;
    ``scale`` defaults to ``max|x| / 32767`` over the finite values (1 if all are zero)."""
    values = np.asarray(values, float)
    finite = np.isfinite(values)
    if scale is None:
        peak = float(np.abs(values[finite]).max()) if finite.any() else 0.0
        scale = peak / INT16_MAX if peak > 0 else 1.0
    codes = np.full(values.shape, NAN_CODE, dtype=np.int16)
    codes[finite] = np.clip(np.rint(values[finite] / scale), -INT16_MAX, INT16_MAX)
    return _entry(codes, "int16", float(scale))


def decode_entry(entry: Mapping) -> np.ndarray:
    """The array of one entry (float64 for a scaled int16 entry, NaN where ``NAN_CODE``)."""
    dtype = np.dtype(entry["dtype"]).newbyteorder("<")
    raw = np.frombuffer(base64.b64decode(entry["data"]), dtype=dtype).reshape(entry["shape"])
    if "scale" not in entry:
        return raw.astype(dtype.newbyteorder("="))
    values = raw.astype(float) * entry["scale"]
    values[raw == NAN_CODE] = np.nan
    return values


def encode(frames: Frames, platform, *, title: str = "",
           flag_names: Mapping[int, str] | None = None, steps: int | None = None,
           plots: Sequence[Plot] | None = None, captions: Sequence[str] | None = None,
           focus: Sequence[int] | None = None) -> dict:
    """The JSON-ready object a page embeds (see the module for the arrays).

    Parameters
    ----------
    frames : Frames
        M frames.
    platform : Platform
        What is drawn: ``geometry.base_joints`` (C_i, base frame, m), ``geometry.
        platform_joints`` (E_i, platform frame, m), ``platform.payload_mass`` (kg) and
        ``platform.payload_com`` (platform frame, m).
    title : str
        Shown at the page's top.
    flag_names : mapping of int to str, optional
        Each flag bit's meaning (``gsfric.evaluation.flags.FLAG_NAMES``).
    steps : int, optional
        Steps of the whole record (default: up to the last frame's).
    plots : sequence of Plot, optional
        The plots under the 3-D view (default: ``DEFAULT_PLOTS``), curves (M, 6).
    captions : sequence of str, optional
        M names, one per frame, shown instead of its time.
    focus : sequence of int, optional
        M legs (0-5), one per frame: the leg whose values the frame shows (as a click on it
        would).
    """
    plots = DEFAULT_PLOTS if plots is None else tuple(plots)
    if captions is not None and len(captions) != len(frames):
        raise ValueError(f"captions: {len(captions)} for {len(frames)} frames")
    if focus is not None and (len(focus) != len(frames) or not all(0 <= k < 6 for k in focus)):
        raise ValueError(f"focus: one leg 0-5 for each of the {len(frames)} frames")
    base_joints = np.asarray(platform.geometry.base_joints, float)
    platform_joints = np.asarray(platform.geometry.platform_joints, float)
    t0 = float(frames.t[0])
    arrays = {"t": _entry(frames.t - t0, "float32"), "step": _entry(frames.step, "int32"),
              "flag": _entry(np.clip(frames.flag, 0, 255), "uint8"),
              "quaternion": quantise(frames.quaternion, 1.0 / INT16_MAX)}
    for name in _SCALED:
        arrays[name] = quantise(getattr(frames, name))
    listed = _listed(plots, frames, arrays)
    body = platform.platform
    return {"format": FORMAT, "title": title, "t0": t0, "frames": len(frames),
            "steps": int(steps if steps is not None else frames.step[-1] + 1),
            "fps": frame_rate(frames),
            "base_joints": np.asarray(base_joints, float).tolist(),
            "platform_joints": np.asarray(platform_joints, float).tolist(),
            "legs": leg_parts(frames, base_joints, platform_joints),
            "payload": {"mass": float(body.payload_mass),
                        "com": np.asarray(body.payload_com, float).tolist()},
            "flag_names": {str(k): v for k, v in (flag_names or {}).items()},
            "plots": listed, "captions": list(captions) if captions is not None else None,
            "focus": [int(k) for k in focus] if focus is not None else None,
            "units": _UNITS, "arrays": arrays}


def _listed(plots: Sequence[Plot], frames: Frames, arrays: dict) -> list[dict]:
    """The JSON entries of ``plots``; the values of their curves are added to ``arrays`` as
    ``curve0``, ``curve1``, ... (a curve naming a frames' array reads that one, added once)."""
    listed = [{"title": plot.title, "unit": plot.unit, "curves": []} for plot in plots]
    for entry, plot in zip(listed, plots):
        for curve in plot.curves:
            named = isinstance(curve.values, str)
            name = curve.values if named else f"curve{sum(len(e['curves']) for e in listed)}"
            if not named and len(curve.values) != len(frames):
                raise ValueError(f"{plot.title}: {curve.label} has {len(curve.values)} "
                                 f"rows for {len(frames)} frames")
            for key, values in ((name, curve.values), (curve.minus, curve.minus)):
                if key is not None and key not in arrays:
                    arrays[key] = quantise(getattr(frames, key) if isinstance(values, str)
                                           else values)
            entry["curves"].append({"label": curve.label, "array": name, "dash": curve.dash,
                                    "minus": curve.minus})
    return listed


def leg_lengths(frames: Frames, base_joints, platform_joints) -> np.ndarray:
    """|E_i - C_i| of each frame, (M, 6) m (E_i = position + R(quaternion) e_i)."""
    q = frames.quaternion / np.linalg.norm(frames.quaternion, axis=1, keepdims=True)
    w, v = q[:, :1, None], q[:, None, 1:]
    e = np.asarray(platform_joints, float)[None]
    # rotate e by q: e + 2 w (v x e) + 2 v x (v x e)
    c1 = np.cross(v, e)
    rotated = e + 2 * w * c1 + 2 * np.cross(v, c1)
    top = frames.position[:, None, :] + rotated
    return np.linalg.norm(top - np.asarray(base_joints, float)[None], axis=2)


def leg_parts(frames: Frames, base_joints, platform_joints) -> dict:
    """How the legs are drawn: a cylinder from C_i and a rod from E_i, each of a fixed length
    (m) that keeps them overlapping over the record's leg lengths, and their radii (m)."""
    d = leg_lengths(frames, base_joints, platform_joints)
    d = d[np.isfinite(d)]
    shortest, longest = (float(d.min()), float(d.max())) if d.size else (1.0, 1.0)
    part = min(max(0.55 * longest, 0.5 * shortest), 0.92 * shortest)
    size = float(np.abs(np.asarray(base_joints, float)[:, :2]).max())
    return {"cylinder": part, "rod": part, "radius": 0.035 * size,
            "shortest": shortest, "longest": longest}


def embedded(html: str) -> dict:
    """The data object of a page written by ``gsfric.view`` (``json`` of its
    ``<script id="gsfric-data">`` element)."""
    found = re.search(r'<script type="application/json" id="gsfric-data">(.*?)</script>',
                      html, flags=re.S)
    if found is None:
        raise ValueError("not a gsfric view page: no gsfric-data element")
    return json.loads(found.group(1))


def decode(data: Mapping) -> dict[str, np.ndarray]:
    """Every array of the embedded data (``encode``), decoded; ``t`` in s of the record."""
    arrays = {name: decode_entry(entry) for name, entry in data["arrays"].items()}
    arrays["t"] = arrays["t"].astype(float) + data["t0"]
    return arrays
