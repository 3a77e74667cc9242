"""A 3-D view of an evaluation in one self-contained HTML page (``gsfric view``,
``Result.to_html``, ``Result.show``).

Modules: ``frames`` (the steps kept for playback and the values drawn: ``FrameCollector``),
``data`` (their quantised, base64 form in the page, the plots under the 3-D view, and its
decoding), ``page`` (the page: template.html, viewer.js and three.js from vendor/, inline;
writing it; Jupyter), ``comparison`` (the plots of a discovery's view: measured and model
forces, residuals, the named effects' contributions).

The package reads a Result, a Discovery and a Platform by their attributes only and imports
nothing above ``io/`` (docs/explanation/architecture.md, level 3).
"""

from gsfric.view.data import Curve, Plot, decode, embedded
from gsfric.view.frames import DEFAULT_FPS, MAX_FRAMES, FrameCollector, Frames
from gsfric.view.page import notebook_html, page, show, write_page

__all__ = ["DEFAULT_FPS", "MAX_FRAMES", "Curve", "FrameCollector", "Frames", "Plot", "decode",
           "embedded", "notebook_html", "page", "show", "write_page"]
