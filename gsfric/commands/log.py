"""``gsfric log inspect``: a proposed log format and rig for a controller's log."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.commands.common import checked_paths
from gsfric.io.files import output_folder
from gsfric.loginspect import inspect_log
from gsfric.models import platform_from
from gsfric.platform.rig import Rig

FILES = {"log_format": "log_format.toml", "rig": "rig.toml"}
"""The files ``inspect --out DIR`` writes."""


@click.group()
def log():
    """Read a controller's log: `gsfric log inspect LOG` proposes its log format and a rig."""


@log.command()
@click.argument("log_file", metavar="LOG", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              help=f"Folder to write {FILES['log_format']} (the log format, for simulate's "
                   f"--column-map) and {FILES['rig']} (a rig to edit and expand with `gsfric "
                   "platform --template --rig`) [default: write nothing].")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, path_type=Path),
              help="The rig's platform TOML: its geometry gives the home height and the legs "
                   "[default: --rig's, or the reference platform's sizes scaled to the log].")
@click.option("--rig", "rig_file", type=click.Path(dir_okay=False, path_type=Path),
              help="The rig's sizes (a rig TOML, `gsfric platform --rig-template`), instead "
                   "of --platform.")
@click.option("--time", "time_column", metavar="COLUMN",
              help="The time column [default: found by its name and its values].")
@click.option("--axes", metavar="X,Y,Z",
              help="The controller's frame, the log format's axes: for the platform's x, y, "
                   "z the log's signed axis, e.g. x,-y,-z [default: from the names].")
@checked_paths({"log_file": "log", "platform_file": "platform", "rig_file": "rig"},
               folders=("out",))
def inspect(log_file, out, platform_file, rig_file, time_column, axes):
    """Propose a column map for LOG from its names and values, and say what it assumed.

    Finds the time counter (unit, wrap, jitter), the pose columns and their units, the
    angle convention, the log's own velocity and acceleration columns (checked against the
    differentiated poses), the load cells, the controller's frame, the rest pose, the
    workspace, and a home height and stroke that contain the motion. Prints each
    assumption on one line with its evidence; with --out writes a commented log format and
    a rig template.
    """
    if platform_file is not None and rig_file is not None:
        raise click.UsageError("give --platform or --rig, not both")
    platform = platform_from(platform_file) if platform_file is not None else None
    rig = Rig.from_toml(rig_file) if rig_file is not None else None
    found = inspect_log(log_file, platform=platform, rig=rig, time=time_column, axes=axes)
    for line in found.lines():
        click.echo(line)
    if out is None:
        click.echo(f"(nothing written: give --out DIR for {FILES['log_format']} and "
                   f"{FILES['rig']})")
        return
    with output_folder(out, inputs={"log": log_file, "platform": platform_file,
                                    "rig": rig_file}) as folder:
        (folder / FILES["log_format"]).write_text(found.log_format_toml(), encoding="utf-8")
        (folder / FILES["rig"]).write_text(found.rig_toml(), encoding="utf-8")
    click.echo(f"wrote {out / FILES['log_format']} and {out / FILES['rig']}")
    platform_arg = platform_file or "platform.toml"
    if platform_file is None:
        click.echo(f"next: edit {out / FILES['rig']}, then gsfric platform --template --rig "
                   f"{out / FILES['rig']} --out platform.toml")
    click.echo(f"then: gsfric simulate --trajectory {log_file} --column-map "
               f"{out / FILES['log_format']} --platform {platform_arg} --out forces.csv")
