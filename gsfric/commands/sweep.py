"""``gsfric sweep``: load envelopes per joint over motions, a workspace and platform variants."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import click

from gsfric.commands.common import EXIT_CHECK, checked_paths, fail, partial_of, seed_option
from gsfric.errors import GsfricWarning
from gsfric.sweep import sweep as run_sweep
from gsfric.sweep.plan import CHUNK_STEPS


def _pairs(values, option, ranged):
    """``NAME=MIN:MAX`` (ranged) or ``NAME=VALUE`` options as a dict; one-line errors, also
    for a name given twice (the later value would silently replace the first)."""
    out = {}
    for text in values:
        name, sep, rest = text.partition("=")
        if sep and name.strip() in out:
            fail(f"{option}: {name.strip()!r} given twice; give each parameter once")
        try:
            if not sep:
                raise ValueError
            if ranged:
                lo, colon, hi = rest.partition(":")
                if not colon:
                    raise ValueError
                out[name.strip()] = (float(lo), float(hi))
            else:
                out[name.strip()] = float(rest)
        except ValueError:
            form = "NAME=MIN:MAX" if ranged else "NAME=VALUE"
            fail(f"{option}: expected {form}, got {text!r}")
    return out


@click.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Output folder (built in OUT.partial, renamed when complete; "
                                  "an unfinished sweep there resumes).")
@click.option("--trajectories", multiple=True, metavar="GLOB",
              help="Trajectory files, a glob such as 'runs/*.parquet' (repeatable).")
@click.option("--workspace", type=click.Path(dir_okay=False, path_type=Path),
              help="Workspace TOML: pose ranges, sampling, velocity/acceleration bounds.")
@click.option("--platform", "platform_file", type=click.Path(path_type=Path),
              help="Platform TOML, with optional [limits] (default: the reference platform).")
@click.option("--vary", multiple=True, metavar="NAME=MIN:MAX",
              help="A parameter range of the variants, e.g. platform.payload_mass=0:10 "
                   "(repeatable).")
@click.option("--tolerance", multiple=True, metavar="NAME=SD",
              help="A Monte-Carlo tolerance, e.g. geometry.base_joints=0.0005 (repeatable).")
@click.option("--variants", type=click.IntRange(1), default=None,
              help="Variants drawn at random besides the nominal one (with --vary or "
                   "--tolerance): a Latin hypercube over the --vary ranges, normal errors for "
                   "the --tolerance ones [default: 16].")
@click.option("--grid", type=click.IntRange(1), default=None, metavar="N",
              help="Instead of random draws: N evenly spaced values of each --vary range, "
                   "ends included, every combination (N^k variants for k ranges). Not with "
                   "--variants or --tolerance.")
@seed_option("the variants")
@click.option("--scheduler", default=None, metavar="auto|serial|local|tcp://HOST:PORT",
              help="Where tasks run [default: DASK_SCHEDULER_ADDRESS if set, else serial for "
                   "small sweeps and a local cluster of one process per core].")
@click.option("--workers", type=click.IntRange(1, 256), default=None,
              help="Worker processes of the local cluster [default: one per core].")
@click.option("--chunk-steps", type=click.IntRange(1), default=None,
              help="Evaluated steps per task [default: 1000000, a second or more].")
@click.option("--progress/--no-progress", default=None,
              help="Progress bar with total and ETA [default: when stderr is a terminal].")
@click.option("--no-plots", is_flag=True, help="Skip the plots and worst_cases.html.")
@click.option("--strict", is_flag=True, help="Exit 1 when a case exceeds the [limits].")
@checked_paths({"trajectories": "trajectory", "workspace": "workspace",
                "platform_file": "platform"}, folders=("out_dir", partial_of("out_dir")))
def sweep(out_dir, trajectories, workspace, platform_file, vary, tolerance, variants, grid, seed,
          scheduler, workers, chunk_steps, progress, no_plots, strict):
    """Load envelopes per joint over motions, a workspace and platform variants.

    Platform variants are drawn at random by default (--vary ranges by Latin hypercube,
    --tolerance as normal errors, --variants of them, reproducible by --seed); --grid N lays
    N evenly spaced values over each range instead. Writes envelopes.parquet (per case,
    quantity and leg, with where each extreme occurs), summary.csv, variants.csv, limits.csv
    (cases beyond the platform's [limits]), sweep.json, plots and worst_cases.html (the 3-D
    view of each joint's worst-case pose). See docs/howto/sizing.md.
    """
    if grid is not None and variants is not None:
        fail("--grid: gives the number of values per parameter; leave out --variants")
    if grid is not None and tolerance:
        fail("--grid: not with --tolerance, which are random draws")
    if grid is not None and not vary:
        fail("--grid: give the ranges to lay it over with --vary NAME=MIN:MAX")
    if variants is not None and not (vary or tolerance):
        fail("--variants: gives the number of platform variants to draw; give the ranges "
             "they are drawn from with --vary NAME=MIN:MAX or --tolerance NAME=SD")
    result = run_sweep(out_dir, trajectories=list(trajectories) or None, workspace=workspace,
                       platform=platform_file, vary=_pairs(vary, "--vary", True),
                       tolerances=_pairs(tolerance, "--tolerance", False),
                       variants=16 if variants is None else variants, grid=grid,
                       seed=seed, scheduler=scheduler, workers=workers,
                       chunk_steps=chunk_steps or CHUNK_STEPS, progress=progress,
                       plots=not no_plots)
    _report(result, strict)


def _report(result, strict: bool) -> None:
    """The sweep's summary lines: cases, the most loaded universal joint, the limits."""
    info = result.info
    click.echo(f"wrote {result.out} ({info['cases']} cases, {info['steps']} steps, "
               f"{info['flagged']} flagged)")
    click.echo(f"variants: {info.get('variants_drawn', '')}")
    top = result.most_loaded("R_C")
    if top is None:
        warnings.warn(f"{result.out}: every step of every case is flagged (see the flagged "
                      "column of envelopes.parquet): no load envelope", GsfricWarning,
                      stacklevel=2)
        return
    click.echo(f"most loaded universal joint: leg {int(top.leg)}, |R_C| = {top.value:.4g} N "
               f"({top.motion}, variant {int(top.variant)}, step {int(top.step)})")
    if info["limits"]:
        n = info["exceeding_cases"]
        click.echo(f"limits: {n} case(s) exceed them" + (f" (see {result.out / 'limits.csv'})"
                                                          if n else ""))
        if n and strict:
            sys.exit(EXIT_CHECK)
    else:
        click.echo("limits: no limits given (the platform has no [limits]): nothing checked")
