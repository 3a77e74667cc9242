"""``gsfric bench``: the throughput table of the compiled, NumPy and per-step evaluations."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.bench.throughput import run_bench


@click.command()
@click.option("--quick", is_flag=True, help="Small sizes only (N = 40 and 1e3).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path),
              help="Also write the table as JSON.")
def bench(quick, out):
    """Print the throughput table: compiled vs NumPy-vectorised vs per-step loop."""
    run_bench(quick=quick, out=out)
