"""The ``gsfric`` command line.

Every command has ``--help``. Exit codes: 0 success; 1 a check failed (``derive --check``
found generated/ stale, ``simulate --strict`` found flagged steps); 2 bad input or usage (a
one-line reason on stderr); 3 an internal or build failure (also a full disk); 128 + the
signal number when stopped by SIGINT (130), SIGHUP (129) or SIGTERM (143), after removing the
temporary outputs; 141 when the reader of stdout went away (``gsfric bench | head``), quietly.
See docs/robustness.md.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
from pathlib import Path

import click

from gsfric.evaluation.columns import DEFAULT_GROUPS as DEFAULT_COLUMN_GROUPS
from gsfric.evaluation.columns import GROUPS as COLUMN_GROUPS

EXIT_CHECK = 1
EXIT_INPUT = 2
EXIT_INTERNAL = 3
EXIT_PIPE = 128 + 13

_STOP_SIGNALS = ("SIGTERM", "SIGHUP")


class _StopSignals:
    """While entered, SIGTERM and SIGHUP raise ``Interrupted`` in the main thread, and SIGINT
    KeyboardInterrupt (unless it is ignored), so that temporary outputs and compiler processes
    are cleaned up.

    ``received`` keeps the first stop signal that arrived, and ``check`` raises it again: one
    that lands inside an extension module's import comes out as an ImportError that does not
    chain the exception raised here, and one raised inside a callback is only reported.
    """

    def __init__(self):
        self.received: int | None = None
        self._previous = {}

    def _handle(self, signum, frame):
        from gsfric.errors import Interrupted

        if self.received is None:
            self.received = signum
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Interrupted(signum)

    def __enter__(self):
        for name in (*_STOP_SIGNALS, "SIGINT"):
            number = getattr(signal, name, None)
            if number is None:
                continue
            if name == "SIGINT" and signal.getsignal(number) is not signal.default_int_handler:
                continue                          # ignored (a background job): keep it so
            with contextlib.suppress(ValueError, OSError):   # not the main thread
                self._previous[number] = signal.signal(number, self._handle)
        return self

    def check(self) -> None:
        """Raise the stop if one arrived (``gsfric.io.commit_check``): its own exception may
        have been swallowed, raised inside a callback that the interpreter only reports."""
        from gsfric.errors import Interrupted

        if self.received == signal.SIGINT:
            raise KeyboardInterrupt
        if self.received is not None:
            raise Interrupted(self.received)

    def __exit__(self, *exc_info):
        for number, handler in self._previous.items():
            with contextlib.suppress(ValueError, OSError):
                signal.signal(number, handler)
        return False


@contextlib.contextmanager
def _one_line_warnings():
    """Warnings (a rebuilt cache, implausible units, the CasADi fallback) as one line each."""
    import warnings

    def show(message, category, filename, lineno, file=None, line=None):
        click.echo(f"gsfric: warning: {message}", err=True)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield


@contextlib.contextmanager
def _no_cycle_collection():
    """No cycle collection inside, and the objects left at exit frozen (``simulate``, whose
    imports it covers as a decorator).

    A streamed run makes no cyclic garbage to speak of, while its imports (SciPy, pandas,
    pyarrow) create objects that every collection would walk again, and the interpreter's exit
    would walk them once more: together a tenth of the CPU time of a million-step run.
    """
    import atexit
    import gc

    collecting = gc.isenabled()
    gc.disable()
    atexit.unregister(gc.freeze)
    atexit.register(gc.freeze)
    try:
        yield
    finally:
        if collecting:
            gc.enable()


def _quiet_broken_pipe() -> None:
    """stdout's reader went away: send the rest to /dev/null and exit 141 without a word."""
    with contextlib.suppress(OSError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    sys.exit(EXIT_PIPE)


def _fail(message: str, code: int = EXIT_INPUT) -> None:
    click.echo(f"gsfric: error: {message}", err=True)
    sys.exit(code)


class _Group(click.Group):
    """Turns the library's errors into one-line messages and exit codes."""

    def invoke(self, ctx):
        from gsfric.errors import GsfricError, InputError, Interrupted, StepFlagError
        from gsfric.io.files import commit_check

        stops = _StopSignals()
        try:
            with stops, commit_check(stops.check), _one_line_warnings():
                result = super().invoke(ctx)
                stops.check()            # a stop the run went on through never succeeds
                return result
        except Interrupted as exc:
            name = signal.Signals(exc.signum).name
            _fail(f"stopped by {name}; no output was left half-written", 128 + exc.signum)
        except BrokenPipeError:
            _quiet_broken_pipe()
        except InputError as exc:
            _fail(str(exc), EXIT_INPUT)
        except StepFlagError as exc:
            _fail(str(exc), EXIT_CHECK)
        except GsfricError as exc:
            _fail(str(exc), EXIT_INTERNAL)
        except KeyboardInterrupt:
            _fail("interrupted; no output was left half-written", 130)
        except OSError as exc:
            where = f"{exc.filename}: " if exc.filename else ""
            _fail(f"{where}{exc.strerror or exc}", EXIT_INTERNAL)
        except Exception as exc:
            # a stop signal that arrived inside an import or a cleanup comes out as the error
            # it caused there (an ImportError, chained to the stop or not): still a stop
            stop = _stop_in_chain(exc)
            signum = getattr(stop, "signum", signal.SIGINT) if stop else stops.received
            if signum is None:
                raise
            if signum == signal.SIGINT:
                _fail("interrupted; no output was left half-written", 130)
            name = signal.Signals(signum).name
            _fail(f"stopped by {name}; no output was left half-written", 128 + signum)

    def main(self, args=None, prog_name=None, **kwargs):
        """Usage errors (unknown option, missing argument) as one line too, exit 2."""
        try:
            result = super().main(args, prog_name, standalone_mode=False, **kwargs)
            sys.stdout.flush()
            return result
        except BrokenPipeError:
            _quiet_broken_pipe()
        except click.exceptions.NoArgsIsHelpError as exc:
            click.echo(exc.ctx.get_help(), err=True)
            sys.exit(EXIT_INPUT)
        except click.UsageError as exc:
            hint = f" (see `gsfric {exc.ctx.info_name} --help`)" if exc.ctx and \
                exc.ctx.parent else " (see `gsfric --help`)"
            _fail(exc.format_message().replace("\n", " ") + hint, EXIT_INPUT)
        except click.exceptions.Exit as exc:
            sys.exit(exc.exit_code)
        except click.Abort:
            _fail("aborted", EXIT_CHECK)
        except click.ClickException as exc:
            _fail(exc.format_message(), EXIT_INPUT)


def _stop_in_chain(exc: BaseException) -> BaseException | None:
    """The Interrupted or KeyboardInterrupt among the causes and contexts of ``exc``, if any."""
    from gsfric.errors import Interrupted

    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, (Interrupted, KeyboardInterrupt)):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def _log_options(command=None, *, keep=True):
    """--column-map, --units, --angles, --keep-columns: how to read a log (gsfric.io.LogFormat)."""
    if command is None:
        return lambda c: _log_options(c, keep=keep)
    options = [
        click.option("--column-map", metavar="FILE.toml|NAME=COLUMN,...",
                     help="The log's column for each gsfric column, e.g. "
                          "'t=C2H time (us),x=pos_x,roll=Roll'; or a TOML file with a "
                          "[columns] table (and [units], angles, wrap, keep). See docs/logs.md."),
        click.option("--units", "units_map", metavar="NAME=UNIT,...",
                     help="Units of the log's columns, by gsfric name, e.g. "
                          "'t=us,x=mm,y=mm,z=mm,roll=deg' (s ms us ns; m cm mm um; rad deg "
                          "mrad; N kN) [default: SI]."),
        click.option("--angles", type=click.Choice(["xyz", "XYZ"]), default=None,
                     help="Convention of roll, pitch, yaw columns: xyz extrinsic "
                          "(R = Rz(yaw) Ry(pitch) Rx(roll)) or XYZ intrinsic "
                          "(R = Rx(roll) Ry(pitch) Rz(yaw)) [default: xyz]."),
        click.option("--keep-columns", metavar="COLUMN,...",
                     help="Log columns to copy unchanged into the output (other columns that "
                          "are not gsfric inputs are ignored, with a note)."),
    ][:None if keep else 3]
    for option in reversed(options):
        command = option(command)
    return command


