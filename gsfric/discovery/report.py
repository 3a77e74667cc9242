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
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from gsfric._checks import as_path
from gsfric._optional import optional
from gsfric.discovery.answer import platform_text
from gsfric.discovery.floor import ForceNoise, read_noise_record
from gsfric.discovery.markdown import stribeck_scale
from gsfric.discovery.rest import poses_from_columns
from gsfric.discovery.results import Discovery
from gsfric.discovery.view import write_view
from gsfric.discovery.workflow import discover
from gsfric.io.files import atomic_write, check_output_folder, check_outputs, output_folder
from gsfric.io.readers import read_measured_columns
from gsfric.models import platform_from
from gsfric.platform.usable import check_forces, check_poses
from gsfric.signal.savgol import DEFAULT_POLYORDER

PLOTS = ("residuals_time.png", "residuals_speed.png", "regimes.png")


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


# -- gsfric discover --------------------------------------------------------------------------


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
            handle.write(d.report())
        written.append(path)
        if figures:
            written += plots(d, out)
            written.append(write_view(d, out / "report.html"))
    return [Path(out_dir) / p.name for p in written]


def discover_file(measured: str | os.PathLike[str],
                  platform_file: str | os.PathLike[str] | None = None, *, seed: int = 0,
                  progress: bool = False,
                  force_noise: float | Sequence[float] | None = None,
                  noise_record: str | os.PathLike[str] | None = None, **options) -> Discovery:
    """Read a measured-data file and run the workflow on it (``run_discover`` without the
    outputs); parameters as ``run_discover``'s."""
    platform = platform_from(platform_file)
    log_format = options.pop("log_format", None)   # column map and units of a log
    sensor = _force_noise(force_noise, noise_record, log_format)
    motion, forces, lengths, columns = read_measured_columns(measured, None, DEFAULT_POLYORDER,
                                                          log_format)
    poses = poses_from_columns(columns)
    check_poses(platform, *poses, motion.t, str(measured))
    check_forces(platform, forces, str(measured))
    result = discover(motion, forces, platform, seed=seed, progress=progress, poses=poses,
                      force_noise=sensor, **options)
    result.source = str(measured)
    if isinstance(platform_file, (str, os.PathLike)):
        result.platform_source = str(platform_file)
    how = motion.differentiation()
    if how is not None:
        result.notes.append(f"differentiation: {how.describe()}")
    if lengths is not None:
        model_lengths = result.result_before.D
        gap = float(np.sqrt(np.mean((lengths - model_lengths) ** 2)))
        if gap > 1e-3:
            result.notes.append(
                f"the leg lengths D1..D6 in the file differ from those of the recorded pose by "
                f"{gap * 1e3:.3g} mm RMS: check the platform's geometry")
    return result


def run_discover(measured: str | os.PathLike[str],
                 platform_file: str | os.PathLike[str] | None = None,
                 out_dir: str | os.PathLike[str] = ".", *, seed: int = 0,
                 progress: bool = True, figures: bool = True,
                 force_noise: float | Sequence[float] | None = None,
                 noise_record: str | os.PathLike[str] | None = None, **options) -> list[Path]:
    """``gsfric discover``: read measured data, run the workflow, write its outputs.

    Parameters
    ----------
    measured : path-like
        Measured-data file (CSV or Parquet; SPEC's columns, read by
        ``gsfric.io.read_measured``: bad files raise a one-line ``InputError``).
    platform_file : path-like, optional
        Platform TOML of the current model (default: the reference platform).
    out_dir : path-like
        Output directory (created if needed).
    seed : int
        Seed of the block bootstrap.
    progress : bool
        Progress on stderr.
    figures : bool
        Write the plots and report.html (the 3-D view).
    force_noise : float or sequence of 6 floats, optional
        The load cells' noise, N (a sensor specification; ``--force-noise``), one value or one
        per leg. Default: ``noise_record``'s, else the ``force_noise`` of the log's format
        (``log_format`` in ``options``), else estimated from the force channels.
    noise_record : path-like, optional
        A recording at rest (CSV or Parquet with F1..F6): each force channel's standard
        deviation about its mean is the load cells' noise.
    **options
        ``Settings`` fields; ``log_format`` (a ``LogFormat``) for a log's columns and units.

    Returns
    -------
    list of Path
        The files written (``verdict_line`` of the result is summary.json's ``answer``).

    Raises
    ------
    InputTypeError
        A path that is not a str or os.PathLike.
    InputError
        A bad file (naming the row and column), mostly unusable data, an output that is an
        input, a bad setting.
    OutputError
        An output could not be written (a full disk); nothing partial is left.
    """
    measured = as_path(measured, "measured")
    out_dir = as_path(out_dir, "out_dir")
    if platform_file is not None:
        platform_file = as_path(platform_file, "platform_file")
    check_outputs([out_dir], {"measured-data": measured, "platform": platform_file,
                              "noise-record": noise_record})
    check_output_folder(out_dir)
    result = discover_file(measured, platform_file, seed=seed, progress=progress,
                           force_noise=force_noise, noise_record=noise_record, **options)
    return write(result, out_dir, figures=figures)


def _force_noise(force_noise, noise_record, log_format) -> ForceNoise | None:
    """The load cells' noise the user gives, by precedence: ``--force-noise``,
    ``--noise-record``, the log format's ``force_noise``; None: estimated."""
    if force_noise is not None:
        return ForceNoise.specified(force_noise)
    if noise_record is not None:
        return read_noise_record(noise_record, log_format)
    if log_format is not None and log_format.force_noise is not None:
        return ForceNoise.specified(log_format.force_noise, "force_noise of the column map")
    return None
