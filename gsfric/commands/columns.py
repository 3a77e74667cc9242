"""``gsfric columns``: every output column of ``simulate`` with its unit and sign convention."""

from __future__ import annotations

import click

from gsfric.evaluation.columns import listing, markdown_table


@click.command()
@click.option("--markdown", is_flag=True, help="As the Markdown table of the README.")
@click.option("--no-measured", is_flag=True,
              help="Leave out the columns added for a measured-data input.")
def columns(markdown, no_measured):
    """List every output column of `simulate` with its unit and sign convention."""
    text = markdown_table(not no_measured) if markdown else listing(not no_measured)
    click.echo(text)