def _log_format(column_map, units_map, angles, keep_columns):
    from gsfric.io.logs import LogFormat

    return LogFormat.from_options(column_map, units_map, angles, keep_columns)


def _platform(path):
    from gsfric.models import reference_platform
    from gsfric.platform.description import Platform

    return reference_platform() if path is None else Platform.from_toml(path)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="gsfric")
def main():
    """Reaction forces and friction in every joint of a Gough-Stewart platform."""


@main.command()
@click.option("--check", is_flag=True, help="Exit 1 if generated/ is stale; write nothing.")
def derive(check):
    """Regenerate generated/ from the SymPy derivation in derive/ (needs sympy).

    derive/ is not installed with gsfric (a wheel carries only its output, generated/): this
    command runs in a source checkout, e.g. after `pip install -e ".[derive]"` there.
    """
    checkout = Path(__file__).resolve().parent.parent
    if not (checkout / "derive" / "build.py").is_file():
        _fail("`gsfric derive` needs a source checkout of gsfric (derive/ and generated/ are "
              "not installed, only the generated model is): clone the repository and run "
              "`pip install -e \".[derive]\"` there")
    if str(checkout) not in sys.path:
        sys.path.insert(0, str(checkout))
    try:
        from derive import build
    except ImportError as exc:
        _fail(f"the derivation needs sympy ({exc}); install it with "
              "`pip install -e \".[derive]\"` in the checkout")
    if check:
        reason = build.is_stale()
        if reason:
            click.echo(f"generated/ is stale: {reason}; run `gsfric derive`", err=True)
            sys.exit(EXIT_CHECK)
        click.echo("generated/ is up to date")
        return
    build.write(build.generate())
    click.echo(f"wrote {build.GENERATED}")


