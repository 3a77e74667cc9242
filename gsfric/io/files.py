"""Output files written atomically: a reader never sees a partly written file, and an interrupted
run leaves nothing behind (temporary names beside the output, renamed when complete). No output
is ever the same file as an input of the run, and a device or FIFO is written into, never
replaced."""

from __future__ import annotations

import codecs
import contextlib
import contextvars
import errno
import glob
import os
import re
import shutil
import stat
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, Any

import tomllib

from gsfric.errors import InputError, OutputError

_COMMIT_CHECK: contextvars.ContextVar = contextvars.ContextVar("gsfric_commit_check",
                                                               default=None)


_GROUP: contextvars.ContextVar = contextvars.ContextVar("gsfric_output_group", default=None)
"""The (temporary name, path) of the files written so far in the current ``output_group``."""

_TEMP_TAG = ".gsfric-"
"""Temporary outputs are named ``.{name}.gsfric-{pid}-{random}.tmp`` beside the output, so that a
later run can recognise (and remove) those of its own that a killed process (SIGKILL, a power
cut) left behind."""

PathArg = str | os.PathLike[str]
Inputs = Mapping[str, PathArg | None] | Iterable[PathArg | tuple[str, PathArg | None] | None]
"""A run's input files: paths or (what, path) pairs, or a mapping of what each is (e.g.
"trajectory", "platform") to its path; the error messages name what it is. Entries that are not paths (``None``, a
``Platform`` given as an object) are ignored."""


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True
    return True


