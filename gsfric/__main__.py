"""``python -m gsfric``: the command line, as the ``gsfric`` script."""

from gsfric.cli import main

if __name__ == "__main__":
    main(prog_name="gsfric")
