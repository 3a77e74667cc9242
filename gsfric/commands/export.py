"""``gsfric export``: a self-contained C library of one platform, and its check (``--verify``)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from gsfric.commands.common import EXIT_CHECK, checked_paths
from gsfric.errors import InputError
from gsfric.export.verify import verify_library
from gsfric.export.writer import CODES, MODELS, export_library
from gsfric.models import platform_from


@click.command()
@click.option("--platform", "platform_file", type=click.Path(path_type=Path),
              help="Platform TOML (default: the reference platform).")
@click.option("--out", type=click.Path(path_type=Path),
              help="Folder to write (created; written to a temporary folder and renamed).")
@click.option("--model", type=click.Choice(MODELS), default=None,
              help="Friction model: coupled (fixed iterations) or paper (post hoc) "
                   "[default: the platform's].")
@click.option("--prefix", default="gsfric", show_default=True,
              help="C identifier: the header <prefix>.h and the prefix of every name.")
@click.option("--code", type=click.Choice(CODES), default="specialised", show_default=True,
              help="Build of the model: specialised (the platform's numbers folded into "
                   "straight-line code, fastest) or generic (the generated code of every "
                   "platform, reading the parameters as data).")
@click.option("--verify", "verify_dir", type=click.Path(path_type=Path), metavar="DIR",
              help="Instead of exporting, build the export in DIR with the system compiler "
                   "(CC) and compare it with the Python evaluation; exit 1 if it differs.")
@checked_paths({"platform_file": "platform", "verify_dir": "export-folder"},
               folders=("out",))
def export(platform_file, out, model, prefix, code, verify_dir):
    """Write a self-contained C99 library of a platform for a real-time controller.

    The folder holds <prefix>.h (the platform's parameters baked in), <prefix>.c (the
    model, by default with the platform folded into its code; no heap, no global state, no
    I/O, only math.h), a Makefile, a CMakeLists.txt, an example and a README.
    `gsfric export --verify DIR` builds it and reports the worst relative error against the
    Python evaluation and the median latency of one step. See docs/howto/export.md.
    """
    if verify_dir is not None:
        if out is not None or platform_file is not None or model is not None:
            raise InputError("--verify DIR checks an existing export: give it alone (without "
                             "--out, --platform or --model)")
        report = verify_library(verify_dir)
        for line in report.lines():
            click.echo(line)
        if not report.ok:
            sys.exit(EXIT_CHECK)
        return
    if out is None:
        raise InputError("--out: missing; name the folder to write (or give --verify DIR)")
    if platform_file is not None and not Path(platform_file).is_file():
        what = "is a directory" if Path(platform_file).is_dir() else "no such file"
        raise InputError(f"--platform: {platform_file}: {what}")
    written = export_library(platform_from(platform_file), out, model=model, prefix=prefix,
                             platform_file=platform_file, code=code)
    click.echo(f"wrote {written.folder} ({written.prefix}.h, {written.prefix}.c; "
               f"{written.model} model, {written.code} build)")
