"""The 3-D view as one self-contained HTML page: template, three.js, the viewer script and the
data, all inline; nothing is loaded from the network or from other files.

The page (``template.html``) holds three.js (``vendor/``, the npm package's minified builds,
unchanged) as text in ``<script type="text/plain">`` elements, the viewer (``viewer.js``) as a
module script that loads three.js from blob URLs, and the frames as JSON
(``gsfric.view.data``). It opens from disk (``file://``) and in a Jupyter output cell (an
iframe's ``srcdoc``, ``notebook_html``).
"""

from __future__ import annotations

import functools
import html
import importlib.resources
import json
import os
import re
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

from gsfric._optional import optional
from gsfric.io.files import Inputs, atomic_write
from gsfric.view.data import Plot, encode
from gsfric.view.frames import Frames

THREE_VERSION = "0.185.1"
"""The three.js release in ``vendor/`` (vendor/README.md)."""

_SLOT = re.compile(r"@([a-z_]+)@")
"""A slot of template.html, filled in one pass (what is put in is not searched again)."""


@functools.cache
def resource(name: str) -> str:
    """The text of a file of this package (``template.html``, ``viewer.js``,
    ``vendor/three.core.min.js``, ...)."""
    path = importlib.resources.files("gsfric.view").joinpath(*name.split("/"))
    return path.read_text(encoding="utf-8")


def _script_text(text: str, what: str) -> str:
    """``text`` safe inside a ``<script>`` element (no ``</script``)."""
    if "</script" in text.lower():
        raise ValueError(f"{what}: contains '</script'")
    return text


def page(frames: Frames, platform, *, title: str = "",
         flag_names: Mapping[int, str] | None = None, steps: int | None = None,
         plots: Sequence[Plot] | None = None, captions: Sequence[str] | None = None,
         focus: Sequence[int] | None = None) -> str:
    """The HTML text of a view of ``frames`` on ``platform`` (parameters as
    ``gsfric.view.data.encode``).

    Returns
    -------
    str
        One self-contained page: about 0.8 MB of three.js and viewer plus 190 bytes a frame.
    """
    data = encode(frames, platform, title=title, flag_names=flag_names, steps=steps,
                  plots=plots, captions=captions, focus=focus)
    text = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    values = {"title": html.escape(title or "gsfric view"), "three_version": THREE_VERSION,
              "three_core": _script_text(resource("vendor/three.core.min.js"), "three.core"),
              "three_module": _script_text(resource("vendor/three.module.min.js"),
                                           "three.module"),
              "data": text, "viewer": _script_text(resource("viewer.js"), "viewer.js")}
    return _SLOT.sub(lambda m: values.get(m.group(1), m.group(0)), resource("template.html"))


def write_page(path: str | os.PathLike[str], text: str, *, inputs: Inputs = ()) -> Path:
    """Write a page atomically (``gsfric.io.files.atomic_write``: a temporary file renamed
    when complete); ``path`` must not be one of ``inputs``. Returns the path."""
    with atomic_write(path, "w", encoding="utf-8", inputs=inputs) as handle:
        handle.write(text)
    return Path(path)


def notebook_html(text: str, height: int = 760) -> str:
    """An ``<iframe>`` whose ``srcdoc`` is the page ``text``: for a Jupyter output cell (the
    page keeps its own scripts and styles away from the notebook's)."""
    return (f'<iframe srcdoc="{html.escape(text, quote=True)}" style="width: 100%; '
            f'height: {int(height)}px; border: 0" '
            f'title="gsfric view"></iframe>')


def show(text: str, height: int = 760) -> None:
    """Display the page ``text`` in the running Jupyter front end (``IPython.display``)."""
    display = optional("IPython.display")
    with warnings.catch_warnings():     # IPython suggests its IFrame, which takes a URL only
        warnings.filterwarnings("ignore", "Consider using IPython.display.IFrame")
        shown = display.HTML(notebook_html(text, height))
    display.display(shown)
