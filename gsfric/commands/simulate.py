"""``gsfric simulate``: evaluate a trajectory or measured-data file, streamed in chunks."""

from __future__ import annotations

import atexit
import contextlib
import gc
import warnings
from pathlib import Path

import click

from gsfric.commands.common import checked_paths, evaluation_options, log_options, with_options
from gsfric.errors import IgnoredColumnsWarning, InputError
from gsfric.evaluation.breakdown import flat
from gsfric.evaluation.columns import DEFAULT_GROUPS as DEFAULT_COLUMN_GROUPS
from gsfric.evaluation.columns import GROUPS as COLUMN_GROUPS
from gsfric.evaluation.evaluator import breakdown
from gsfric.io.files import output_group
from gsfric.io.logs import LogFormat
from gsfric.io.readers import read_trajectory
from gsfric.io.tables import write_table
from gsfric.models import platform_from
from gsfric.platform.usable import FLAGGED_LIMIT
from gsfric.simulate import parse_columns, simulate_file


@contextlib.contextmanager
def _no_cycle_collection():
    """No cycle collection inside, and the objects left at exit frozen (the run of ``simulate``).

    A streamed run makes no cyclic garbage to speak of, while its imports (SciPy, pandas,
    pyarrow) create objects that every collection would walk again, and the interpreter's exit
    would walk them once more: together a tenth of the CPU time of a million-step run.
    """
    collecting = gc.isenabled()
    gc.disable()
    atexit.unregister(gc.freeze)
    atexit.register(gc.freeze)
    try:
        yield
    finally:
        if collecting:
            gc.enable()


def _options(command):
    """The options of ``simulate`` besides those of a log's format."""
    path = click.Path(path_type=Path)
    shared = evaluation_options()
    options = [
        click.option("--trajectory", type=path, required=True,
                     help="Trajectory or measured-data file (CSV or Parquet): t,x,y,z with "
                          "alpha,beta,gamma, qw,qx,qy,qz or roll,pitch,yaw; other names and "
                          "units with --column-map and --units."),
        shared["platform"],
        click.option("--out", type=path, required=True,
                     help="Output file, CSV or Parquet by extension; written to a temporary "
                          "file and renamed when complete."),
        shared["mode"],
        click.option("--strict", is_flag=True,
                     help="Fail (exit 1, no output) at the first chunk with a flagged step."),
        shared["threads"],
        shared["chunk"],
        shared["window"],
        click.option("--no-uncertainty", "no_uncertainty", is_flag=True,
                     help="Leave out sigma_F1..6 and rest (the differentiation's uncertainty "
                          "of F and the legs possibly at rest), its warning and the "
                          "comparison with the log's own rates."),
        click.option("--progress/--no-progress", default=None,
                     help="A progress bar on stderr, with total and ETA [default: when stderr "
                          "is a terminal]."),
        click.option("--quiet", is_flag=True,
                     help="No progress bar and no summary line (warnings and errors still go "
                          "to stderr)."),
        click.option("--columns", default=None, metavar="GROUP[,GROUP...]",
                     help=f"Output groups: {', '.join(COLUMN_GROUPS)}, or all [default: "
                          f"{','.join(DEFAULT_COLUMN_GROUPS)}]; t and flag are always written. "
                          "`gsfric columns` lists every column with its group."),
        click.option("--float32", is_flag=True,
                     help="Write the outputs as float32 (relative error up to 6e-8, half the "
                          "size)."),
        click.option("--breakdown", "breakdown_file", type=path, default=None,
                     help="Also write F per leg split into its parts (inertia, gravity, "
                          "payload, joint friction, prismatic friction by kind, effects) to "
                          "this CSV or Parquet file (kinematic mode; the trajectory is read "
                          "whole)."),
        click.option("--plot", type=path, default=None, metavar="FILE",
                     help="Also write a figure of the actuator forces F and the prismatic "
                          "friction Ffr of every leg over the record (PNG, SVG or PDF by the "
                          "extension; needs matplotlib)."),
        click.option("--keep-flagged", is_flag=True,
                     help=f"Write the output even when more than {100 * FLAGGED_LIMIT:g} % of "
                          "the steps are flagged (above it the run fails, exit 1, no output: "
                          "the platform or the log's frame is likely not the rig's); up to "
                          "half of them."),
        click.option("--verbose", "-v", is_flag=True,
                     help="Name the log's ignored columns (counted in one warning otherwise)."),
    ]
    return with_options(command, options)