def remove_stale_temporaries(path: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files or folders of ``path`` that dead gsfric processes left.

    Only names ``.{name}.gsfric-{pid}-*.tmp`` in ``path``'s directory whose process no longer
    runs are removed (a run still writing is never disturbed). Returns what was removed.
    """

    path = Path(path)
    removed = []
    pattern = f".{glob.escape(path.name)}{_TEMP_TAG}*.tmp"
    for stale in path.parent.glob(pattern):
        pid_text = stale.name[len(path.name) + 1 + len(_TEMP_TAG):].split("-", 1)[0]
        if not pid_text.isdigit() or _pid_alive(int(pid_text)):
            continue
        with contextlib.suppress(OSError):
            if stale.is_dir() and not stale.is_symlink():
                shutil.rmtree(stale)
            else:
                stale.unlink()
            removed.append(stale)
    return removed


def _temp_prefix(path: Path) -> str:
    return f".{path.name}{_TEMP_TAG}{os.getpid()}-"


def resolve_output(path: str | os.PathLike[str]) -> Path:
    """The file an output path stands for: a symbolic link's target (the link is kept).

    Raises
    ------
    InputError
        A symbolic link loop.
    """
    path = Path(path)
    try:
        os.stat(path)
    except FileNotFoundError:
        pass
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise InputError(f"{path}: symbolic link loop (too many levels of symbolic "
                             "links)") from None
    if path.is_symlink():
        return Path(os.path.realpath(path))
    return path


def same_file(a: PathArg, b: PathArg) -> bool:
    """Whether two paths name one file: the same path once symbolic links are resolved
    (``os.path.realpath``, whether or not the file exists yet), or, both existing, the same
    device and inode (``os.path.samefile``: hard links)."""
    try:
        return os.path.realpath(a) == os.path.realpath(b) or os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def _named_inputs(inputs: Inputs) -> list[tuple[str, Path]]:
    """(what, path) of each given input; "input" where ``inputs`` does not say what it is."""
    pairs = inputs.items() if isinstance(inputs, Mapping) else (
        p if isinstance(p, tuple) else ("input", p) for p in inputs)
    return [(what, Path(p)) for what, p in pairs
            if isinstance(p, (str, os.PathLike)) and str(p) != ""]


def check_outputs(outputs: Iterable[PathArg | None], inputs: Inputs = ()) -> None:
    """Refuse outputs that would overwrite an input, or each other, before anything is written.

    An output may not be the same file (``same_file``: after symbolic links, or a hard link)
    as one of ``inputs``, nor as another of ``outputs``; a character device or FIFO
    (``is_stream``) may be given as several outputs, being written into, not replaced.

    Once the outputs pass, the temporaries that killed runs left beside them are removed
    (``remove_stale_temporaries``): the next run cleans up even when it fails later.

    Raises
    ------
    InputError
        One line naming both paths, e.g. ``p.csv: is the same file as the platform file
        p2.csv; choose another output``.
    """
    outputs = [o for o in outputs if o is not None]
    _check_named(outputs, _named_inputs(inputs))
    for out in outputs:
        with contextlib.suppress(OSError, ValueError):
            remove_stale_temporaries(resolve_output(out))


def check_output_folder(path: PathArg) -> None:
    """Refuse, before any work, an output folder that exists and is not a directory (a
    file, a device such as /dev/null: ``output_folder`` never replaces one).

    Raises
    ------
    InputError
        ``{path}: exists and is not a directory``.
    """
    given = Path(path)
    if resolve_output(given).exists() and not resolve_output(given).is_dir():
        raise InputError(f"{given}: exists and is not a directory")


def _check_named(outputs: Iterable[PathArg | None], named: list[tuple[str, Path]]) -> None:
    """``check_outputs`` with the inputs as (what, path) pairs."""
    earlier: list[Path] = []
    for out in (Path(o) for o in outputs if o is not None):
        for what, source in named:
            if same_file(out, source):
                if str(out) == str(source):
                    raise InputError(f"{out}: is the {what} file itself; choose another output")
                raise InputError(f"{out}: is the same file as the {what} file {source}; "
                                 "choose another output")
        for other in earlier:
            if same_file(out, other) and not is_stream(out):
                raise InputError(f"{out}: is the same file as the output {other}; give each "
                                 "output its own file")
        earlier.append(out)


def check_run_paths(reads: Inputs, files: Iterable[PathArg | None] = (),
                    folders: Iterable[PathArg | None] = ()) -> None:
    """The one check of a run's paths, before anything is read or written: no path the run
    reads (``reads``: a trajectory, measured data, a platform, rig, column map, noise record,
    workspace, an export folder) is one of its outputs (``files`` and ``folders``:
    ``check_outputs``), nor lies inside an output folder (``inside_folder``: links resolved,
    folders compared by device and inode), where a write could replace it.

    Raises
    ------
    InputError
        One line naming the output and the input, e.g. ``out: holds the column-map file
        out/map.toml, an input of the run; choose another output directory``.
    """
    named = _named_inputs(reads)
    files = [f for f in files if f is not None]
    folders = [Path(f) for f in folders if f is not None and str(f) != ""]
    check_outputs([*files, *folders], named)
    _check_inside(folders, named)
    for path in files:
        check_output_place(path)


def check_output_place(path: PathArg) -> None:
    """Refuse, before any work, an output file that could not be written where it is given:
    a directory or another node that is not a file, device or FIFO (``atomic_write``), or a
    file whose folder (a symbolic link's, the target's) does not exist. A command writing
    several files checks each one so: a later one that cannot be written must not fail the
    run after an earlier one is in place.

    Raises
    ------
    InputError
        ``{path}: is a directory; give a file name``, ``{path}: directory 'DIR' does not
        exist``, ``{path}: 'DIR' is not a directory``.
    """
    given = Path(path)
    if _output_node(given) == "stream":
        return
    parent = resolve_output(given).parent
    if not parent.exists():
        raise InputError(f"{given}: directory {str(parent)!r} does not exist")
    if not parent.is_dir():
        raise InputError(f"{given}: {str(parent)!r} is not a directory")


def _check_inside(folders: Iterable[Path], named: list[tuple[str, Path]]) -> None:
    """``InputError`` if one of the inputs ``named`` lies inside one of ``folders``."""
    for folder in folders:
        for what, source in named:
            if inside_folder(source, folder):
                raise InputError(f"{folder}: holds the {what} file {source}, an input of the "
                                 "run; choose another output directory")


def inside_folder(path: PathArg, folder: PathArg) -> bool:
    """Whether ``path`` lies (at any depth) in the existing directory ``folder``: an ancestor
    of ``path`` as given (made absolute) or with its symbolic links resolved is ``folder``
    by device and inode (``os.stat``: links, bind mounts and ``..`` all compare equal)."""
    try:
        home = os.stat(folder)
        given = Path(os.path.abspath(path))
        real = Path(os.path.realpath(path))
    except (OSError, ValueError):
        return False
    if not stat.S_ISDIR(home.st_mode):
        return False
    for parent in {*given.parents, *real.parents}:
        with contextlib.suppress(OSError, ValueError):
            st = os.stat(parent)
            if (st.st_dev, st.st_ino) == (home.st_dev, home.st_ino):
                return True
    return False


def is_stream(path: PathArg) -> bool:
    """Whether ``path`` (a symbolic link followed) is a character device or a FIFO: an output
    that ``atomic_write`` writes into, as a shell redirection does, instead of replacing it."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)


def _output_node(given: Path) -> str:
    """What an output path is now: "stream" (a character device or FIFO, links followed) or
    "file" (a regular file, or nothing yet); ``InputError`` for any other node."""
    try:
        mode = os.stat(given).st_mode
    except OSError:
        return "file"               # missing, or a problem the write itself names
    if stat.S_ISCHR(mode) or stat.S_ISFIFO(mode):
        return "stream"
    if stat.S_ISDIR(mode):
        raise InputError(f"{given}: is a directory; give a file name")
    if not stat.S_ISREG(mode):
        what = "a block device" if stat.S_ISBLK(mode) else \
            "a socket" if stat.S_ISSOCK(mode) else "a special file"
        raise InputError(f"{given}: is {what}; give a file name (or a character device or "
                         "FIFO, written into)")
    return "file"


def _write_failure(path: Path, error: OSError, what: str = "file") -> OutputError:
    reason = error.strerror or str(error) or type(error).__name__
    return OutputError(f"{path}: cannot write ({reason}); nothing was written, an earlier "
                       f"{what} of that name is unchanged")


@contextlib.contextmanager
def commit_check(check) -> Iterator[None]:
    """Within the block, ``atomic_write`` and ``output_folder`` call ``check()`` (in the calling
    context) just before they move their outputs into place; an exception it raises leaves the
    earlier outputs as they were. The command line checks for a stop signal there: one whose
    exception the interpreter swallowed (raised inside a callback, reported as "Exception
    ignored") must still keep a half-done run from replacing them."""
    token = _COMMIT_CHECK.set(check)
    try:
        yield
    finally:
        _COMMIT_CHECK.reset(token)


def _before_commit() -> None:
    check = _COMMIT_CHECK.get()
    if check is not None:
        check()


@contextlib.contextmanager
def output_group() -> Iterator[None]:
    """Within the block, the regular files that ``atomic_write`` writes are moved into place
    together when the block ends without an error (a run's table, its breakdown and its
    figure): each stays a complete temporary file until then, and an error or a signal in the
    block removes every one, leaving all the earlier files of those names as they were. A
    group inside a group joins the outer one. Character devices and FIFOs are written into as
    the block runs (``atomic_write``)."""
    if _GROUP.get() is not None:
        yield
        return
    pending: list[tuple[str, Path]] = []
    token = _GROUP.set(pending)
    try:
        yield
        _before_commit()
        for tmp_name, path in pending:
            _replace_file(tmp_name, path)
        for directory in {path.parent for _, path in pending}:
            _sync_directory(directory)
    except BaseException:
        for tmp_name, _ in pending:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp_name)
        raise
    finally:
        _GROUP.reset(token)


