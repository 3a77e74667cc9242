"""A 3-D view of an evaluation in one self-contained HTML page (``gsfric view``,
``Result.to_html``, ``Result.show``).

Modules: ``frames`` (the steps kept for playback and the values drawn: ``FrameCollector``),
``data`` (their quantised, base64 form in the page, and its decoding), ``page`` (the page:
template.html, viewer.js and three.js from vendor/, inline; writing it; Jupyter).

The package reads a Result and a Platform's geometry by their attributes only and imports
nothing above ``io/`` (docs/explanation/architecture.md, level 3).
"""

from gsfric.view.data import decode, embedded
from gsfric.view.frames import DEFAULT_FPS, MAX_FRAMES, FrameCollector, Frames
from gsfric.view.page import notebook_html, page, show, write_page

__all__ = ["DEFAULT_FPS", "MAX_FRAMES", "FrameCollector", "Frames", "decode", "embedded",
           "notebook_html", "page", "show", "write_page"]
