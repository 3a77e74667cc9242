"""``gsfric synth``: synthetic measured data with hidden effects and noise."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.commands.common import checked_paths, seed_option
from gsfric.synth import run_synth


@click.command()
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Measured-data file to write (CSV or Parquet).")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML of the true system (its [effects] are the hidden effects).")
@click.option("--effect", "effects", multiple=True, metavar="NAME[:param=value,...]",
              help="Hidden effect to add, e.g. stribeck:static=2,velocity=0.01 (repeatable).")
@click.option("--motion", "motion_file", type=click.Path(dir_okay=False, exists=True),
              help="Trajectory file to drive (e.g. `gsfric excite`'s) instead of the random "
                   "motion, its poses as every command reads them (smoothed where they are "
                   "noisy); its times replace --samples and --rate.")
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
@seed_option("the noise")
@checked_paths({"platform_file": "platform", "motion_file": "motion"}, files=("out",))
def synth(out, platform_file, effects, motion_file, samples, rate, noise, noise_correlation,
          pose_noise, seed):
    """Write synthetic measured data with hidden effects and noise (reproducible by seed).

    The motion is a random six-axis motion: the reference platform's, carried over to the
    platform's size. It moves about the platform's home pose (level, legs at mid-stroke); its
    translations scale with the stroke, its rotations with the stroke over the platform's
    radius, and its periods with the square root of the stroke, so that the accelerations
    stay the reference's. At most 1,000,000 samples (the record is held in memory)."""
    given = [f"--{name}" for name in ("samples", "rate") if click.get_current_context()
             .get_parameter_source(name) is not click.core.ParameterSource.DEFAULT]
    if motion_file is not None and given:
        raise click.UsageError(f"{' and '.join(given)}: the --motion file's own times set "
                               "the samples and the rate; leave them out")
    path = run_synth(out, platform_file=platform_file, effects=effects, samples=samples,
                     rate=rate, noise=noise, noise_correlation=noise_correlation,
                     pose_noise=pose_noise, seed=seed, motion_file=motion_file)
    click.echo(f"wrote {path}")