@main.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Directory for tables, report, plots and platform.toml.")
@click.option("--mode", type=click.Choice(["paper", "kinematic"]), default="paper",
              show_default=True,
              help="paper: the paper's constant accelerations; kinematic: from the motion.")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML (default: the paper's reference platform).")
@click.option("--no-plots", is_flag=True, help="Skip the plots.")
def paper(out_dir, mode, platform_file, no_plots):
    """Run the paper's 40-step motion and write Tables 1-3, a report and plots."""
    from gsfric.paper.report import run_paper

    written = run_paper(out_dir, mode=mode, platform_file=platform_file, plots=not no_plots)
    for path in written:
        click.echo(f"wrote {path}")


@main.command()
@click.option("--trajectory", type=click.Path(path_type=Path), required=True,
              help="Trajectory or measured-data file (CSV or Parquet): t,x,y,z with "
                   "alpha,beta,gamma, qw,qx,qy,qz or roll,pitch,yaw; other names and units "
                   "with --column-map and --units.")
@click.option("--platform", "platform_file", type=click.Path(path_type=Path),
              help="Platform TOML (default: the reference platform).")
@click.option("--out", type=click.Path(path_type=Path), required=True,
              help="Output file, CSV or Parquet by extension; written to a temporary file "
                   "and renamed when complete.")
@click.option("--mode", type=click.Choice(["kinematic", "paper"]), default="kinematic",
              show_default=True,
              help="kinematic: velocities and accelerations differentiated from the motion; "
                   "paper: the paper's constant accelerations (its Tables 1-3).")
@click.option("--strict", is_flag=True,
              help="Fail (exit 1, no output) at the first chunk with a flagged step.")
@click.option("--threads", type=click.IntRange(1, 64), default=1, show_default=True,
              help="Threads of the compiled evaluation (OpenMP).")
@click.option("--chunk", type=int, default=100_000, show_default=True,
              help="Steps read, differentiated and evaluated at a time (memory grows with "
                   "it); a file of at most this many rows is read whole.")
@click.option("--window", type=int, default=None,
              help="Savitzky-Golay window, odd, samples [default: a filter per sample for a "
                   "file read whole, one window by cross-validation on the first chunk for a "
                   "streamed one].")
@click.option("--progress/--no-progress", default=None,
              help="A progress bar on stderr, with total and ETA [default: when stderr is a "
                   "terminal].")
@click.option("--quiet", is_flag=True,
              help="No progress bar and no summary line (warnings and errors still go to "
                   "stderr).")
@click.option("--columns", default=None, metavar="GROUP[,GROUP...]",
              help=f"Output groups: {', '.join(COLUMN_GROUPS)}, or all [default: "
                   f"{','.join(DEFAULT_COLUMN_GROUPS)}]; t and flag are always written. "
                   "`gsfric columns` lists every column with its group.")
@click.option("--float32", is_flag=True,
              help="Write the outputs as float32 (relative error up to 6e-8, half the size).")
@click.option("--breakdown", "breakdown_file", type=click.Path(path_type=Path), default=None,
              help="Also write F per leg split into its parts (inertia, gravity, payload, "
                   "joint friction, prismatic friction by kind, effects) to this CSV or "
                   "Parquet file (kinematic mode; the trajectory is read whole).")
@_log_options
@_no_cycle_collection()
def simulate(trajectory, platform_file, out, mode, strict, threads, chunk, window, progress,
             quiet, columns, float32, breakdown_file, column_map, units_map, angles, keep_columns):
    """Evaluate a motion: actuator forces, reactions and friction at every step.

    The trajectory may be a measured-data file: with F1..F6 the output also has
    F1_measured..F6_measured and F1_residual..F6_residual (measured minus model).
    `gsfric columns` lists every output column with its unit.

    Long files are streamed: read, differentiated and evaluated chunk by chunk in bounded
    memory. Flagged steps (see the flag column) are reported with their indices in one
    warning at the end, or make the run fail with --strict.
    """
    import warnings

    from gsfric.simulate.stream import parse_columns, simulate_file

    if breakdown_file is not None and mode != "kinematic":
        from gsfric.errors import InputError

        raise InputError("--breakdown: only in the kinematic mode")

    with warnings.catch_warnings():                    # shown one line each by _Group
        warnings.simplefilter("always", UserWarning)   # GsfricWarning, flags, build, staleness
        log_format = _log_format(column_map, units_map, angles, keep_columns)
        platform = _platform(platform_file)
        summary = simulate_file(trajectory, out, platform, mode=mode, strict=strict,
                                chunk=chunk, window=window, n_threads=threads,
                                progress=False if quiet else progress,
                                log_format=log_format, columns=parse_columns(columns),
                                float32=float32)
        if breakdown_file is not None:
            from gsfric import io
            from gsfric.evaluation.breakdown import to_frame
            from gsfric.evaluation.evaluator import breakdown

            motion = io.read_trajectory(trajectory, log_format=log_format)
            io.write_table(to_frame(motion.t, breakdown(platform, motion)), breakdown_file)
            if not quiet:
                click.echo(f"wrote {breakdown_file}")
    if not quiet:
        click.echo(f"wrote {out} ({summary.steps} steps, {summary.flagged} flagged)")


@main.command()
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
@_log_options(keep=False)
def discover(measured, platform_file, out_dir, seed, progress, quiet, column_map, units_map,
             angles):
    """Find which physical effect the model is missing, fit it, and show the gap shrink."""
    from gsfric.discovery import run_discover

    show = False if quiet else sys.stderr.isatty() if progress is None else progress
    log_format = _log_format(column_map, units_map, angles, None)
    written = run_discover(measured, platform_file, out_dir, seed=seed, progress=show,
                           **({"log_format": log_format} if log_format else {}))
    if not quiet:
        for path in written:
            click.echo(f"wrote {path}")


@main.command()
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Measured-data file to write (CSV or Parquet).")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML of the true system (its [effects] are the hidden effects).")
@click.option("--effect", "effects", multiple=True, metavar="NAME[:param=value,...]",
              help="Hidden effect to add, e.g. stribeck:static=2,velocity=0.01 (repeatable).")
