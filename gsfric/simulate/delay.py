"""The sensor's ``time_offset`` applied across the chunks of a streamed evaluation, as over the whole record."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


class SensorDelay:
    """The sensor's ``time_offset`` applied across chunks exactly as over the whole record.

    ``F(t - delay)`` interpolates between the finite steps around ``t - delay``, which may lie
    in an earlier chunk (delay > 0) or a later one (delay < 0): the finite steps' times and
    forces are carried from chunk to chunk (back to the last one at or before the earliest
    time still needed), and a chunk waits, its columns built, until the samples after its last
    ``t - delay`` have been evaluated (or the file has ended). The interpolation brackets are
    those of the whole record, so the values are the same, bit for bit, as
    ``gsfric.platform.catalog.apply_sensor`` over the whole record (``Evaluator.evaluate``)."""

    def __init__(self, gains: np.ndarray, delay: float) -> None:
        self.gains, self.delay = gains, delay
        self.t = np.empty(0)
        self.F = np.empty((0, 6))
        self.pending: list[tuple] = []

    def add(self, t: np.ndarray, F: np.ndarray, good: np.ndarray,
            build: Callable[[np.ndarray], Any]) -> list:
        """Take one chunk: its times, mechanism forces F (N, 6), finite steps, and
        ``build(F_sensor)`` giving what to write. Returns what is ready, in order."""
        self.t = np.concatenate([self.t, t[good]])
        self.F = np.concatenate([self.F, F[good]])
        self.pending.append((t, good, build))
        return self._ready(final=False)

    def finish(self) -> list:
        """Everything still waiting (the file has ended)."""
        return self._ready(final=True)

    def _ready(self, final: bool) -> list:
        done = []
        while self.pending:
            t, good, build = self.pending[0]
            if not final and not (len(self.t) and self.t[-1] >= t[-1] - self.delay):
                break
            self.pending.pop(0)
            done.append(build(self._shifted(t, good)))
            earliest = (self.pending[0][0][0] if self.pending else t[-1]) - self.delay
            first = int(np.searchsorted(self.t, earliest, side="right")) - 1
            if first > 0:
                self.t, self.F = self.t[first:], self.F[first:]
        return done

    def _shifted(self, t: np.ndarray, good: np.ndarray) -> np.ndarray:
        """The sensor's F (N, 6) at the chunk's times t (NaN where not ``good``)."""
        shifted = np.full((len(t), 6), np.nan)
        if len(self.t):
            x = t[good] - self.delay
            part = np.empty((len(x), 6))
            for i in range(6):
                part[:, i] = np.interp(x, self.t, self.F[:, i])
            shifted[good] = part * (1.0 + self.gains)
        return shifted
