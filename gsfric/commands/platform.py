"""``gsfric platform --template``: a commented platform TOML to start from."""

from __future__ import annotations

from pathlib import Path

import click

from gsfric.io.files import atomic_write
from gsfric.models import reference_platform
from gsfric.platform.description import Platform


@click.command()
@click.option("--template", is_flag=True, required=True,
              help="Write a commented, minimal platform TOML (the reference platform's "
                   "values, units in the comments).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path),
              help="File to write [default: standard output].")
def platform(template, out):
    """Write a platform file to start from: `gsfric platform --template --out my.toml`."""
    text = platform_template()
    if out is None:
        click.echo(text, nl=False)
        return
    with atomic_write(out, "w") as handle:
        handle.write(text)
    click.echo(f"wrote {out}")


def _rows(a) -> str:
    """The rows of a matrix as TOML array lines, one a line."""
    return "\n".join(f"    [{', '.join(repr(float(v)) for v in row)}]," for row in a)


def _matrix(a) -> str:
    """A matrix as a TOML array of arrays on one line."""
    return "[" + ", ".join("[" + ", ".join(repr(float(v)) for v in row) + "]"
                           for row in a) + "]"


def platform_template() -> str:
    """The reference platform as a commented TOML: what `Platform.from_toml` needs, with units."""
    p = reference_platform()
    g = p.geometry
    stroke = "" if g.stroke is None else (
        f"stroke = [{g.stroke[0]:.6g}, {g.stroke[1]:.6g}]   # m, shortest and longest leg "
        "(steps outside are flagged)\n")
    b = p.platform
    return f"""# A gsfric platform (SI units, angles in rad). Read with `gsfric simulate --platform FILE`
# or gsfric.Platform.from_toml(FILE). Required: [geometry] base_joints, platform_joints and
# [platform] mass, inertia; everything else has the default shown. `gsfric effects` lists
# the optional [effects].

gravity = {p.gravity:g}                 # m/s^2, along -z of the base frame

[geometry]
# C_i, the universal joints, in the base frame (m), one row per leg 1..6
base_joints = [
{_rows(g.base_joints)}
]
# E_i, the spherical joints, in the platform frame (m), leg i joins C_i and E_i
platform_joints = [
{_rows(g.platform_joints)}
]
{stroke}
[platform]
mass = {b.mass:g}                     # kg, the moving platform
inertia = [[{b.inertia[0, 0]:g}, 0, 0], [0, {b.inertia[1, 1]:g}, 0], [0, 0, {b.inertia[2, 2]:g}]]   # kg m^2, about its centre of mass, platform frame
payload_mass = {b.payload_mass:g}              # kg, at payload_com (platform frame, m)
""" + _legs_and_friction(p)


def _legs_and_friction(p: Platform) -> str:
    """The template's [legs], [friction] and [effects] tables."""
    f = p.friction
    return f"""
[legs]
model = "{p.legs.model}"                # "rigid", or "paper": the paper's zone centres at 0.25 D and 0.75 D
lower_mass = {p.legs.lower_mass:g}               # kg, moves with the universal joint
lower_com = {p.legs.lower_com:g}                # m from C_i along the leg (rigid model)
lower_inertia = {_matrix(p.legs.lower_inertia)}   # kg m^2, leg body frame (z along the leg)
upper_mass = {p.legs.upper_mass:g}               # kg, moves with the spherical joint end
upper_com = {p.legs.upper_com:g}                # m from E_i along the leg (rigid model)
upper_inertia = {_matrix(p.legs.upper_inertia)}   # kg m^2, leg body frame

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
