"""``gsfric derive``: regenerate generated/ from the SymPy derivation of a source checkout."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

import click

from gsfric.commands.common import EXIT_CHECK, fail

CHECKOUT = Path(__file__).resolve().parent.parent.parent
"""The source checkout gsfric runs from, if it is one (derive/ beside gsfric/)."""


def _build_module() -> ModuleType:
    """derive/build.py of the checkout (not installed with gsfric: loaded from its path)."""
    if not (CHECKOUT / "derive" / "build.py").is_file():
        fail("`gsfric derive` needs a source checkout of gsfric (derive/ and generated/ are "
             "not installed, only the generated model is): clone the repository and run "
             "`pip install -e \".[derive]\"` there")
    if str(CHECKOUT) not in sys.path:
        sys.path.insert(0, str(CHECKOUT))
    try:
        return importlib.import_module("derive.build")
    except ImportError as exc:
        fail(f"the derivation needs sympy ({exc}); install it with "
             "`pip install -e \".[derive]\"` in the checkout")


@click.command()
@click.option("--check", is_flag=True, help="Exit 1 if generated/ is stale; write nothing.")
def derive(check):
    """Regenerate generated/ from the SymPy derivation in derive/ (needs sympy).

    derive/ is not installed with gsfric (a wheel carries only its output, generated/): this
    command runs in a source checkout, e.g. after `pip install -e ".[derive]"` there.
    """
    build = _build_module()
    if check:
        reason = build.is_stale()
        if reason:
            click.echo(f"generated/ is stale: {reason}; run `gsfric derive`", err=True)
            sys.exit(EXIT_CHECK)
        click.echo("generated/ is up to date")
        return
    build.write(build.generate())
    click.echo(f"wrote {build.GENERATED}")
