"""Outputs of ``gsfric discover``: summary.json (SPEC), a readable report, plots.

Files written in the output directory, each atomically:

* ``summary.json``: ``effects`` (name, parameters, evidence), ``rms_before``, ``rms_after``,
  ``noise_rms_estimate`` (SPEC), plus the refit, the rounds, the gap per leg and per regime
  (``Discovery.summary()``, ``summary.summary``);
* ``report.md``: the same for a reader, with the decisions explained (``Discovery.report()``,
  ``markdown.report``);
* ``platform.toml``: the final model, commented (``answer.platform_text``);
* ``residuals_time.png``, ``residuals_speed.png``, ``regimes.png``: residuals before and after
  over time, against the leg speed, and per regime;
* ``report.html``: the 3-D view of the final model along the measured motion, with the
  measured and model forces, the residuals and the named effects' contributions per leg
  (``gsfric.discovery.view``).

Without the figures (``--no-plots``) neither the plots nor report.html is written, the report
does not list them, and an earlier run's copies in the folder are removed (they would show
another record).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from gsfric._optional import optional
from gsfric.discovery.answer import platform_text
from gsfric.discovery.markdown import stribeck_scale
from gsfric.discovery.outcome import Discovery
from gsfric.discovery.view import write_view
from gsfric.io.files import atomic_write, output_folder

PLOTS = ("residuals_time.png", "residuals_speed.png", "regimes.png")
VIEW = "report.html"
"""The 3-D view of model and measurement (``gsfric.discovery.view``)."""


# -- plots ------------------------------------------------------------------------------------


def _thin(n: int, most: int = 2000) -> slice:
    return slice(None, None, max(1, n // most))


def _binned(u: np.ndarray, r: np.ndarray, bins: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Means of ``r`` in ``bins`` equal bins of ``u`` (empty bins dropped)."""
    edges = np.linspace(u.min(), u.max(), bins + 1)
    idx = np.clip(np.searchsorted(edges[1:-1], u), 0, bins - 1)
    keep = [j for j in range(bins) if (idx == j).any()]
    return (np.array([u[idx == j].mean() for j in keep]),
            np.array([r[idx == j].mean() for j in keep]))


def _speed_figure(figure, d: Discovery):
    """Residual against each leg's speed, symmetric-log speed axis (linear within the
    Stribeck scale), binned means evenly spaced on that axis."""
    rb, ra = d.residual_before, d.residual_after
    k = _thin(len(d.t))
    speed = d.result_before.D_dot[d.used]
    scale = stribeck_scale(d)
    fig = figure(figsize=(12, 7))
    axes = fig.subplots(2, 3, sharex=True)
    for i, ax in enumerate(axes.ravel()):
        v = speed[:, i]
        u = np.sign(v) * np.log1p(np.abs(v) / scale)          # the axis' own spacing
        for r, colour, label in ((rb, "0.5", "before"), (ra, "C0", "after")):
            centres, means = _binned(u, r[:, i])
            ax.plot(v[k], r[k, i], ".", ms=1.5, color=colour, alpha=0.25)
            ax.plot(np.sign(centres) * scale * np.expm1(np.abs(centres)), means, "-",
                    color=colour, lw=1.8, label=f"{label} (binned mean)")
        ax.set_xscale("symlog", linthresh=scale, linscale=1.0)
        ax.axvspan(-scale, scale, color="C1", alpha=0.08, lw=0)
        ax.axvline(0, color="k", lw=0.5)
        ax.set_title(f"leg {i + 1}", fontsize=10)
        ax.tick_params(labelsize=8)
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="upper left")
    for ax in axes[1]:
        ax.set_xlabel("leg speed dD/dt (m/s), symmetric-log axis", fontsize=9)
    for ax in axes[:, 0]:
        ax.set_ylabel("residual F_measured - F_model (N)", fontsize=9)
    fig.suptitle(f"Residual (N) against leg speed (m/s): linear within ±{scale:.3g} m/s "
                 "(shaded: the Stribeck velocity scale), logarithmic beyond")
    fig.subplots_adjust(left=0.07, right=0.98, top=0.9, bottom=0.09, wspace=0.22, hspace=0.25)
    return fig


