"""Reading and writing files: tables (CSV or Parquet), trajectories, measured data, other
programs' logs, and outputs written atomically.

The format follows the extension: ``.csv`` or ``.parquet`` / ``.pq`` (case-insensitive). Every
problem with an input file raises an ``InputError`` with a one-line message naming the file and,
where it applies, the row and the column, e.g. ``trajectory.csv: row 17: column 'x' is NaN``.

Modules: ``files`` (atomic writes, output folders), ``tables`` (CSV and Parquet), ``logs``
(column maps, units, time counters: ``LogFormat``), ``readers`` (trajectories and measured
data as a ``Motion``).
"""

from gsfric.io.files import atomic_write, output_folder
from gsfric.io.logs import LogFormat
from gsfric.io.readers import motion_from_frame, read_measured, read_trajectory
from gsfric.io.tables import read_table, write_table

__all__ = ["LogFormat", "atomic_write", "motion_from_frame", "output_folder", "read_measured",
           "read_table", "read_trajectory", "write_table"]