@contextlib.contextmanager
def atomic_write(path: PathArg, mode: str = "w", *, encoding: str = "utf-8",
                 newline: str | None = None, inputs: Inputs = ()) -> Iterator[IO[Any]]:
    """Open a temporary file next to ``path`` and move it onto ``path`` when the block ends.

    The temporary file lives in the same directory (so ``os.replace`` is atomic), is named
    ``.{name}.gsfric-{pid}-{random}.tmp`` (those of dead processes are removed on the next
    write of the same output, see ``remove_stale_temporaries``), is flushed and fsync'ed before
    the move, and is removed if the block raises or a signal interrupts it; ``path`` is then
    left as it was. A symbolic link ``path`` is followed: its target is written, the link kept.
    A new file gets the usual permissions (0666 less the umask), a replaced file keeps its own.

    ``path`` must not be the same file as one of ``inputs`` (after symbolic links, or a hard
    link: ``check_outputs``), checked before anything is written.

    A ``path`` that is a character device or a FIFO (``/dev/null``, ``/dev/stdout``, a named
    pipe; links followed) is written into directly, as a shell redirection does: no temporary
    file, no rename, the node is never unlinked or replaced; what the block wrote before an
    error has then already gone out. Other nodes that are not regular files (a directory, a
    socket, a block device) are refused.

    Parameters
    ----------
    path : path-like
        The file to write.
    mode : {"w", "wt", "wb"}
        Text or binary.
    encoding, newline :
        As for ``open``, text mode only.
    inputs : paths, or a mapping of what each is to its path
        The run's input files, which ``path`` must not be.

    Yields
    ------
    file object

    Raises
    ------
    InputError
        The directory is missing or not writable, ``path`` is an input, a directory, a socket,
        a block device or a link loop.
    OutputError
        Writing failed part way (a full disk, an I/O error); nothing was left.
    """
    if mode not in ("w", "wt", "wb"):
        raise ValueError(f"atomic_write: mode must be 'w', 'wt' or 'wb', got {mode!r}")
    given = Path(path)
    check_outputs([given], inputs)
    target = resolve_output(given)
    text_options = {} if "b" in mode else {"encoding": encoding, "newline": newline}
    if _output_node(given) == "stream":
        with _write_into(given, mode, text_options) as handle:
            yield handle
    else:
        with _write_replacing(given, target, mode, text_options) as handle:
            yield handle


