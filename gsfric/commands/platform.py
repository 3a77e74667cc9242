"""``gsfric platform --template``: a commented platform TOML to start from, of the reference
platform or of a rig's sizes (options, or a rig TOML: ``gsfric.platform.rig``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import click

from gsfric.commands.common import checked_paths, fail, with_options
from gsfric.errors import InputError
from gsfric.io.files import atomic_write
from gsfric.models import reference_platform
from gsfric.platform.rig import Rig, rig_platform_toml, rig_toml
from gsfric.platform.text import commented_toml


def _size_options(command):
    options = [
        click.option("--base-radius", type=float, metavar="M",
                     help="Radius of the circle of the universal joints C_i, m."),
        click.option("--base-half-angle", type=float, metavar="RAD",
                     help="Half the angle between the two joints of a base pair, rad."),
        click.option("--platform-radius", type=float, metavar="M",
                     help="Radius of the circle of the spherical joints E_i, m."),
        click.option("--platform-half-angle", type=float, metavar="RAD",
                     help="Half the angle between the two joints of a platform pair, rad."),
        click.option("--home-height", type=float, metavar="M",
                     help="Platform frame above the base frame at home, m [default: the "
                          "height of mid-stroke legs]."),
        click.option("--stroke", type=float, nargs=2, metavar="MIN MAX",
                     help="Shortest and longest leg length, m."),
        click.option("--platform-mass", type=float, metavar="KG", help="Moving platform, kg."),
        click.option("--lower-mass", type=float, metavar="KG",
                     help="Each leg's lower part (moves with the universal joint), kg."),
        click.option("--upper-mass", type=float, metavar="KG",
                     help="Each leg's upper part (moves with the spherical joint end), kg."),
        click.option("--payload-mass", type=float, metavar="KG", help="Payload, kg."),
        click.option("--friction-model", type=click.Choice(["coupled", "paper"]),
                     help="Friction model [default: coupled]."),
    ]
    return with_options(command, options)


@click.command()
@click.option("--template", is_flag=True,
              help="Write a commented platform TOML: the reference platform's, or, with "
                   "--rig or size options, the platform of those sizes (units in comments).")
@click.option("--rig", "rig_file", type=click.Path(dir_okay=False, exists=True),
              help="A rig TOML (the size options as keys, e.g. base_radius = 2.0) to expand; "
                   "options given override its values.")
@click.option("--rig-template", is_flag=True,
              help="Write a commented rig TOML (the reference platform's sizes) to edit and "
                   "expand with --template --rig.")
@click.option("--show", is_flag=True,
              help="Print the values of the rig's platform that its sizes do not state "
                   "(home height, bushing positions, centres of mass and inertias of the "
                   "platform and the leg parts), each given in the rig or how it is derived.")
@_size_options
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path),
              help="File to write [default: standard output].")
@checked_paths({"rig_file": "rig"}, files=("out",))
def platform(template, rig_file, rig_template, show, out, **sizes):
    """Write a platform file to start from: `gsfric platform --template --out my.toml`.

    With sizes (options or --rig FILE) the platform is built from them: joint pairs at 0, 120,
    240 deg (base) and 60, 180, 300 deg (platform); inertias, leg parts and bushings derived
    from the masses and sizes (stated in the file's comments); sizes not given are the
    reference platform's. Values drawn from the rig are checked: the home pose must lie
    within the stroke. A rig file may give any derived value explicitly (platform_inertia,
    lower_com, lower_inertia, upper_com, upper_inertia, bushing_offset, bushing_spacing);
    --show prints them all, given or derived, and so does writing a rig's platform to --out.
    """
    given = {k: v for k, v in sizes.items() if v is not None}
    if show and not (template or rig_template):
        if not (rig_file or given):
            fail("--show: give the rig (--rig FILE or size options)")
        click.echo("\n".join(_rig(rig_file, given).derived().lines()))
        return
    if template == rig_template:
        fail("give one of --template and --rig-template")
    rig = None
    if not (rig_file or given):
        text = rig_toml(_reference_rig()) if rig_template else platform_template()
    else:
        rig = _rig(rig_file, given)
        text = rig_toml(rig) if rig_template else rig_platform_toml(rig, rig_file or "")
    if out is None:
        click.echo(text, nl=False)
        return
    with atomic_write(out, "w") as handle:
        handle.write(text)
    click.echo(f"wrote {out}")
    if rig is not None and template:
        click.echo("values the sizes do not state (give them in the rig file to override):\n"
                   + "\n".join(f"  {line}" for line in rig.derived().lines()))


def _reference_rig() -> Rig:
    return Rig.from_platform(reference_platform())


def _rig(rig_file, given: dict) -> Rig:
    """The rig of a rig file (or the reference platform's sizes) with the options given."""
    if rig_file:
        base = dataclasses.asdict(Rig.from_toml(rig_file))
    else:
        base = dataclasses.asdict(_reference_rig())
        base["home_height"] = None
    names = {"stroke": "--stroke"}
    try:
        return Rig(**{**base, **given})
    except InputError as error:
        message = str(error)
        key = message.partition(":")[0]
        option = names.get(key, "--" + key.replace("_", "-"))
        if key in given:
            message = f"{option}: {message.partition(': ')[2]}"
        raise InputError(message) from None


def platform_template() -> str:
    """The reference platform as a commented TOML: what `Platform.from_toml` needs, with units."""
    return commented_toml(reference_platform(), header=[
        "A gsfric platform (SI units, angles in rad): the reference platform. Read with",
        "`gsfric simulate --platform FILE` or gsfric.Platform.from_toml(FILE). Required:",
        "[geometry] base_joints, platform_joints and [platform] mass, inertia; the other keys",
        "have defaults. `gsfric effects` lists the optional [effects]. For a platform of your",
        "rig's sizes: `gsfric platform --template --base-radius 2 --stroke 3 4.6 ...` or",
        "`gsfric platform --rig-template --out rig.toml`, edit, then",
        "`gsfric platform --template --rig rig.toml --out platform.toml`."])
