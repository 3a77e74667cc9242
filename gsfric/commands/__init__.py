"""The commands of the ``gsfric`` command line, one module each, loaded by ``gsfric.cli`` only
when the command runs (``common``: exit codes, one-line errors and the options they share)."""
