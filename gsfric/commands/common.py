"""What the commands share: exit codes, one-line errors, and the options of a log's format.

Exit codes: 0 success; ``EXIT_CHECK`` (1) a check failed; ``EXIT_INPUT`` (2) bad input or usage;
``EXIT_INTERNAL`` (3) an internal or build failure; ``EXIT_PIPE`` (141) the reader of stdout
went away. See ``gsfric.cli`` and docs/explanation/robustness.md.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable, Mapping
from pathlib import Path

import click

from gsfric.errors import InputError
from gsfric.io.files import check_run_paths, trajectory_files

EXIT_CHECK = 1
EXIT_INPUT = 2
EXIT_INTERNAL = 3
EXIT_PIPE = 128 + 13


def fail(message: str, code: int = EXIT_INPUT) -> None:
    """Print ``gsfric: error: message`` on stderr and exit with ``code``."""
    click.echo(f"gsfric: error: {message}", err=True)
    sys.exit(code)


def log_options(command=None, *, keep=True):
    """--column-map, --units, --angles, --keep-columns: how to read a log (gsfric.io.LogFormat)."""
    if command is None:
        return lambda c: log_options(c, keep=keep)
    options = [
        click.option("--column-map", metavar="FILE.toml|NAME=COLUMN,...",
                     help="The log's column for each gsfric column, e.g. "
                          "'t=C2H time (us),x=pos_x,roll=Roll'; or a TOML file with a "
                          "[columns] table (and [units], angles, wrap, keep, the controller's "
                          "frame: axes, [offset]; the log's own rates: vx..vz, omega_x.., "
                          "ax.., alpha_x..). See docs/howto/read-a-log.md."),
        click.option("--units", "units_map", metavar="NAME=UNIT,...",
                     help="Units of the log's columns, by gsfric name, e.g. "
                          "'t=us,x=mm,y=mm,z=mm,roll=deg' (s ms us ns; m cm mm um; rad deg "
                          "mrad; N kN; m/s mm/s; rad/s deg/s; m/s^2 mm/s^2 g) [default: SI]."),
        click.option("--angles", type=click.Choice(["xyz", "XYZ"]), default=None,
                     help="Convention of roll, pitch, yaw columns: xyz extrinsic "
                          "(R = Rz(yaw) Ry(pitch) Rx(roll)) or XYZ intrinsic "
                          "(R = Rx(roll) Ry(pitch) Rz(yaw)) [default: xyz]."),
        click.option("--keep-columns", metavar="COLUMN,...",
                     help="Log columns to copy unchanged into the output (other columns that "
                          "are not gsfric inputs are ignored, with a note)."),
    ][:None if keep else 3]
    return with_options(command, options)


def seed_option(what: str):
    """``--seed``: a non-negative integer (NumPy's generators take no negative seed), 0 by
    default; ``what`` says what it seeds."""
    return click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True,
                        help=f"Seed of {what} (an integer >= 0; the same seed, the same result).")


def with_options(command, options: list[Callable]):
    """``command`` decorated with the click ``options``, listed in the order --help shows them."""
    for option in reversed(options):
        command = option(command)
    return command


def checked_paths(reads: Mapping[str, str], files: tuple[str, ...] = (),
                  folders: tuple[str | Callable[[dict], object], ...] = ()):
    """Decorate a command's callback with the one check of its paths
    (``gsfric.io.files.check_run_paths``), run before the command reads anything: no input
    is an output or lies inside an output folder.

    ``reads`` maps each option (callback argument) the command reads files from to what the
    messages call it ("trajectory", "column-map"...): a path, several (``--trajectories``
    globs, expanded as ``sweep`` does) or a ``--column-map`` (a path when it names a .toml
    file). ``files`` and ``folders`` name the output options; a folder may also be given as
    a function of the arguments (``sweep``'s ``OUT.partial``).
    """
    def decorate(callback):
        @functools.wraps(callback)
        def run(**kwargs):
            inputs = [(what, path) for name, what in reads.items()
                      for path in _read_paths(name, kwargs.get(name))]
            dirs = [f(kwargs) if callable(f) else kwargs.get(f) for f in folders]
            check_run_paths(inputs, [kwargs.get(f) for f in files], dirs)
            return callback(**kwargs)
        return run
    return decorate


def _read_paths(name: str, value) -> list:
    """The files an input option's value names (none for an inline ``--column-map``)."""
    if value is None or value == ():
        return []
    if name == "column_map":
        return [value] if str(value).lower().endswith(".toml") else []
    if name == "trajectories":
        return trajectory_files(list(value))
    return [value]


def partial_of(name: str) -> Callable[[dict], Path | None]:
    """The ``OUT.partial`` folder of the output folder option ``name`` (``sweep``)."""
    def partial(kwargs: dict) -> Path | None:
        out = kwargs.get(name)
        return None if out is None else Path(out).with_name(Path(out).name + ".partial")
    return partial


def force_noise_values(text: str | None) -> list[float] | None:
    """``--force-noise``'s numbers (one or six, by commas); InputError for anything else."""
    if text is None:
        return None
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"--force-noise: one number (N) or six separated by commas, got "
                         f"{text!r}") from None


def evaluation_options() -> dict[str, Callable]:
    """The options of a command that evaluates a trajectory file as ``simulate`` does
    (``simulate``, ``view``), by name: platform, mode, threads, chunk, window."""
    return {
        "platform": click.option("--platform", "platform_file", type=click.Path(path_type=Path),
                                 help="Platform TOML (default: the reference platform)."),
        "mode": click.option(
            "--mode", type=click.Choice(["kinematic", "paper"]), default="kinematic",
            show_default=True,
            help="kinematic: velocities and accelerations differentiated from the motion; "
                 "paper: the paper's constant accelerations (its Tables 1-3)."),
        "threads": click.option("--threads", type=click.IntRange(1, 64), default=1,
                                show_default=True,
                                help="Threads of the compiled evaluation."),
        "chunk": click.option(
            "--chunk", type=int, default=100_000, show_default=True,
            help="Steps read and differentiated at a time (memory grows with it, about 1.3 kB "
                 "a step; they are evaluated 50,000 at a time); a file of at most this many "
                 "rows is read whole."),
        "window": click.option(
            "--window", type=int, default=None,
            help="Savitzky-Golay window, odd, samples; jittered time stamps are taken as evenly "
                 "spaced unless the poses look noisier on the even grid than on the stamps, "
                 "and are then fitted with polynomials of this window on their own stamps "
                 "[default: a filter per sample for a file read whole, one window by "
                 "cross-validation on the first chunk for a streamed one]."),
    }
