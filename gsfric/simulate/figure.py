"""``simulate --plot FILE``: a figure of the actuator forces and the prismatic friction of every
leg over the record, gathered piece by piece in bounded memory.

A record of any length is kept as at most ``MAX_BINS`` bins of consecutive steps: each bin
holds the smallest and the largest value of every series over its steps, so that no peak is
lost however many steps a bin holds; the bins widen (two merged into one) as the record grows.
The figure draws each leg's band between them (a line while a bin is one step), with the
flagged steps marked, and, where the motion was differentiated from poses, the force's band of
one standard deviation from the differentiation (``sigma_F``, its largest value in each bin).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gsfric._optional import optional
from gsfric.errors import InputError
from gsfric.io.files import atomic_write

MAX_BINS = 4000
"""Bins kept of a record: about two per pixel across a figure 12 inches wide at 150 dpi."""

FORMATS = ("png", "svg", "pdf")
"""The figure's formats, by the file's extension."""

SERIES = (("F", "actuator force F (N)"), ("Ffr", "prismatic friction Ffr (N)"))
"""(Result array, axis label) of each panel of the figure: the file's F1..F6 and Ffr1..Ffr6."""

SIGMA = "sigma_F"
"""The Result array of the force's uncertainty, kept after ``SERIES`` when a piece has it."""


@dataclass
class Trace:
    """Per-bin extremes of ``SERIES`` over the steps added so far.

    Attributes
    ----------
    stride : int
        Steps per bin (a power of two).
    t : ndarray, shape (B,)
        First time of each bin, s.
    low, high : ndarray, shape (B, S, 6)
        Smallest and largest value of each series per leg over each bin's steps (NaN: no
        finite value): ``SERIES``, then ``SIGMA`` when the pieces have it (S = 3).
    flagged : ndarray of bool, shape (B,)
        Whether a bin holds a flagged step.
    fill : int
        Steps in the last bin (``stride`` when it is full).
    """

    stride: int = 1
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    low: np.ndarray = field(default_factory=lambda: np.zeros((0, len(SERIES), 6)))
    high: np.ndarray = field(default_factory=lambda: np.zeros((0, len(SERIES), 6)))
    flagged: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    fill: int = 0

    def add(self, t: np.ndarray, arrays, flag: np.ndarray) -> None:
        """Add a piece: times (N,) s, ``arrays`` holding ``SERIES``' arrays (N, 6), flags
        (N,)."""
        n = len(t)
        keys = [key for key, _ in SERIES] + ([SIGMA] if SIGMA in arrays else [])
        values = np.stack([np.reshape(arrays[key], (n, 6)) for key in keys], axis=1)
        if not len(self.t):
            self.low = self.high = np.zeros((0, len(keys), 6))
        bad = np.asarray(flag) != 0
        s = 0
        while s < n:
            if self.fill and self.fill < self.stride:      # the last bin first
                e = min(n, s + self.stride - self.fill)
                self._extend_last(values[s:e], bool(bad[s:e].any()))
                s = e
                continue
            whole = (n - s) // self.stride * self.stride
            if whole:
                self._append(t[s:s + whole:self.stride], values[s:s + whole], bad[s:s + whole],
                             self.stride)
                s += whole
            else:
                self._append(t[s:s + 1], values[s:], bad[s:], n - s)
                s = n
            while len(self.t) > MAX_BINS:
                self._widen()

    def _append(self, starts: np.ndarray, values: np.ndarray, bad: np.ndarray,
                size: int) -> None:
        """Append bins of ``size`` steps (the last of them possibly fewer: ``len(values)``)."""
        k = len(starts)
        shape = (k, -1) + values.shape[1:]
        blocks = values.reshape(shape) if len(values) == k * size else values[None]
        with np.errstate(invalid="ignore"):
            self.low = np.concatenate([self.low, np.fmin.reduce(blocks, axis=1)])
            self.high = np.concatenate([self.high, np.fmax.reduce(blocks, axis=1)])
        self.flagged = np.concatenate([self.flagged, bad.reshape(k, -1).any(axis=1)])
        self.t = np.concatenate([self.t, starts])
        self.fill = len(values) - (k - 1) * size

    def _extend_last(self, values: np.ndarray, bad: bool) -> None:
        self.low[-1] = np.fmin(self.low[-1], np.fmin.reduce(values, axis=0))
        self.high[-1] = np.fmax(self.high[-1], np.fmax.reduce(values, axis=0))
        self.flagged[-1] |= bad
        self.fill += len(values)

    def _widen(self) -> None:
        """Merge the bins in pairs: twice the steps a bin (an odd last bin stays alone)."""
        odd = len(self.t) % 2
        n = len(self.t) - odd

        def pairs(a, merge):
            return np.concatenate([merge(a[0:n:2], a[1:n:2]), a[n:]])

        self.t = np.concatenate([self.t[0:n:2], self.t[n:]])
        self.low, self.high = pairs(self.low, np.fmin), pairs(self.high, np.fmax)
        self.flagged = pairs(self.flagged, np.logical_or)
        self.fill = self.fill if odd else self.fill + self.stride
        self.stride *= 2


def check_figure(path) -> str:
    """The figure's format from the extension of ``path`` (``FORMATS``), before any work:
    ``InputError`` naming the path for another one; matplotlib imported (an error naming it
    when it is missing)."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in FORMATS:
        raise InputError(f"{path}: --plot: unknown figure format {suffix or '(none)'!r}; give "
                         f"a file ending in {', '.join('.' + f for f in FORMATS)}")
    optional("matplotlib.figure")
    return suffix


def write_figure(path, trace: Trace, t0: float, title: str = "") -> None:
    """Write the figure of ``trace`` to ``path`` (PNG, SVG or PDF by the extension, through a
    temporary file): a panel per series of ``SERIES``, legs 1..6, time from ``t0``, s."""
    figure_module = optional("matplotlib.figure")
    backend = optional("matplotlib.backends.backend_agg")
    fig = figure_module.Figure(figsize=(12, 7), layout="constrained")
    backend.FigureCanvasAgg(fig)
    axes = fig.subplots(len(SERIES), 1, sharex=True)
    t, low, high, flagged = trace.t - t0, trace.low, trace.high, trace.flagged
    sigma = high[:, len(SERIES)] if high.shape[1] > len(SERIES) else None
    for j, (ax, (_, label)) in enumerate(zip(axes, SERIES)):
        for leg in range(6):
            colour = f"C{leg}"
            if j == 0 and sigma is not None:
                ax.fill_between(t, low[:, j, leg] - sigma[:, leg],
                                high[:, j, leg] + sigma[:, leg], color=colour, alpha=0.15, lw=0)
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
    if sigma is not None:
        title += " (pale: F \u00b1 sigma_F, the differentiation's standard deviation)"
    if title:
        fig.suptitle(title.strip())
    suffix = check_figure(path)
    with atomic_write(path, "wb") as handle:
        fig.savefig(handle, format=suffix, dpi=150)