@click.option("--samples", type=click.IntRange(20), default=4000, show_default=True,
              help="Number of samples (rows) to write.")
@click.option("--rate", type=click.FloatRange(1.0, 1e6), default=200.0, show_default=True,
              help="Sampling rate, Hz (1 Hz to 1 MHz).")
@click.option("--noise", type=float, default=0.1, show_default=True,
              help="Force noise standard deviation, N.")
@click.option("--noise-correlation", type=click.FloatRange(0, 0.999), default=0.0,
              show_default=True, help="AR(1) coefficient of the force noise (0: white).")
@click.option("--pose-noise", type=float, default=0.0, show_default=True,
              help="Position noise standard deviation, m (angles: the same number in rad).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the noise (the same seed gives the same file).")
def synth(out, platform_file, effects, samples, rate, noise, noise_correlation, pose_noise,
          seed):
    """Write synthetic measured data with hidden effects and noise (reproducible by seed)."""
    from gsfric.synth import run_synth

    path = run_synth(out, platform_file=platform_file, effects=effects, samples=samples,
                     rate=rate, noise=noise, noise_correlation=noise_correlation,
                     pose_noise=pose_noise, seed=seed)
    click.echo(f"wrote {path}")


@main.command()
@click.option("--quick", is_flag=True, help="Small sizes only (N = 40 and 1e3).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path),
              help="Also write the table as JSON.")
