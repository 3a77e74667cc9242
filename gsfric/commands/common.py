"""What the commands share: exit codes, one-line errors, and the options of a log's format.

Exit codes: 0 success; ``EXIT_CHECK`` (1) a check failed; ``EXIT_INPUT`` (2) bad input or usage;
``EXIT_INTERNAL`` (3) an internal or build failure; ``EXIT_PIPE`` (141) the reader of stdout
went away. See ``gsfric.cli`` and docs/explanation/robustness.md.
"""

from __future__ import annotations

import sys

import click

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
    for option in reversed(options):
        command = option(command)
    return command
