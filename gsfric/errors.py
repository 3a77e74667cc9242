"""Exceptions and warnings raised by gsfric.

``InputError`` is the only exception that bad input (a platform TOML file, a trajectory or
measured-data table, arrays given to a constructor) produces. Its message is a single line that
names the file, the key or column and, for tables, the 1-based data row, e.g.
``trajectory.csv: row 17: column 'x' is NaN``.
"""

from __future__ import annotations


class GsfricError(Exception):
    """Base class of every exception raised by gsfric."""


class InputError(GsfricError, ValueError):
    """Bad input: a file, a key, a column, a row or an array that cannot be used.

    The message is always one line: any whitespace run (newlines included) is collapsed to a
    single space.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


class StepFlagError(GsfricError):
    """A trajectory step could not be evaluated soundly (see the ``flag`` column of results)."""


class GsfricWarning(UserWarning):
    """Input that can be used but looks suspicious (angles in degrees, a gimbal-lock jump, ...)."""
