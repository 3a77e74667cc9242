"""The per-leg table of peaks: the largest actuator force, prismatic friction and joint
reactions of each leg over a record, with the time of each, gathered piece by piece.

``Result.summary()`` and the end of ``gsfric simulate`` print the same table (``Peaks.table``):
a Result adds its whole record at once, ``simulate`` each piece as it is evaluated. Peaks are
taken over the sound steps (flag 0): a flagged step's values (a leg outside its stroke, a
near-singular pose) are not forces the rig sees. Times are given from the record's first step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

PEAK_ROWS: tuple[tuple[str, str, str], ...] = (
    ("|F|", "N", "F"),
    ("|Ffr|", "N", "Ffr"),
    ("|R_E|", "N", "R_E"),
    ("|R_C|", "N", "R_C"),
    ("|M_C|", "N m", "M_C"),
)
"""(label, unit, Result array) of each quantity of the table: the actuator force,
the prismatic friction that loads it (``Ffr1..Ffr6``), the reactions at E_i and C_i (their
magnitude) and the universal joint's constraint moment."""

PEAK_ARRAYS = tuple(key for _, _, key in PEAK_ROWS)
"""The Result arrays the table reads."""


@dataclass
class Peaks:
    """Largest magnitudes per leg and the times they occur, over the pieces added so far.

    Attributes
    ----------
    t0 : float or None
        Time of the record's first step, s (None before any step is added).
    steps : int
        Steps added.
    sound : int
        Steps added with flag 0 (those the peaks are taken over).
    values : dict of str -> ndarray (6,)
        Largest magnitude of each ``PEAK_ARRAYS`` array per leg (N or N m); NaN while no sound
        step had a finite value.
    times : dict of str -> ndarray (6,)
        Time of each peak from ``t0``, s.
    """

    t0: float | None = None
    steps: int = 0
    sound: int = 0
    values: dict[str, np.ndarray] = field(default_factory=dict)
    times: dict[str, np.ndarray] = field(default_factory=dict)

    def add(self, t: np.ndarray, arrays, flag: np.ndarray) -> None:
        """Add a piece: times ``t`` (N,) s, ``arrays`` (a mapping holding the arrays of
        ``PEAK_ARRAYS`` that are there, (N, 6) or (N, 6, 3), or flat per step as
        ``evaluate_outputs`` gives them: (N, 6) or (N, 18)), flags (N,)."""
        t = np.asarray(t, dtype=np.float64)
        if not len(t):
            return
        if self.t0 is None:
            self.t0 = float(t[0])
        self.steps += len(t)
        good = np.asarray(flag) == 0
        sound = int(np.count_nonzero(good))
        self.sound += sound
        for _, _, key in PEAK_ROWS:
            if key not in arrays:
                continue
            values = np.reshape(arrays[key], (len(t), 6, -1))
            # squared magnitudes (no root per step); flagged steps never peak, and only they
            # can be NaN (a non-finite output flags its step)
            size = np.square(values[:, :, 0]) if values.shape[2] == 1 else \
                np.einsum("nlk,nlk->nl", values, values)
            if sound < len(t):
                size[~good] = -np.inf
            at = np.argmax(size, axis=0)
            top = size[at, np.arange(6)]                    # -inf: no sound finite step
            peak = np.sqrt(np.where(top >= 0.0, top, np.nan))
            best = self.values.setdefault(key, np.full(6, np.nan))
            when = self.times.setdefault(key, np.full(6, np.nan))
            better = np.isfinite(peak) & ~(peak <= best)      # NaN best: any finite peak
            best[better] = peak[better]
            when[better] = t[at[better]] - self.t0

    def table(self) -> str:
        """The table: a line per leg, a peak and its time (s from the record's start) per
        quantity, units in the header."""
        rows = [row for row in PEAK_ROWS if row[2] in self.values]
        if not rows or not self.sound:
            return "peaks: no sound step (every step flagged)" if self.steps else "peaks: no step"
        heads = [f"{label} ({unit})" for label, unit, _ in rows]
        lines = [(f"peaks per leg over the {self.sound} sound steps; t: s from the record's "
                  f"start (t0 = {self.t0:.6g} s)"),
                 "leg" + "".join(f"{h:>12s}{'t':>9s}" for h in heads)]
        for leg in range(6):
            cells = "".join(f"{self.values[key][leg]:12.4g}{self.times[key][leg]:9.3f}"
                            for _, _, key in rows)
            lines.append(f"{leg + 1:3d}{cells}")
        return "\n".join(lines)
