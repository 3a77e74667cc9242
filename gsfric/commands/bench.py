"""``gsfric bench``: the throughput table of the compiled model (``gsfric.throughput``)."""

from __future__ import annotations

import json
from pathlib import Path

import click

from gsfric.commands.common import checked_paths, fail
from gsfric.io.files import atomic_write
from gsfric.throughput import format_table, measure


@click.command()
@click.option("--quick", is_flag=True, help="Small sizes only (N = 40 and 1e3).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path),
              help="Also write the figures as JSON.")
@click.option("--all", "every", is_flag=True, hidden=True)
@checked_paths({}, files=("out",))
def bench(quick, out, every):
    """Print the throughput table of the compiled model (steps per second).

    The compiled actuator map of the reference platform at N = 40 to 1e6 steps per call:
    SIMD over steps on one and two threads, and one step per call."""
    if every:
        fail("--all: every user path against its goal is measured from a source checkout: "
             "`make bench-all` (or `python -m benchmarks.all`)")
    run = measure(quick, progress=lambda s: click.echo(s, err=True))
    click.echo(format_table(run))
    if out is not None:
        with atomic_write(out) as f:
            f.write(json.dumps(run.as_dict(), indent=2) + "\n")
        click.echo(f"wrote {out}")