def _regimes_figure(figure, d: Discovery):
    """RMS residual per band of each regime, before and after, bands as labelled rows."""
    bands = d.regimes
    fig = figure(figsize=(9, 0.32 * len(bands) + 1.6))
    ax = fig.subplots()
    y = np.arange(len(bands))[::-1]
    ax.barh(y + 0.2, [b.rms_before for b in bands], 0.4, color="0.6", label="before")
    ax.barh(y - 0.2, [b.rms_after for b in bands], 0.4, color="C0", label="after")
    ax.set_yticks(y, [f"{b.regime}: {b.name}" for b in bands], fontsize=9)
    for n in range(1, len(bands)):
        if bands[n].regime != bands[n - 1].regime:
            ax.axhline(y[n] + 0.5, color="0.8", lw=0.8)
    ax.set_xlabel("RMS residual (N)")
    ax.legend(fontsize=9, loc="lower right")
    ax.set_title("Gap per regime: RMS residual (N) in each band, before and after")
    ax.grid(True, axis="x", alpha=0.3)
    fig.tight_layout()
    return fig


def plots(d: Discovery, out_dir: Path) -> list[Path]:
    """Write the three figures; returns their paths."""
    FigureCanvasAgg = optional("matplotlib.backends.backend_agg").FigureCanvasAgg
    Figure = optional("matplotlib.figure").Figure

    def figure(**kwargs):   # on an Agg canvas: no pyplot state, no GUI
        fig = Figure(**kwargs)
        FigureCanvasAgg(fig)
        return fig

    out_dir = Path(out_dir)
    written = []

    def save(fig, name):
        path = out_dir / name
        with atomic_write(path, "wb") as handle:
            fig.savefig(handle, format="png", dpi=90)
        written.append(path)

    t, rb, ra = d.t, d.residual_before, d.residual_after
    k = _thin(len(t))
    fig = figure(figsize=(9, 10))
    axes = fig.subplots(6, 1, sharex=True)
    for i, ax in enumerate(axes):
        ax.plot(t[k], rb[k, i], color="0.6", lw=0.6, label="before")
        ax.plot(t[k], ra[k, i], color="C0", lw=0.6, label="after")
        ax.set_ylabel(f"leg {i + 1}\nN")
    axes[0].legend(loc="upper right", ncol=2, fontsize=8)
    axes[0].set_title("Residual F_measured - F_model (N) over time (s)")
    axes[-1].set_xlabel("t (s)")
    fig.subplots_adjust(left=0.1, right=0.98, top=0.96, bottom=0.05, hspace=0.15)
    save(fig, PLOTS[0])
    save(_speed_figure(figure, d), PLOTS[1])
    save(_regimes_figure(figure, d), PLOTS[2])
    return written


# -- the output folder --------------------------------------------------------------------------


def write(d: Discovery, out_dir: str | os.PathLike[str], *, figures: bool = True
          ) -> list[Path]:
    """Write summary.json (``d.summary()``), platform.toml, report.md (``d.report()``) and
    (with ``figures``) the plots and report.html; returns their paths. ``d.source`` and
    ``d.platform_source`` are the inputs the outputs must not overwrite."""
    written = []
    with output_folder(out_dir, inputs={"measured-data": d.source or None,
                                        "platform": d.platform_source or None}) as out:
        path = out / "summary.json"
        with atomic_write(path) as handle:
            json.dump(d.summary(), handle, indent=2, allow_nan=False)
            handle.write("\n")
        written.append(path)
        path = out / "platform.toml"
        with atomic_write(path, "w") as handle:
            handle.write(platform_text(d))
        written.append(path)
        path = out / "report.md"
        with atomic_write(path) as handle:
            handle.write(d.report(figures))
        written.append(path)
        if figures:
            written += plots(d, out)
            written.append(write_view(d, out / VIEW))
    if not figures:
        # an earlier run's figures in this folder would show another record beside these
        for name in (*PLOTS, VIEW):
            (Path(out_dir) / name).unlink(missing_ok=True)
    return [Path(out_dir) / p.name for p in written]
