"""The ``gsfric`` command line.

Every command has ``--help``. Exit codes: 0 success; 1 a check failed (``derive --check``
found generated/ stale, ``simulate --strict`` found flagged steps); 2 bad input or usage (a
one-line reason on stderr); 3 an internal or build failure.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

EXIT_CHECK = 1
EXIT_INPUT = 2
EXIT_INTERNAL = 3


def _fail(message: str, code: int = EXIT_INPUT) -> None:
    click.echo(f"gsfric: error: {message}", err=True)
    sys.exit(code)


class _Group(click.Group):
    """Turns the library's errors into one-line messages and exit codes."""

    def invoke(self, ctx):
        from gsfric.errors import GsfricError, InputError, StepFlagError

        try:
            return super().invoke(ctx)
        except InputError as exc:
            _fail(str(exc), EXIT_INPUT)
        except StepFlagError as exc:
            _fail(str(exc), EXIT_CHECK)
        except GsfricError as exc:
            _fail(str(exc), EXIT_INTERNAL)
        except KeyboardInterrupt:
            _fail("interrupted; no output was left half-written", 130)

    def main(self, args=None, prog_name=None, **kwargs):
        """Usage errors (unknown option, missing argument) as one line too, exit 2."""
        try:
            return super().main(args, prog_name, standalone_mode=False, **kwargs)
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


def _platform(path):
    from gsfric.models import reference_platform
    from gsfric.platform import Platform

    return reference_platform() if path is None else Platform.from_toml(path)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="gsfric")
def main():
    """Reaction forces and friction in every joint of a Gough-Stewart platform."""


@main.command()
@click.option("--check", is_flag=True, help="Exit 1 if generated/ is stale; write nothing.")
def derive(check):
    """Regenerate generated/ from the SymPy derivation in derive/ (needs sympy)."""
    try:
        from derive import build
    except ImportError as exc:
        _fail(f"the derivation needs the derive/ sources and sympy ({exc}); "
              "install with `pip install -e .[derive]` from the repository")
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
    from gsfric.paper import run_paper

    written = run_paper(out_dir, mode=mode, platform_file=platform_file, plots=not no_plots)
    for path in written:
        click.echo(f"wrote {path}")


@main.command()
@click.option("--trajectory", type=click.Path(path_type=Path), required=True,
              help="Trajectory file (CSV or Parquet): t,x,y,z,alpha,beta,gamma or "
                   "t,x,y,z,qw,qx,qy,qz.")
@click.option("--platform", "platform_file", type=click.Path(path_type=Path),
              help="Platform TOML (default: the reference platform).")
@click.option("--out", type=click.Path(path_type=Path), required=True,
              help="Output file, CSV or Parquet by extension; written to a temporary file "
                   "and renamed when complete.")
@click.option("--mode", type=click.Choice(["kinematic", "paper"]), default="kinematic",
              show_default=True)
@click.option("--strict", is_flag=True,
              help="Fail (exit 1, no output) at the first chunk with a flagged step.")
@click.option("--threads", type=click.IntRange(1, 64), default=1, show_default=True)
@click.option("--chunk", type=int, default=100_000, show_default=True,
              help="Steps read, differentiated and evaluated at a time (memory grows with "
                   "it); a file of at most this many rows is read whole.")
@click.option("--window", type=int, default=None,
              help="Savitzky-Golay window, odd, samples [default: chosen by cross-validation "
                   "on the first chunk].")
@click.option("--progress/--no-progress", default=None,
              help="Progress bar on stderr [default: when stderr is a terminal].")
@click.option("--breakdown", "breakdown_file", type=click.Path(path_type=Path), default=None,
              help="Also write F per leg split into its parts (inertia, gravity, payload, "
                   "joint friction, prismatic friction by kind, effects) to this CSV or "
                   "Parquet file (kinematic mode; the trajectory is read whole).")
def simulate(trajectory, platform_file, out, mode, strict, threads, chunk, window, progress,
             breakdown_file):
    """Evaluate a motion: actuator forces, reactions and friction at every step.

    Long files are streamed: read, differentiated and evaluated chunk by chunk in bounded
    memory. Flagged steps (see the flag column) are reported with their indices in one
    warning at the end, or make the run fail with --strict.
    """
    import warnings

    from gsfric.stream import simulate_file

    if breakdown_file is not None and mode != "kinematic":
        from gsfric.errors import InputError

        raise InputError("--breakdown: only in the kinematic mode")

    def show(message, category, filename, lineno, file=None, line=None):
        click.echo(f"gsfric: warning: {message}", err=True)

    with warnings.catch_warnings():
        warnings.simplefilter("always", UserWarning)   # GsfricWarning, flags, build, staleness
        warnings.showwarning = show
        platform = _platform(platform_file)
        summary = simulate_file(trajectory, out, platform, mode=mode, strict=strict,
                                chunk=chunk, window=window, n_threads=threads,
                                progress=progress)
        if breakdown_file is not None:
            from gsfric import breakdown, io

            motion = io.read_trajectory(trajectory)
            parts = breakdown.breakdown(platform, motion)
            io.write_table(breakdown.to_frame(motion.t, parts), breakdown_file)
            click.echo(f"wrote {breakdown_file}")
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
def discover(measured, platform_file, out_dir, seed):
    """Find which physical effect the model is missing, fit it, and show the gap shrink."""
    from gsfric.discovery import run_discover

    written = run_discover(measured, platform_file, out_dir, seed=seed)
    for path in written:
        click.echo(f"wrote {path}")


@main.command()
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Measured-data file to write (CSV or Parquet).")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML of the true system (its [effects] are the hidden effects).")
@click.option("--effect", "effects", multiple=True, metavar="NAME[:param=value,...]",
              help="Hidden effect to add, e.g. stribeck:static=2,velocity=0.01 (repeatable).")
@click.option("--samples", type=click.IntRange(20), default=4000, show_default=True)
@click.option("--rate", type=float, default=200.0, show_default=True, help="Sampling rate, Hz.")
@click.option("--noise", type=float, default=0.1, show_default=True,
              help="Force noise standard deviation, N.")
@click.option("--noise-correlation", type=click.FloatRange(0, 0.999), default=0.0,
              show_default=True, help="AR(1) coefficient of the force noise (0: white).")
@click.option("--pose-noise", type=float, default=0.0, show_default=True,
              help="Position noise standard deviation, m (angles: the same number in rad).")
@click.option("--seed", type=int, default=0, show_default=True)
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
    from gsfric.bench import run_bench

    run_bench(quick=quick, out=out)


if __name__ == "__main__":
    main()
