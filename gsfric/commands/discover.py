"""``gsfric discover``: find the physical effect a model is missing in measured data."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from gsfric.commands.common import log_options
from gsfric.discovery import run_discover
from gsfric.io.logs import LogFormat


@click.command()
@click.option("--measured", type=click.Path(dir_okay=False, exists=True), required=True,
              help="Measured data: trajectory columns plus F1..F6 (optional D1..D6).")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML of the current model (default: the reference platform).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Directory for summary.json, the report and plots.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the block bootstrap.")
@click.option("--progress/--no-progress", default=None,
              help="A progress bar over the workflow's stages on stderr [default: when stderr "
                   "is a terminal].")
@click.option("--quiet", is_flag=True,
              help="No progress bar and no list of written files (warnings and errors still "
                   "go to stderr).")
@log_options(keep=False)
def discover(measured, platform_file, out_dir, seed, progress, quiet, column_map, units_map,
             angles):
    """Find which physical effect the model is missing, fit it, and show the gap shrink."""
    show = False if quiet else sys.stderr.isatty() if progress is None else progress
    log_format = LogFormat.from_options(column_map, units_map, angles, None)
    written = run_discover(measured, platform_file, out_dir, seed=seed, progress=show,
                           **({"log_format": log_format} if log_format else {}))
    if not quiet:
        for path in written:
            click.echo(f"wrote {path}")
