"""``gsfric effects``: the catalog of optional effects with parameters, defaults and units."""

from __future__ import annotations

import click

from gsfric.platform.catalog import describe, markdown_table


@click.command()
@click.option("--markdown", is_flag=True, help="As the Markdown table of the reference.")
def effects(markdown):
    """List the catalog of optional effects, with their parameters, defaults and units.

    Switch one on in a platform's [effects] table, e.g. stribeck = { static = 2.0 }, or hide it
    in synthetic data with `gsfric synth --effect stribeck:static=2`.
    """
    if markdown:
        click.echo(markdown_table())
        return
    for effect in describe():
        click.echo(f"{effect['name']}: {effect['description']}")
        for p in effect["parameters"]:
            unit = p["unit"] or "1"
            click.echo(f"    {p['name']} = {p['default']:g} {unit}  ({p['description']})")