@contextlib.contextmanager
def _write_into(given: Path, mode: str, text_options: dict) -> Iterator[IO[Any]]:
    """Write into the character device or FIFO ``given`` as it is (opened without creating or
    truncating anything; a FIFO's open waits for its reader)."""
    try:
        fd = os.open(given, os.O_WRONLY | os.O_NOCTTY)
    except OSError as error:
        raise InputError(f"{given}: cannot write ({error.strerror})") from None
    try:
        with os.fdopen(fd, mode, **text_options) as handle:
            yield handle
            handle.flush()
            _before_commit()
    except OSError as error:
        if isinstance(error, BrokenPipeError):
            raise
        reason = error.strerror or str(error) or type(error).__name__
        raise OutputError(f"{given}: cannot write ({reason})") from None


@contextlib.contextmanager
def _write_replacing(given: Path, path: Path, mode: str,
                     text_options: dict) -> Iterator[IO[Any]]:
    """Write a temporary file beside the regular (or new) file ``path`` and rename it onto
    ``path`` when the block ends without an error (see ``atomic_write``)."""
    with contextlib.suppress(OSError):
        remove_stale_temporaries(path)
    fd, tmp_name = _temporary_file(given, path)
    try:
        try:
            with os.fdopen(fd, mode, **text_options) as handle:
                yield handle
                handle.flush()
                os.fsync(handle.fileno())
            if _GROUP.get() is not None:          # moved into place with the group's others
                _GROUP.get().append((tmp_name, path))
                return
            _before_commit()
            _replace_file(tmp_name, path)
        except OSError as error:
            if isinstance(error, BrokenPipeError):
                raise
            raise _write_failure(given, error) from None
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp_name)
        raise
    _sync_directory(path.parent)