@click.command()
@_options
@log_options
@_no_cycle_collection()
@checked_paths({"trajectory": "trajectory", "platform_file": "platform",
                "column_map": "column-map"}, files=("out", "breakdown_file", "plot"))
def simulate(trajectory, platform_file, out, mode, strict, threads, chunk, window,
             no_uncertainty, progress, quiet, columns, float32, breakdown_file, plot,
             keep_flagged, verbose, column_map,
             units_map, angles, keep_columns):
    """Evaluate a motion: actuator forces, reactions and friction at every step.

    The trajectory may be a measured-data file: with F1..F6 the output also has
    F1_measured..F6_measured and F1_residual..F6_residual (measured minus model).
    `gsfric columns` lists every output column with its unit.

    Long files are streamed: read, differentiated and evaluated chunk by chunk in bounded
    memory. Flagged steps (see the flag column) are reported with their share, time ranges
    and indices in one warning at the end; more than 10 % of them flagged fails the run
    unless --keep-flagged, any flagged step with --strict.

    The run ends with a table of the peaks of every leg (|F|, |Ffr|, |R_E|, |R_C|, |M_C|
    over the sound steps, with their times from the record's start), as Result.summary().
    """
    if breakdown_file is not None and mode != "kinematic":
        raise InputError("--breakdown: only in the kinematic mode")
    with warnings.catch_warnings():                    # shown one line each by the group
        warnings.simplefilter("always", UserWarning)   # GsfricWarning, flags, build, staleness
        if verbose:
            _name_ignored_columns()
        log_format = LogFormat.from_options(column_map, units_map, angles, keep_columns)
        platform = platform_from(platform_file)
        with output_group():            # the table, --plot and --breakdown: all or none
            summary = simulate_file(trajectory, out, platform, mode=mode, strict=strict,
                                    chunk=chunk, window=window, n_threads=threads,
                                    progress=False if quiet else progress,
                                    log_format=log_format, columns=parse_columns(columns),
                                    float32=float32, keep_flagged=keep_flagged, plot=plot,
                                    uncertainty=not no_uncertainty)
            if breakdown_file is not None:
                _write_breakdown(trajectory, log_format, platform, breakdown_file)
    if not quiet:
        click.echo(f"wrote {out} ({summary.steps} steps, {summary.flagged} flagged; "
                   f"differentiated by {summary.differentiation})")
        if plot is not None:
            click.echo(f"wrote {plot}")
        if breakdown_file is not None:
            click.echo(f"wrote {breakdown_file}")
        click.echo(summary.peaks.table())
        if summary.rest_steps:
            click.echo(f"{summary.rest_steps} steps with a leg possibly at rest (the rest "
                       "column): friction there is bounded by its Coulomb level")
        if summary.rates is not None:
            click.echo(summary.rates.describe())


def _name_ignored_columns() -> None:
    """``--verbose``: after the warning that counts a log's ignored columns, a line naming
    them (once)."""
    show, named = warnings.showwarning, set()

    def show_names(message, category, *args, **kwargs):
        show(message, category, *args, **kwargs)
        if isinstance(message, IgnoredColumnsWarning) and message.names not in named:
            named.add(message.names)
            click.echo("gsfric: ignored columns: " + ", ".join(map(repr, message.names)),
                       err=True)

    warnings.showwarning = show_names


def _write_breakdown(trajectory, log_format, platform, breakdown_file) -> None:
    """``--breakdown``: F per leg split into its parts along the whole trajectory."""
    motion = read_trajectory(trajectory, log_format=log_format)
    write_table(flat(breakdown(platform, motion)), breakdown_file)
