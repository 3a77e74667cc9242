"""``gsfric identify``: a rig's parameters, with uncertainty, from a measured record."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.commands.common import checked_paths, force_noise_values, log_options
from gsfric.identification.files import identify_file, write_outputs
from gsfric.io.files import check_output_folder
from gsfric.io.logs import LogFormat


@click.command()
@click.option("--measured", type=click.Path(dir_okay=False, exists=True), required=True,
              help="Measured data: trajectory columns plus F1..F6 (e.g. along a motion from "
                   "`gsfric excite`).")
@click.option("--platform", "platform_file", type=click.Path(dir_okay=False, exists=True),
              help="Platform TOML to start from: its geometry, and the values the motion "
                   "cannot identify (default: the reference platform).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Directory for platform.toml and identification.json.")
@click.option("--validate", "validate_file", type=click.Path(dir_okay=False, exists=True),
              help="A second measured record: the prediction error on it before and after.")
@click.option("--sensors", is_flag=True,
              help="Also identify the load cells' offsets and gains.")
@click.option("--force-noise", metavar="N|N1,...,N6",
              help="The load cells' noise (standard deviation, N), one value or six [default: "
                   "estimated from the fit's residual].")
@log_options(keep=False)
@checked_paths({"measured": "measured-data", "platform_file": "platform",
                "validate_file": "validation record", "column_map": "column-map"},
               folders=("out_dir",))
def identify(measured, platform_file, out_dir, validate_file, sensors, force_noise,
             column_map, units_map, angles):
    """Identify the platform's masses, inertias, friction and effects from a measured record.

    Writes platform.toml (the identified values, 95 % intervals in comments, the record's
    SHA-256) and identification.json (each parameter's value, std, unit and whether the
    motion identifies it), and prints what the motion cannot identify and why.
    """
    log_format = LogFormat.from_options(column_map, units_map, angles, None)
    check_output_folder(out_dir)
    result = identify_file(measured, platform_file, validate_file=validate_file,
                           sensors=sensors, force_noise=force_noise_values(force_noise),
                           log_format=log_format)
    inputs = {"measured-data": measured, "platform": platform_file,
              "validation record": validate_file}
    for path in write_outputs(result, out_dir, inputs=inputs):
        click.echo(f"wrote {path}")
    if result.validation is not None:
        v = result.validation
        left = f"; {v.flagged} flagged steps left out" if v.flagged else ""
        click.echo(f"validation on {v.source}: {_rms(v.before):.4g} N RMS before, "
                   f"{_rms(v.after):.4g} N after (noise {_rms(v.noise):.4g} N{left})")
    click.echo(result.statement())


def _rms(values) -> float:
    return float((sum(v * v for v in values) / len(values)) ** 0.5)