def _temporary_file(given: Path, path: Path) -> tuple[int, str]:
    """A new temporary file beside ``path`` (descriptor, name); ``InputError`` naming ``given``
    when its directory is missing or not writable."""
    directory = path.parent
    try:
        return tempfile.mkstemp(prefix=_temp_prefix(path), suffix=".tmp", dir=directory)
    except FileNotFoundError as error:
        if directory.is_dir():
            raise InputError(f"{given}: cannot write ({error.strerror})") from None
        raise InputError(f"{given}: directory {str(directory)!r} does not exist") from None
    except NotADirectoryError:
        raise InputError(f"{given}: {str(directory)!r} is not a directory") from None
    except OSError as error:
        raise InputError(f"{given}: cannot write ({error.strerror})") from None


def _replace_file(tmp_name: str, path: Path) -> None:
    """Move the complete temporary file onto ``path``, with ``path``'s permissions if it exists
    (else 0666 less the umask)."""
    try:
        permissions = path.stat().st_mode & 0o7777
    except FileNotFoundError:
        permissions = 0o666 & ~_current_umask()
    os.chmod(tmp_name, permissions)
    os.replace(tmp_name, path)


def _sync_directory(directory: Path) -> None:
    with contextlib.suppress(OSError):
        dir_fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)


@contextlib.contextmanager
def output_folder(path: PathArg, *, inputs: Inputs = ()) -> Iterator[Path]:
    """Write a set of outputs into a temporary folder and move them into ``path`` as a whole.

    Yields a new empty folder beside ``path`` (``.{name}.gsfric-{pid}-{random}.tmp``). When the
    block ends without an error, the folder itself is renamed to ``path`` if ``path`` does not
    exist or is empty; otherwise each file is renamed into ``path`` (other files there are
    left alone). Only renames happen then, which need no disk space: either every output of
    the run is in place or, if the block raises or a signal interrupts it, none is and the
    temporary folder is removed (earlier outputs stay as they were). Files of ``inputs`` are
    never replaced (``check_outputs``): ``path`` being one is refused at once, an output file
    that is one before anything moves.

    Parameters
    ----------
    path : path-like
        The output directory (created with its parents if missing).
    inputs : paths, or a mapping of what each is to its path
        Files the run reads (``None`` entries are ignored).

    Yields
    ------
    Path
        The temporary folder to write into (plain files only).

    Raises
    ------
    InputError
        ``path`` exists and is not a directory (never replaced), cannot be created or written,
        or ``path`` or an output in it is one of ``inputs``.
    OutputError
        A write failed (a full disk); nothing was left.
    """
    if not str(path).strip():
        raise InputError("--out: the output folder's path is empty")
    given = Path(path)
    protected = _named_inputs(inputs)
    _check_named([given], protected)
    _check_inside([given], protected)
    path = _output_directory(given)
    with contextlib.suppress(OSError):
        remove_stale_temporaries(path)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(path), suffix=".tmp", dir=path.parent))
    except OSError as error:
        raise InputError(f"{given}: cannot write in {str(path.parent)!r} "
                         f"({error.strerror})") from None
    try:
        try:
            yield tmp
            _before_commit()
            names = sorted(p.name for p in tmp.iterdir())
            _refuse_to_replace_inputs(given, path, names, protected)
            _move_folder(given, path, tmp, names)
            _sync_directory(path.parent)
        except OSError as error:
            if isinstance(error, BrokenPipeError):
                raise
            raise _write_failure(given, error, "output") from None
        except OutputError as error:   # name the final path, not the temporary folder
            raise OutputError(str(error).replace(str(tmp), str(given))) from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _output_directory(given: Path) -> Path:
    """The directory ``given`` stands for (a link followed), its parents created."""
    path = resolve_output(given)
    if path.exists() and not path.is_dir():
        raise InputError(f"{given}: exists and is not a directory")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise InputError(f"{given}: {str(path.parent)!r} is not a directory") from None
    except OSError as error:
        raise InputError(f"{given}: cannot create the directory ({error.strerror})") from None
    return path


