"""``gsfric excite``: an excitation motion designed for ``gsfric identify``."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.commands.common import checked_paths, seed_option
from gsfric.identification.excite import MAX_ACCELERATION, MAX_SPEED, PERIOD
from gsfric.identification.excite import excite as design
from gsfric.io.files import check_outputs
from gsfric.io.tables import table_kind, write_table
from gsfric.models import platform_from


@click.command()
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML: geometry, stroke and current values (default: the "
                   "reference platform).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Trajectory file to write (CSV or Parquet), as `simulate --trajectory` "
                   "reads it.")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), default=60.0,
              show_default=True, help="Duration, s (rounded up to whole periods).")
@click.option("--rate", type=click.FloatRange(1.0, 1e6), default=500.0, show_default=True,
              help="Sampling rate, Hz.")
@click.option("--period", type=click.FloatRange(min=0, min_open=True), default=PERIOD,
              show_default=True, help="Period of the Fourier series, s.")
@click.option("--max-speed", type=click.FloatRange(min=0, min_open=True), default=MAX_SPEED,
              show_default=True, help="Leg speed limit, m/s.")
@click.option("--max-acceleration", type=click.FloatRange(min=0, min_open=True),
              default=MAX_ACCELERATION, show_default=True,
              help="Leg acceleration limit, m/s^2.")
@click.option("--force-noise", type=click.FloatRange(min=0, min_open=True),
              help="Force noise (N) for the expected standard deviations [default: 0.5 % of "
                   "the mean static actuator force].")
@click.option("--sensors", is_flag=True, help="Include the load cells' offsets and gains.")
@seed_option("the search")
@checked_paths({"platform_file": "platform"}, files=("out",))
def excite(platform_file, out, duration, rate, period, max_speed, max_acceleration,
           force_noise, sensors, seed):
    """Design an excitation motion that identifies the platform's parameters well.

    A finite Fourier series per pose coordinate, at rest at both ends, within the stroke and
    the leg speed and acceleration limits, chosen for D-optimality; prints the expected
    standard deviation of each parameter and the condition number against a plain sinusoid.
    """
    check_outputs([out], {"platform": platform_file})
    table_kind(out)
    result = design(platform_from(platform_file), duration=duration, rate=rate,
                    period=period, max_speed=max_speed, max_acceleration=max_acceleration,
                    force_noise=force_noise, sensors=sensors, seed=seed)
    write_table(result.motion.to_frame(), out)
    click.echo(f"wrote {out}")
    click.echo(result.report())
