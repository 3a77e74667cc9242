"""Exceptions and warnings raised by gsfric.

``InputError`` (and its subclass ``InputTypeError`` for an argument of the wrong type) is the
only exception that bad input (a platform TOML file, a trajectory or
measured-data table, arrays given to a constructor) produces. Its message is a single line that
names the file, the key or column and, for tables, the 1-based data row, e.g.
``trajectory.csv: row 17: column 'x' is NaN``.
"""

from __future__ import annotations

import signal


class GsfricError(Exception):
    """Base class of every exception raised by gsfric."""


class InputError(GsfricError, ValueError):
    """Bad input: a file, a key, a column, a row or an array that cannot be used.

    The message is always one line: any whitespace run (newlines included) is collapsed to a
    single space.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


class InputTypeError(InputError, TypeError):
    """An argument of the wrong type (None, a string for an array, a list for a Platform...).

    Both an ``InputError`` (``except InputError`` catches every bad input; the command line
    exits 2) and a ``TypeError`` (what Python code catches for a wrong type). One line.
    """


class StepFlagError(GsfricError):
    """A trajectory step could not be evaluated soundly (see the ``flag`` column of results)."""


class LibraryError(GsfricError):
    """The compiled model installed with gsfric is missing or cannot be loaded (a broken
    install): the message names the file and how to reinstall. One line."""

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


class BuildError(GsfricError):
    """A C compiler that a command needs is missing or failed: only ``gsfric export --verify``
    compiles anything (the exported library, with the user's compiler)."""


class GsfricWarning(UserWarning):
    """Input that can be used but looks suspicious (angles in degrees, a gimbal-lock jump, ...)."""


class IgnoredColumnsWarning(GsfricWarning):
    """Columns of a log that are not gsfric inputs and were not kept: the message counts them,
    ``names`` lists them (``gsfric simulate --verbose`` prints them)."""

    def __init__(self, message: str, names: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self.names = tuple(names)


class DataWarning(GsfricWarning):
    """Rows of an input that were left out so that the others can be used (a dropout row of a
    controller log: every value zero); the message names the file and the rows."""


class OutputError(GsfricError):
    """An output could not be written completely (a full disk, an I/O error).

    Nothing partial is left: the temporary file or folder is removed and an earlier output of
    the same name is unchanged. The message is one line naming the path.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


class Interrupted(BaseException):
    """A termination signal (SIGINT, SIGTERM, SIGHUP) arrived while a command ran.

    Raised in the main thread by the handlers that ``gsfric.cli`` installs, so that ``finally``
    blocks and ``except BaseException`` clean-ups (temporary files, compiler processes) run as
    for Ctrl-C; the command line then exits with 128 + the signal number.
    """

    def __init__(self, signum: int) -> None:
        self.signum = int(signum)
        super().__init__(signal.Signals(self.signum).name)
