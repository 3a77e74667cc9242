"""Reading and writing files: tables (CSV or Parquet), trajectories, measured data, other
programs' logs, and outputs written atomically.

The format follows the extension: ``.csv`` or ``.parquet`` / ``.pq`` (case-insensitive). Every
problem with an input file raises an ``InputError`` with a one-line message naming the file and,
where it applies, the row and the column, e.g. ``trajectory.csv: row 17: column 'x' is NaN``.

Modules: ``files`` (atomic writes, output folders), ``tables`` (CSV and Parquet), ``logs``
(column maps, units, time counters: ``LogFormat``), ``readers`` (trajectories and measured
data as a ``Motion``), ``arrow`` (Arrow arrays of numbers to NumPy and back, without pandas). Their main names are attributes of this package, each imported on first
use: ``gsfric.io.files`` (what the command line needs to write its outputs) loads no NumPy.
"""

import importlib

_HOMES = {"atomic_write": "gsfric.io.files", "output_folder": "gsfric.io.files",
          "LogFormat": "gsfric.io.logs", "motion_from_frame": "gsfric.io.readers",
          "read_measured": "gsfric.io.readers", "read_trajectory": "gsfric.io.readers",
          "read_table": "gsfric.io.tables", "write_table": "gsfric.io.tables"}
"""Public name -> the module it lives in."""

_MODULES = ("files", "logs", "readers", "tables")

__all__ = sorted(_HOMES)


def __getattr__(name):
    if name in _HOMES:
        value = getattr(importlib.import_module(_HOMES[name]), name)
        globals()[name] = value          # later look-ups skip this function
        return value
    if name in _MODULES:
        return importlib.import_module(f"gsfric.io.{name}")
    raise AttributeError(f"module 'gsfric.io' has no attribute {name!r}")


def __dir__():
    """The public names and the modules (for ``dir(gsfric.io)`` and tab completion)."""
    return sorted({*_HOMES, *_MODULES})
