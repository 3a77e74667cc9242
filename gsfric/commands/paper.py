"""``gsfric paper``: the paper's 40-step motion, its Tables 1-3, a report and plots."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.commands.common import checked_paths
from gsfric.paper.report import run_paper


@click.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Directory for tables, report, plots and platform.toml.")
@click.option("--mode", type=click.Choice(["paper", "kinematic"]), default="paper",
              show_default=True,
              help="paper: the paper's constant accelerations; kinematic: from the motion.")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML (default: the paper's reference platform).")
@click.option("--no-plots", is_flag=True, help="Skip the plots.")
@checked_paths({"platform_file": "platform"}, folders=("out_dir",))
def paper(out_dir, mode, platform_file, no_plots):
    """Run the paper's 40-step motion and write Tables 1-3, a report and plots."""
    written = run_paper(out_dir, mode=mode, platform_file=platform_file, plots=not no_plots)
    for path in written:
        click.echo(f"wrote {path}")
