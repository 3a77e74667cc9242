"""``gsfric bench``: the throughput table of the compiled, NumPy and per-step evaluations."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.bench.all import run_all
from gsfric.bench.throughput import run_bench
from gsfric.sweep.scaling import dask_scaling


@click.command()
@click.option("--quick", is_flag=True, help="Small sizes only (N = 40 and 1e3; with --all, "
              "every path at a small size, goals not judged).")
@click.option("--all", "every", is_flag=True,
              help="Every user path against its goal, in one run: evaluate, simulate to "
                   "Parquet, threads beside a busy core, discover, the control loop, Dask.")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path),
              help="Also write the table as JSON.")
def bench(quick, every, out):
    """Print the throughput table: compiled vs NumPy-vectorised vs per-step loop.

    With --all: every user path against its goal, measured in one run."""
    if every:
        run_all(quick=quick, out=out, dask=dask_scaling)
    else:
        run_bench(quick=quick, out=out)
