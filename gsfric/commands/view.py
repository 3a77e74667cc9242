"""``gsfric view``: a trajectory evaluated as by ``simulate`` and written as a 3-D view."""

from __future__ import annotations

import warnings
from pathlib import Path

import click

from gsfric.commands.common import checked_paths, evaluation_options, log_options, with_options
from gsfric.io.logs import LogFormat
from gsfric.simulate import view_file
from gsfric.view import DEFAULT_FPS, MAX_FRAMES


def _options(command):
    """The options of ``view`` besides those of a log's format."""
    path = click.Path(path_type=Path)
    shared = evaluation_options()
    options = [
        click.option("--trajectory", type=path,
                     help="Trajectory or measured-data file (CSV or Parquet), as for "
                          "`gsfric simulate`."),
        click.option("--measured", type=path,
                     help="Measured-data file (CSV or Parquet): the trajectory with the "
                          "measured forces F1..F6, plotted against the model's with the "
                          "residual (instead of --trajectory; the forces are required)."),
        shared["platform"],
        click.option("--out", type=path, required=True,
                     help="The page, .html; written to a temporary file and renamed when "
                          "complete."),
        shared["mode"],
        click.option("--fps", type=click.FloatRange(min=0, min_open=True), default=DEFAULT_FPS,
                     show_default=True,
                     help=f"Frames per second of motion time kept for playback (at most "
                          f"{MAX_FRAMES:,} frames in all: a longer record gets fewer a "
                          "second)."),
        click.option("--title", default=None,
                     help="The page's title [default: the trajectory's name and the mode]."),
        shared["threads"],
        shared["chunk"],
        shared["window"],
        click.option("--quiet", is_flag=True, help="No summary line."),
    ]
    return with_options(command, options)


@click.command()
@_options
@log_options
@checked_paths({"trajectory": "trajectory", "measured": "measured-data",
                "platform_file": "platform", "column_map": "column-map"}, files=("out",))
def view(trajectory, measured, platform_file, out, mode, fps, title, threads, chunk, window,
         quiet, column_map, units_map, angles, keep_columns):
    """Write a 3-D view of a motion and its joint loads: one HTML page, opened offline.

    The trajectory is read and evaluated as by `gsfric simulate`. The page draws the base, the
    platform and the legs coloured by actuator force, the joint reactions as arrows, each
    joint's friction as a colour and the flagged steps, with plots of the force and the
    prismatic friction per leg, play, pause, speed and a time slider; hovering or clicking a
    leg shows its values. A measured-data file's forces F1..F6 are plotted against the model's,
    with the residual. It needs no network and no server: three.js is inside it. Open it
    at a time with #t=SECONDS after its address (file:///.../view.html#t=2.5).
    """
    if (trajectory is None) == (measured is None):
        raise click.UsageError("give one of --trajectory and --measured")
    with warnings.catch_warnings():                    # shown one line each by the group
        warnings.simplefilter("always", UserWarning)
        log_format = LogFormat.from_options(column_map, units_map, angles, keep_columns)
        summary = view_file(trajectory or measured, out, platform_file, mode=mode,
                            chunk=chunk, window=window, n_threads=threads,
                            log_format=log_format, fps=fps, title=title,
                            measured=measured is not None)
    if not quiet:
        click.echo(f"wrote {out} ({summary.steps} steps as {summary.frames} frames, "
                   f"{summary.size / 1e6:.1f} MB, {summary.flagged} flagged)")
