"""``simulate --plot FILE``: a figure of the actuator forces and the prismatic friction of every
leg over the record, gathered piece by piece in bounded memory.

A record of any length is kept as at most ``MAX_BINS`` bins of consecutive steps: each bin
holds the smallest and the largest value of every series over its steps, so that no peak is
lost however many steps a bin holds; the bins widen (two merged into one) as the record grows.
The figure draws each leg's band between them (a line while a bin is one step), with the
flagged steps marked.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gsfric._optional import optional
from gsfric.io.files import atomic_write

MAX_BINS = 4000
"""Bins kept of a record: about two per pixel across a figure 12 inches wide at 150 dpi."""

SERIES = (("F", "actuator force F (N)"), ("Ffr", "prismatic friction Ffr (N)"))
"""(Result array, axis label) of each panel of the figure: the file's F1..F6 and Ffr1..Ffr6."""


@dataclass
class Trace:
    """Per-bin extremes of ``SERIES`` over the steps added so far.

    Attributes
    ----------
    stride : int
        Steps per bin (a power of two).
    t : list of float
        First time of each bin, s.
    low, high : list of ndarray (len(SERIES), 6)
        Smallest and largest value of each series per leg over each bin's steps (NaN: no
        finite value).
    flagged : list of bool
        Whether a bin holds a flagged step.
    """

    stride: int = 1
    t: list = field(default_factory=list)
    low: list = field(default_factory=list)
    high: list = field(default_factory=list)
    flagged: list = field(default_factory=list)
    _fill: int = 0                  # steps in the last bin

    def add(self, t: np.ndarray, arrays, flag: np.ndarray) -> None:
        """Add a piece: times (N,) s, ``arrays`` holding ``SERIES``' arrays (N, 6), flags
        (N,)."""
        n = len(t)
        values = np.stack([np.reshape(arrays[key], (n, 6)) for key, _ in SERIES], axis=1)
        s = 0
        while s < n:
            if self._fill == 0 or self._fill >= self.stride:
                self._open(float(t[s]))
            e = min(n, s + self.stride - self._fill)
            self._merge_into(-1, values[s:e], bool(np.any(flag[s:e])))
            self._fill += e - s
            s = e
            if len(self.t) > MAX_BINS and self._fill >= self.stride:
                self._widen()

    def _open(self, t0: float) -> None:
        self.t.append(t0)
        self.low.append(np.full((len(SERIES), 6), np.nan))
        self.high.append(np.full((len(SERIES), 6), np.nan))
        self.flagged.append(False)
        self._fill = 0

    def _merge_into(self, k: int, values: np.ndarray, flagged: bool) -> None:
        with np.errstate(invalid="ignore"):
            low = np.fmin.reduce(values, axis=0) if len(values) else self.low[k]
            high = np.fmax.reduce(values, axis=0) if len(values) else self.high[k]
        self.low[k] = np.fmin(self.low[k], low)
        self.high[k] = np.fmax(self.high[k], high)
        self.flagged[k] = self.flagged[k] or flagged

    def _widen(self) -> None:
        """Merge the full bins in pairs: twice the steps a bin (an odd last bin stays, half
        full)."""
        odd = len(self.t) % 2
        n = len(self.t) - odd
        rest = slice(n, None)
        self.t = self.t[0:n:2] + self.t[rest]
        self.low = [np.fmin(a, b) for a, b in zip(self.low[0:n:2], self.low[1:n:2])] \
            + self.low[rest]
        self.high = [np.fmax(a, b) for a, b in zip(self.high[0:n:2], self.high[1:n:2])] \
            + self.high[rest]
        self.flagged = [a or b for a, b in zip(self.flagged[0:n:2], self.flagged[1:n:2])] \
            + self.flagged[rest]
        self._fill = self.stride if odd else 2 * self.stride
        self.stride *= 2


def write_figure(path, trace: Trace, t0: float, title: str = "") -> None:
    """Write the figure of ``trace`` to ``path`` (PNG, SVG or PDF by the extension, through a
    temporary file): a panel per series of ``SERIES``, legs 1..6, time from ``t0``, s."""
    figure_module = optional("matplotlib.figure")
    backend = optional("matplotlib.backends.backend_agg")
    fig = figure_module.Figure(figsize=(12, 7), layout="constrained")
    backend.FigureCanvasAgg(fig)
    axes = fig.subplots(len(SERIES), 1, sharex=True)
    t = np.asarray(trace.t) - t0
    low, high = np.asarray(trace.low), np.asarray(trace.high)
    flagged = np.asarray(trace.flagged, dtype=bool)
    for j, (ax, (_, label)) in enumerate(zip(axes, SERIES)):
        for leg in range(6):
            colour = f"C{leg}"
            if trace.stride == 1:
                ax.plot(t, high[:, j, leg], color=colour, lw=0.8, label=f"leg {leg + 1}")
            else:
                ax.fill_between(t, low[:, j, leg], high[:, j, leg], color=colour, alpha=0.5,
                                lw=0, label=f"leg {leg + 1}")
        if flagged.any():
            bottom = np.nanmin(low[:, j]) if np.isfinite(low[:, j]).any() else 0.0
            ax.plot(t[flagged], np.full(int(flagged.sum()), bottom), "|", color="C3",
                    ms=8, label="flagged")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(ncol=7, fontsize="small", loc="upper right")
    axes[-1].set_xlabel(f"t from the record's start (s; t0 = {t0:.6g} s)")
    if trace.stride > 1:
        title += f" (band: smallest to largest over every {trace.stride} steps)"
    if title:
        fig.suptitle(title.strip())
    suffix = str(path).rsplit(".", 1)[-1].lower() if "." in str(path) else "png"
    with atomic_write(path, "wb") as handle:
        fig.savefig(handle, format=suffix, dpi=150)