def bench(quick, out):
    """Print the throughput table: compiled vs NumPy-vectorised vs per-step loop."""
    from gsfric.bench.throughput import run_bench

    run_bench(quick=quick, out=out)


def _pairs(values, option, ranged):
    """``NAME=MIN:MAX`` (ranged) or ``NAME=VALUE`` options as a dict; one-line errors."""
    out = {}
    for text in values:
        name, sep, rest = text.partition("=")
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
            _fail(f"{option}: expected {form}, got {text!r}")
    return out


@main.command()
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
@click.option("--variants", type=click.IntRange(1), default=16, show_default=True,
              help="Variants drawn besides the nominal one (with --vary or --tolerance).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the variants.")
@click.option("--scheduler", default=None, metavar="auto|serial|local|tcp://HOST:PORT",
              help="Where tasks run [default: DASK_SCHEDULER_ADDRESS if set, else serial for "
                   "small sweeps and a local cluster of one process per core].")
@click.option("--workers", type=click.IntRange(1, 256), default=None,
              help="Worker processes of the local cluster [default: one per core].")
@click.option("--chunk-steps", type=click.IntRange(1), default=None,
              help="Evaluated steps per task [default: 1000000, a second or more].")
@click.option("--progress/--no-progress", default=None,
              help="Progress bar with total and ETA [default: when stderr is a terminal].")
@click.option("--no-plots", is_flag=True, help="Skip the plots.")
@click.option("--strict", is_flag=True, help="Exit 1 when a case exceeds the [limits].")
def sweep(out_dir, trajectories, workspace, platform_file, vary, tolerance, variants, seed,
          scheduler, workers, chunk_steps, progress, no_plots, strict):
    """Load envelopes per joint over motions, a workspace and platform variants.

    Writes envelopes.parquet (per case, quantity and leg, with where each extreme occurs),
    summary.csv, variants.csv, limits.csv (cases beyond the platform's [limits]), sweep.json
    and plots. See docs/sizing.md.
    """
    from gsfric.sweep import sweep as sw

    result = sw.sweep(out_dir, trajectories=list(trajectories) or None, workspace=workspace,
                      platform=platform_file, vary=_pairs(vary, "--vary", True),
                      tolerances=_pairs(tolerance, "--tolerance", False), variants=variants,
                      seed=seed, scheduler=scheduler, workers=workers,
                      chunk_steps=chunk_steps or sw.CHUNK_STEPS, progress=progress,
                      plots=not no_plots)
    info = result.info
    click.echo(f"wrote {result.out} ({info['cases']} cases, {info['steps']} steps, "
               f"{info['flagged']} flagged)")
    top = result.most_loaded("R_C")
    click.echo(f"most loaded universal joint: leg {int(top.leg)}, |R_C| = {top.value:.4g} N "
               f"({top.motion}, variant {int(top.variant)}, step {int(top.step)})")
    if info["limits"]:
        n = info["exceeding_cases"]
        click.echo(f"limits: {n} case(s) exceed them" + (f" (see {result.out / 'limits.csv'})"
                                                          if n else ""))
        if n and strict:
            sys.exit(EXIT_CHECK)
@main.command()
@click.option("--markdown", is_flag=True, help="As the Markdown table of the README.")
@click.option("--no-measured", is_flag=True,
              help="Leave out the columns added for a measured-data input.")
def columns(markdown, no_measured):
    """List every output column of `simulate` with its unit and sign convention."""
    from gsfric.evaluation import columns as cols

    text = cols.markdown_table(not no_measured) if markdown else cols.listing(not no_measured)
    click.echo(text)


