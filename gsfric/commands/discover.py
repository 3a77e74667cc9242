"""``gsfric discover``: find the physical effect a model is missing in measured data."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from gsfric.commands.common import checked_paths, force_noise_values, log_options, seed_option
from gsfric.discovery.answer import verdict_line
from gsfric.discovery.api import discover as discover_data
from gsfric.io.logs import LogFormat


@click.command()
@click.option("--measured", type=click.Path(dir_okay=False, exists=True), required=True,
              help="Measured data: trajectory columns plus F1..F6 (optional D1..D6).")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML of the current model (default: the reference platform).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Directory for summary.json, the report and plots.")
@seed_option("the block bootstrap")
@click.option("--force-noise", metavar="N|N1,...,N6",
              help="The load cells' noise (standard deviation, N; the sensor's specification), "
                   "one value or six, one per leg: the verdict compares the residual with it "
                   "[default: a --noise-record's, the column map's force_noise, else estimated "
                   "from the force channels].")
@click.option("--noise-record", type=click.Path(dir_okay=False, exists=True),
              help="A recording at rest (F1..F6, read with the column map and units): each "
                   "force channel's standard deviation about its mean is the load cells' "
                   "noise.")
@click.option("--progress/--no-progress", default=None,
              help="A progress bar over the workflow's stages on stderr [default: when stderr "
                   "is a terminal].")
@click.option("--no-plots", is_flag=True,
              help="Skip the plots and report.html (the 3-D view), and remove an earlier "
                   "run's from the folder; summary.json, report.md and platform.toml are "
                   "written.")
@click.option("--quiet", is_flag=True,
              help="No progress bar and no list of written files (warnings and errors still "
                   "go to stderr).")
@log_options(keep=False)
@checked_paths({"measured": "measured-data", "platform_file": "platform",
                "noise_record": "noise-record", "column_map": "column-map"},
               folders=("out_dir",))
def discover(measured, platform_file, out_dir, seed, force_noise, noise_record, progress,
             no_plots, quiet, column_map, units_map, angles):
    """Find which physical effect the model is missing, fit it, and show the gap shrink.

    The last line printed is the answer, e.g. `explained: seal_friction (force = 3 N) closes
    97 % of the gap; residual 0.2 N RMS (was 4.06 N) vs noise floor 0.2 N`; report.md
    explains it, with a glossary of its statistics.
    """
    show = False if quiet else sys.stderr.isatty() if progress is None else progress
    log_format = LogFormat.from_options(column_map, units_map, angles, None)
    result = discover_data(measured, platform=platform_file, out=out_dir, seed=seed,
                           progress=show, force_noise=force_noise_values(force_noise),
                           noise_record=noise_record, log_format=log_format,
                           figures=not no_plots)
    if not quiet:
        for path in result.written:
            click.echo(f"wrote {path}")
    click.echo(verdict_line(result))

