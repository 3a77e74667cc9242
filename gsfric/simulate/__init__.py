"""Streamed evaluation of trajectory files of any length in bounded memory (``gsfric simulate``).

Modules: ``blocks`` (a file read in validated blocks of rows), ``differentiate`` (the streamed
motion estimate: ``iter_motions``), ``outputs`` (the output columns), ``delay`` (the sensor's
time offset across chunks), ``writer`` (CSV and Parquet writing), ``run`` (``simulate_file``),
``rates`` (the log's own rates against its poses differentiated), ``view`` (``view_file``: the 3-D view of a file, ``gsfric view``).
"""

from gsfric.simulate.differentiate import MotionChunk, iter_motions
from gsfric.simulate.outputs import parse_columns
from gsfric.simulate.run import Summary, simulate_file
from gsfric.simulate.view import ViewSummary, view_file

__all__ = ["MotionChunk", "Summary", "ViewSummary", "iter_motions", "parse_columns",
           "simulate_file", "view_file"]
