"""The ``gsfric`` command line.

Every command has ``--help``. Exit codes: 0 success; 1 a check failed (``derive --check``
found generated/ stale, ``simulate --strict`` found flagged steps); 2 bad input or usage (a
one-line reason on stderr); 3 an internal or build failure (also a full disk); 128 + the
signal number when stopped by SIGINT (130), SIGHUP (129) or SIGTERM (143), after removing the
temporary outputs; 141 when the reader of stdout went away (``gsfric bench | head``), quietly.
See docs/explanation/robustness.md.

Each command lives in a module of ``gsfric.commands``, imported only when that command runs
or shows its own help, so that ``gsfric --help`` loads none of the numerical stack.
"""

from __future__ import annotations

import contextlib
import gc
import importlib
import os
import signal
import sys
import warnings

import click

from gsfric.commands.common import EXIT_CHECK, EXIT_INPUT, EXIT_INTERNAL, EXIT_PIPE, fail
from gsfric.errors import GsfricError, InputError, Interrupted, StepFlagError
from gsfric.io.files import commit_check

COMMANDS = {
    "bench": "Print the throughput table of the compiled model (steps per second).",
    "columns": "List every output column of `simulate` with its unit and sign convention.",
    "derive": "Regenerate generated/ from the SymPy derivation in derive/ (needs sympy).",
    "discover": "Find which physical effect the model is missing, fit it, and show the gap "
                "shrink.",
    "effects": "List the catalog of optional effects, with their parameters, defaults and "
               "units.",
    "excite": "Design an excitation motion that identifies the platform's parameters well.",
    "export": "Write a self-contained C99 library of a platform for a real-time controller.",
    "identify": "Identify the platform's masses, inertias, friction and effects from a measured "
                "record.",
    "log": "Read a controller's log: `gsfric log inspect LOG` proposes its log format and a "
           "rig.",
    "paper": "Run the paper's 40-step motion and write Tables 1-3, a report and plots.",
    "platform": "Write a platform file to start from: `gsfric platform --template --out "
                "my.toml`.",
    "simulate": "Evaluate a motion: actuator forces, reactions and friction at every step.",
    "sweep": "Load envelopes per joint over motions, a workspace and platform variants.",
    "synth": "Write synthetic measured data with hidden effects and noise (reproducible by "
             "seed).",
    "view": "Write a 3-D view of a motion and its joint loads: one HTML page, opened offline.",
}
"""The commands: name -> the first paragraph of its help, listed by ``gsfric --help`` without
importing the command; the command itself is ``gsfric.commands.<name>.<name>``."""

_STOP_SIGNALS = ("SIGTERM", "SIGHUP")


class _StopSignals:
    """While entered, SIGTERM and SIGHUP raise ``Interrupted`` in the main thread, and SIGINT
    KeyboardInterrupt (unless it is ignored), so that temporary outputs and compiler processes
    are cleaned up.

    ``received`` keeps the first stop signal that arrived, and ``check`` raises it again: one
    that lands inside an extension module's import comes out as an ImportError that does not
    chain the exception raised here, and one raised inside a callback is only reported.
    """

    def __init__(self):
        self.received: int | None = None
        self._previous = {}

    def _handle(self, signum, frame):
        if self.received is None:
            self.received = signum
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Interrupted(signum)

    def __enter__(self):
        for name in (*_STOP_SIGNALS, "SIGINT"):
            number = getattr(signal, name, None)
            if number is None:
                continue
            if name == "SIGINT" and signal.getsignal(number) is not signal.default_int_handler:
                continue                          # ignored (a background job): keep it so
            with contextlib.suppress(ValueError, OSError):   # not the main thread
                self._previous[number] = signal.signal(number, self._handle)
        return self

    def check(self) -> None:
        """Raise the stop if one arrived (``gsfric.io.commit_check``): its own exception may
        have been swallowed, raised inside a callback that the interpreter only reports."""
        if self.received == signal.SIGINT:
            raise KeyboardInterrupt
        if self.received is not None:
            raise Interrupted(self.received)

    def __exit__(self, *exc_info):
        for number, handler in self._previous.items():
            with contextlib.suppress(ValueError, OSError):
                signal.signal(number, handler)
        return False


@contextlib.contextmanager
def _one_line_warnings():
    """Warnings (implausible units, flagged steps, a stale generated/) as one line each, each
    text once in a run (an input read twice, as ``simulate --breakdown`` does, warns once)."""
    shown: set[str] = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = str(message)
        if text in shown:
            return
        shown.add(text)
        click.echo(f"gsfric: warning: {text}", err=True)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield


def _quiet_broken_pipe() -> None:
    """stdout's reader went away: send the rest to /dev/null and exit 141 without a word."""
    with contextlib.suppress(OSError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    sys.exit(EXIT_PIPE)


class _Group(click.Group):
    """Loads each command from ``gsfric.commands`` when it is needed, and turns the library's
    errors into one-line messages and exit codes."""

    def list_commands(self, ctx):
        return sorted(COMMANDS)

    def get_command(self, ctx, cmd_name):
        if cmd_name not in COMMANDS:
            return None
        collecting = gc.isenabled()       # the numerical stack's imports: no cycles to find
        gc.disable()
        try:
            module = importlib.import_module(f"gsfric.commands.{cmd_name}")
        finally:
            if collecting:
                gc.enable()
        return getattr(module, cmd_name)

    def resolve_command(self, ctx, args):
        name, command, rest = super().resolve_command(ctx, args)
        if command is not None and not ctx.resilient_parsing:
            _check_given_options(command, ctx, rest)
        return name, command, rest

    def format_commands(self, ctx, formatter):
        """The list of commands with their short help (from ``COMMANDS``, nothing imported)."""
        limit = formatter.width - 6 - max(len(name) for name in COMMANDS)
        rows = [(name, click.Command(name, help=COMMANDS[name]).get_short_help_str(limit))
                for name in self.list_commands(ctx)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def invoke(self, ctx):
        stops = _StopSignals()
        try:
            with stops, commit_check(stops.check), _one_line_warnings():
                result = super().invoke(ctx)
                stops.check()            # a stop the run went on through never succeeds
                return result
        except Interrupted as exc:
            name = signal.Signals(exc.signum).name
            fail(f"stopped by {name}; no output was left half-written", 128 + exc.signum)
        except BrokenPipeError:
            _quiet_broken_pipe()
        except InputError as exc:
            fail(str(exc), EXIT_INPUT)
        except StepFlagError as exc:
            fail(str(exc), EXIT_CHECK)
        except GsfricError as exc:
            fail(str(exc), EXIT_INTERNAL)
        except KeyboardInterrupt:
            fail("interrupted; no output was left half-written", 130)
        except OSError as exc:
            where = f"{exc.filename}: " if exc.filename else ""
            fail(f"{where}{exc.strerror or exc}", EXIT_INTERNAL)
        except Exception as exc:
            # a stop signal that arrived inside an import or a cleanup comes out as the error
            # it caused there (an ImportError, chained to the stop or not): still a stop
            stop = _stop_in_chain(exc)
            signum = getattr(stop, "signum", signal.SIGINT) if stop else stops.received
            if signum is None:
                raise
            if signum == signal.SIGINT:
                fail("interrupted; no output was left half-written", 130)
            name = signal.Signals(signum).name
            fail(f"stopped by {name}; no output was left half-written", 128 + signum)

    def main(self, args=None, prog_name=None, **kwargs):
        """Usage errors (unknown option, missing argument) as one line too, exit 2."""
        try:
            result = super().main(args, prog_name, standalone_mode=False, **kwargs)
            sys.stdout.flush()
            return result
        except BrokenPipeError:
            _quiet_broken_pipe()
        except click.exceptions.NoArgsIsHelpError as exc:
            click.echo(exc.ctx.get_help(), err=True)
            sys.exit(EXIT_INPUT)
        except click.UsageError as exc:
            fail(exc.format_message().replace("\n", " ") + _help_hint(exc.ctx), EXIT_INPUT)
        except click.exceptions.Exit as exc:
            sys.exit(exc.exit_code)
        except click.Abort:
            fail("aborted", EXIT_CHECK)
        except click.ClickException as exc:
            fail(exc.format_message(), EXIT_INPUT)


def _check_given_options(command: click.Command, parent: click.Context,
                             args: list[str]) -> None:
    """``UsageError`` for an option of one value given more than once (``--out a --out b``):
    click keeps the last, silently dropping the first. Options that collect their values
    (``--vary``), flags and counts may repeat; a group's subcommand is checked too. A line
    that does not parse raises click's own error, with the command named for its help hint
    (click leaves it out of some, such as a missing option value). An empty path (which
    click would take for the current folder) is refused too."""
    ctx = click.Context(command, info_name=command.name, parent=parent)
    try:
        values, rest, order = command.make_parser(ctx).parse_args(args=list(args))
    except click.UsageError as exc:
        if exc.ctx is None:
            exc.ctx = ctx
        raise
    if any(name in args for name in ctx.help_option_names):
        return                                          # --help wins, as in click
    seen: set[str] = set()
    for param in order:
        if isinstance(param.type, click.Path) and values.get(param.name) == "":
            raise click.UsageError(f"{param.opts[0]}: an empty path; give a file or folder "
                                   "name", ctx)
        if not isinstance(param, click.Option) or param.multiple or param.count or \
                param.is_flag:
            continue
        if param.name in seen:
            raise click.UsageError(f"{param.opts[0]}: given more than once; give it once",
                                   ctx)
        seen.add(param.name)
    if isinstance(command, click.Group) and rest:
        sub = command.get_command(ctx, rest[0])
        if sub is not None:
            _check_given_options(sub, ctx, rest[1:])


def _help_hint(ctx: click.Context | None) -> str:
    """`` (see `gsfric COMMAND [SUBCOMMAND] --help`)`` for the command that was given."""
    names = []
    while ctx is not None and ctx.parent is not None:
        names.insert(0, ctx.info_name)
        ctx = ctx.parent
    return f" (see `{' '.join(['gsfric', *names])} --help`)"


def _stop_in_chain(exc: BaseException) -> BaseException | None:
    """The Interrupted or KeyboardInterrupt among the causes and contexts of ``exc``, if any."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, (Interrupted, KeyboardInterrupt)):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="gsfric")
def main():
    """Reaction forces and friction in every joint of a Gough-Stewart platform."""


if __name__ == "__main__":
    main()