@main.command()
def effects():
    """List the catalog of optional effects, with their parameters, defaults and units.

    Switch one on in a platform's [effects] table, e.g. stribeck = { static = 2.0 }, or hide it
    in synthetic data with `gsfric synth --effect stribeck:static=2`.
    """
    from gsfric.platform.catalog import describe

    for effect in describe():
        click.echo(f"{effect['name']}: {effect['description']}")
        for p in effect["parameters"]:
            unit = p["unit"] or "1"
            click.echo(f"    {p['name']} = {p['default']:g} {unit}  ({p['description']})")


@main.command()
@click.option("--template", is_flag=True, required=True,
              help="Write a commented, minimal platform TOML (the reference platform's "
                   "values, units in the comments).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path),
              help="File to write [default: standard output].")
def platform(template, out):
    """Write a platform file to start from: `gsfric platform --template --out my.toml`."""
    text = _platform_template()
    if out is None:
        click.echo(text, nl=False)
        return
    from gsfric.io.files import atomic_write

    with atomic_write(out, "w") as handle:
        handle.write(text)
    click.echo(f"wrote {out}")


def _platform_template() -> str:
    """The reference platform as a commented TOML: what `Platform.from_toml` needs, with units."""
    from gsfric.models import reference_platform

    p = reference_platform()
    g = p.geometry

    def rows(a):
        return "\n".join(f"    [{', '.join(repr(float(v)) for v in row)}]," for row in a)

    def matrix(a):
        return "[" + ", ".join("[" + ", ".join(repr(float(v)) for v in row) + "]"
                               for row in a) + "]"

    stroke = "" if g.stroke is None else (
        f"stroke = [{g.stroke[0]:.6g}, {g.stroke[1]:.6g}]   # m, shortest and longest leg "
        "(steps outside are flagged)\n")
    b, f = p.platform, p.friction
    return f"""# A gsfric platform (SI units, angles in rad). Read with `gsfric simulate --platform FILE`
# or gsfric.Platform.from_toml(FILE). Required: [geometry] base_joints, platform_joints and
# [platform] mass, inertia; everything else has the default shown. `gsfric effects` lists
# the optional [effects].

gravity = {p.gravity:g}                 # m/s^2, along -z of the base frame

[geometry]
# C_i, the universal joints, in the base frame (m), one row per leg 1..6
base_joints = [
{rows(g.base_joints)}
]
# E_i, the spherical joints, in the platform frame (m), leg i joins C_i and E_i
platform_joints = [
{rows(g.platform_joints)}
]
{stroke}
[platform]
mass = {b.mass:g}                     # kg, the moving platform
inertia = [[{b.inertia[0, 0]:g}, 0, 0], [0, {b.inertia[1, 1]:g}, 0], [0, 0, {b.inertia[2, 2]:g}]]   # kg m^2, about its centre of mass, platform frame
payload_mass = {b.payload_mass:g}              # kg, at payload_com (platform frame, m)

[legs]
model = "{p.legs.model}"                # "rigid", or "paper": the paper's zone centres at 0.25 D and 0.75 D
lower_mass = {p.legs.lower_mass:g}               # kg, moves with the universal joint
lower_com = {p.legs.lower_com:g}                # m from C_i along the leg (rigid model)
lower_inertia = {matrix(p.legs.lower_inertia)}   # kg m^2, leg body frame (z along the leg)
upper_mass = {p.legs.upper_mass:g}               # kg, moves with the spherical joint end
upper_com = {p.legs.upper_com:g}                # m from E_i along the leg (rigid model)
upper_inertia = {matrix(p.legs.upper_inertia)}   # kg m^2, leg body frame

[friction]
joint_viscous = {f.joint_viscous:g}          # c_s, N m s/rad, spherical and universal joints
joint_coulomb = {f.joint_coulomb:g}          # mu, 1
joint_radius = {f.joint_radius:g}           # r, m
prismatic_viscous = {f.prismatic_viscous:g}      # N s/m
prismatic_coulomb = {f.prismatic_coulomb:g}      # mu, 1
model = "{f.model}"               # "paper": post-hoc, (35) with R_3; "coupled": friction loads the actuators
bushing_offset = {f.bushing_offset:g}          # m, first bushing from C_i (coupled model)
bushing_spacing = {f.bushing_spacing:g}         # m, between the two bushings (coupled model)
prismatic_seal = {f.prismatic_seal:g}           # N, seal friction (coupled model)

[effects]                       # none switched on; e.g. stribeck = {{ static = 2.0, velocity = 0.01 }}
"""


if __name__ == "__main__":
    main()