def _refuse_to_replace_inputs(given: Path, path: Path, names: list[str],
                              protected: list[tuple[str, Path]]) -> None:
    """``InputError`` if an output ``path / name`` is the same file as one of the inputs
    ``protected`` ((what, path) pairs)."""
    for name in names:
        target = path / name
        for _, source in protected:
            if target.exists() and same_file(target, source):
                raise InputError(f"{given}: writing {name} would replace the input "
                                 f"file {source}; choose another output directory")


def _move_folder(given: Path, path: Path, tmp: Path, names: list[str]) -> None:
    """Rename the folder ``tmp`` to ``path`` if that is missing or empty, else each of its files
    ``names`` into ``path``."""
    if not path.exists() or (path.is_dir() and not any(path.iterdir())):
        os.chmod(tmp, 0o777 & ~_current_umask())
        if path.exists():
            path.rmdir()
        os.replace(tmp, path)
    else:
        if not os.access(path, os.W_OK | os.X_OK):
            raise InputError(f"{given}: directory is not writable")
        for name in names:
            os.replace(tmp / name, path / name)
        tmp.rmdir()


def not_utf8(path: Path, chunk: int = 1 << 20) -> InputError:
    """The one-line error for a file that is not UTF-8 text, naming the line and the offset in
    the file of its first byte that is not (the file read again a chunk at a time: a reader's
    own decode error counts from where its buffer started)."""
    decoder = codecs.getincrementaldecoder("utf-8")()
    offset = lines = 0  # the file's bytes before this chunk, and their line ends
    with open(path, "rb") as handle:
        while True:
            data = handle.read(chunk)
            pending = decoder.getstate()[0]  # a character cut by the chunk's start: no b"\n"
            try:
                decoder.decode(data, final=not data)
            except UnicodeDecodeError as error:
                line = lines + (pending + data)[:error.start].count(b"\n") + 1
                byte = offset - len(pending) + error.start
                return InputError(f"{path}: not UTF-8 text (line {line}, byte {byte} of the "
                                  "file)")
            if not data:
                return InputError(f"{path}: not UTF-8 text")
            offset, lines = offset + len(data), lines + data.count(b"\n")


def read_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The tables of a TOML file; ``InputError`` in one line naming the file for a missing or
    unreadable file, a folder, text that is not UTF-8, invalid TOML (naming a repeated key and
    its line) or nesting too deep. A UTF-8 byte order mark at the start (which Windows
    editors write; TOML does not allow it) is accepted and skipped."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, not a file") from None
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise not_utf8(path) from None
    try:
        return tomllib.loads(text.removeprefix("\ufeff"))
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{path}: {_toml_problem(text, error)}") from None
    except RecursionError:
        raise InputError(f"{path}: invalid TOML: nested too deeply") from None


def _toml_problem(text: str, error: Exception) -> str:
    """The TOML error, naming the key of a repeated key (``Cannot overwrite a value``)."""
    message = str(error)
    line = re.search(r"at line (\d+)", message)
    if "overwrite" in message and line:
        lines = text.splitlines()
        number = int(line.group(1))
        source = lines[number - 1] if 0 < number <= len(lines) else ""
        key = source.split("=")[0].strip().strip("[]").strip()
        if key:
            return f"line {number}: key {key!r} given twice; give each key once"
    return f"invalid TOML: {message}"


def trajectory_files(trajectories) -> list[Path]:
    """The files the glob pattern(s) match, each pattern sorted; their names must differ."""
    if trajectories is None:
        return []
    patterns = [trajectories] if isinstance(trajectories, (str, os.PathLike)) else \
        list(trajectories)
    files: list[Path] = []
    for pattern in patterns:
        matched = sorted(glob.glob(os.fspath(pattern), recursive=True))
        matched = [m for m in matched if Path(m).is_file()]
        if not matched:
            raise InputError(f"trajectories: {os.fspath(pattern)!r} matches no file")
        files += [Path(m) for m in matched]
    names = [f.name for f in files]
    for name in names:
        if names.count(name) > 1:
            raise InputError(f"trajectories: two files are named {name!r}; motions are "
                             "named by file name")
    return files
