"""The frames of a 3-D view: the steps of an evaluation kept for playback, with what is drawn.

A view shows the evaluated record as an animation at up to ``fps`` frames per second of motion
time (``DEFAULT_FPS``): the frames are the first steps at or after the times
``t_0 + k / fps``, at most ``MAX_FRAMES`` of them (fewer per second for a long record), always
with the first and the last step. A frame is a step of the record, its values exact; the steps
between two frames are not shown, but their flags are: each frame carries the bitwise OR of the
flags of the steps since the previous frame, up to and including its own.

``FrameCollector`` takes the record chunk by chunk (a streamed file, ``gsfric view``) or whole
(``Result.to_html``) and keeps only the frames' values, so that its memory is bounded by the
number of frames however long the record is.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from gsfric.signal.rotations import quaternion_from_rotation

DEFAULT_FPS = 60.0
"""Frames per second of motion time: what the eye needs at normal speed."""

MAX_FRAMES = 10_000
"""The most frames a view keeps (a long record is shown at fewer frames per second); it bounds
the page's size (about 2.7 MB at most, 143 bytes a frame before base64; 2.9 MB with measured
forces, 12 bytes a frame more)."""

OUTPUTS = ("F", "R_E", "R_C", "MfrE", "MfrC", "Ffr")
"""The evaluation outputs a view reads (``Result`` names)."""

MEASURED = "F_measured"
"""The key of the measured forces (n, 6), N, in the arrays of ``FrameCollector.add``
(optional: a measured-data file's F1..F6)."""


@dataclass(frozen=True)
class Frames:
    """The values of the M steps a view shows, in the base frame and SI units.

    Attributes
    ----------
    step : ndarray of int64, shape (M,)
        Index of each frame's step in the evaluated record (0-based), increasing.
    t : ndarray, shape (M,)
        Time, s.
    position : ndarray, shape (M, 3)
        Platform origin in the base frame, m.
    quaternion : ndarray, shape (M, 4)
        Platform orientation (qw, qx, qy, qz): rotates platform-frame vectors into the base
        frame; unit length.
    F : ndarray, shape (M, 6)
        Actuator force of each leg, N; positive pushes the platform away (the leg pushes).
    R_E, R_C : ndarray, shape (M, 6, 3)
        Joint reactions at the spherical joints E_i and the universal joints C_i, base
        frame, N (``gsfric columns`` gives their signs).
    MfrE, MfrC : ndarray, shape (M, 6)
        Magnitude of the friction moment in each spherical (E_i) and universal (C_i) joint,
        N m.
    Ffr : ndarray, shape (M, 6)
        Friction force of each prismatic joint along its leg, N (signed as ``Result.Ffr``).
    F_measured : ndarray, shape (M, 6)
        The measured actuator force of each leg (a measured-data file's F1..F6), N; NaN
        where none was given.
    flag : ndarray of int64, shape (M,)
        Bitwise OR of the flags of the steps after the previous frame up to this one.
    """

    step: np.ndarray
    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    F: np.ndarray
    R_E: np.ndarray
    R_C: np.ndarray
    MfrE: np.ndarray
    MfrC: np.ndarray
    Ffr: np.ndarray
    F_measured: np.ndarray
    flag: np.ndarray

    def __len__(self) -> int:
        return len(self.t)

    def take(self, index: np.ndarray) -> Frames:
        """The frames ``index`` (an integer array), each array's rows."""
        return Frames(**{f.name: getattr(self, f.name)[index] for f in fields(self)})

    @classmethod
    def concatenate(cls, parts: list[Frames]) -> Frames:
        """The frames of ``parts`` one after the other."""
        return cls(**{f.name: np.concatenate([getattr(p, f.name) for p in parts])
                      for f in fields(cls)})


def or_since_previous(flag: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """The bitwise OR of ``flag`` (n,) over each chosen index's run: the steps after the
    previous chosen index (from 0 for the first) up to and including it; ``chosen`` (m,)
    increasing, m >= 1. Returns (m,) int64."""
    starts = np.concatenate([[0], chosen[:-1] + 1])
    return np.bitwise_or.reduceat(flag[:chosen[-1] + 1].astype(np.int64), starts)


def _values(start: int, t, position, rotation, arrays: Mapping[str, np.ndarray],
            rows: np.ndarray, flag: np.ndarray) -> Frames:
    """The Frames of the local steps ``rows`` of one chunk whose first step is ``start``;
    ``arrays`` hold the outputs (N, 6), (N, 6, 3) or flat (N, 18)."""
    n = len(rows)

    def legs(name: str, vector: bool) -> np.ndarray:
        values = np.asarray(arrays[name])[rows]
        return values.reshape(n, 6, 3) if vector else values.reshape(n, 6)

    measured = legs(MEASURED, False) if MEASURED in arrays else np.full((n, 6), np.nan)
    return Frames(step=rows.astype(np.int64) + start, t=np.asarray(t, float)[rows],
                  position=np.asarray(position, float)[rows],
                  quaternion=quaternion_from_rotation(np.asarray(rotation, float)[rows]),
                  F=legs("F", False), R_E=legs("R_E", True), R_C=legs("R_C", True),
                  MfrE=np.linalg.norm(legs("MfrE", True), axis=2),
                  MfrC=np.linalg.norm(legs("MfrC", True), axis=2),
                  Ffr=legs("Ffr", False), F_measured=measured, flag=np.asarray(flag, np.int64))


class FrameCollector:
    """Chooses and keeps the frames of a record given chunk by chunk (see the module).

    Parameters
    ----------
    fps : float
        Frames per second of motion time (> 0).
    max_frames : int
        The most frames kept (>= 2); a record that would give more is shown at a lower rate.

    Examples
    --------
    >>> import numpy as np, gsfric
    >>> from gsfric.view.frames import FrameCollector
    >>> motion = gsfric.models.sinusoidal(np.linspace(0, 2, 1001))
    >>> result = gsfric.evaluate(gsfric.reference_platform(), motion)
    >>> frames = FrameCollector(fps=30).add_result(result).finish()
    >>> len(frames), float(frames.t[-1])
    (61, 2.0)
    """

    def __init__(self, fps: float = DEFAULT_FPS, max_frames: int = MAX_FRAMES) -> None:
        if not np.isfinite(fps) or fps <= 0:
            raise ValueError(f"fps: must be a positive number, got {fps!r}")
        self.fps, self.max_frames = float(fps), max(2, int(max_frames))
        self.t0: float | None = None
        self.next_k = 0                  # the next grid time t0 + k / fps to find a frame for
        self.parts: list[Frames] = []
        self.last: Frames | None = None  # the last step seen, the record's end at finish()
        self.pending = 0                 # OR of the flags after the last frame kept

    def add(self, start: int, t: np.ndarray, position: np.ndarray, rotation: np.ndarray,
            arrays: Mapping[str, np.ndarray], flag: np.ndarray) -> FrameCollector:
        """One chunk of the record: n steps from global index ``start``; ``t`` (n,) s,
        ``position`` (n, 3) m, ``rotation`` (n, 3, 3) platform to base, the outputs
        ``OUTPUTS`` of ``arrays`` as a Result holds them (and optionally ``MEASURED``),
        ``flag`` (n,). Returns self."""
        t = np.asarray(t, float)
        flag = np.asarray(flag, np.int64)
        if not len(t):
            return self
        if self.t0 is None:
            self.t0 = float(t[0])
        last_k = int(np.floor((t[-1] - self.t0) * self.fps + 1e-9))
        grid = self.t0 + np.arange(self.next_k, last_k + 1) / self.fps
        rows = np.unique(np.minimum(np.searchsorted(t, grid - 1e-12), len(t) - 1))
        self.next_k = max(self.next_k, last_k + 1)
        if len(rows):
            ors = or_since_previous(flag, rows)
            ors[0] |= self.pending
            self.parts.append(_values(start, t, position, rotation, arrays, rows, ors))
            self.pending = int(np.bitwise_or.reduce(flag[rows[-1] + 1:], initial=0))
        else:
            self.pending |= int(np.bitwise_or.reduce(flag, initial=0))
        end = np.array([len(t) - 1])
        self.last = _values(start, t, position, rotation, arrays, end, np.array([self.pending]))
        return self

    def add_result(self, result, start: int = 0,
                   measured: np.ndarray | None = None) -> FrameCollector:
        """A whole ``Result`` of ``Evaluator.evaluate`` (its motion from ``result.source``) as
        one chunk from step ``start``, with the measured forces of its steps (n, 6), N, if
        any. Returns self."""
        motion = result.source[1]
        arrays = {name: result.arrays[name] for name in OUTPUTS}
        if measured is not None:
            arrays[MEASURED] = measured
        t = np.asarray(result.t, float)
        if self.t0 is None and len(t) > 1 and t[-1] > t[0]:   # the whole record: cap the rate
            self.fps = min(self.fps, (self.max_frames - 1) / float(t[-1] - t[0]))
        return self.add(start, result.t, motion.position, motion.rotation, arrays, result.flag)

    def finish(self) -> Frames:
        """The frames of the record given (the last step always among them), at most
        ``max_frames``."""
        if self.last is None:
            raise ValueError("a view needs at least one step")
        parts = list(self.parts)
        if not parts or parts[-1].step[-1] != self.last.step[0]:
            parts.append(self.last)
        frames = Frames.concatenate(parts)
        if len(frames) <= self.max_frames:
            return frames
        return thin(frames, self.max_frames)


def thin(frames: Frames, max_frames: int) -> Frames:
    """At most ``max_frames`` of ``frames``, evenly in time, the first and last kept and the
    flags of those dropped ORed into the next one kept."""
    t = frames.t
    grid = np.linspace(t[0], t[-1], max_frames)
    chosen = np.unique(np.minimum(np.searchsorted(t, grid - 1e-12), len(t) - 1))
    flags = or_since_previous(frames.flag, chosen)
    thinned = frames.take(chosen)
    return Frames(**{**{f.name: getattr(thinned, f.name) for f in fields(Frames)},
                     "flag": flags})


def frame_rate(frames: Frames) -> float:
    """Frames per second of motion time (mean), 0 for a single frame."""
    span = float(frames.t[-1] - frames.t[0]) if len(frames) else 0.0
    return (len(frames) - 1) / span if span > 0 else 0.0
