"""The one runner of the fault table (``cases.py``): prepares a case's files, runs its command
(in this process through click's CliRunner, or in a fresh process when the fault needs one),
and checks the outcome class, the message, the inputs and the leftovers."""

from __future__ import annotations

import fnmatch
import os
import re
import stat
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from click.testing import CliRunner

from gsfric.cli import main
from gsfric.errors import GsfricError

OK, WARN, ERROR = "ok", "warn", "error"
"""The outcome classes: a correct result; a correct result with a named warning; a one-line
error with its exit code."""

NOTICES = ("gsfric: warning: generated/ is stale", "gsfric: compiling")
"""Lines a run may print whatever the case (a checkout being edited, a first compilation)."""


@dataclass(frozen=True)
class Case:
    """One fault and what the user must get.

    Attributes
    ----------
    id : str
        Unique, "family-command-fault".
    argv : tuple of str
        The command line after ``gsfric``; ``{name}`` is replaced by the path of the file
        ``files[name]`` made (or by ``{tmp}``, the case's folder).
    files : dict name -> maker
        Makers (``maker(folder) -> Path``) of the case's files; every file they make is an
        input that must come out unchanged.
    expect : {"ok", "warn", "error"}
    code : int
        Exit code (0 for ok and warn).
    message : str
        Regex searched in the error line (without "gsfric: error: ") or in the warnings.
    patch : callable (monkeypatch, paths) -> None, optional
        A fault injected in this process (a full disk, a failing task).
    env : dict
        Environment of a case run in a fresh process (``process=True``).
    process : bool
        Run ``python -m gsfric.cli`` in a fresh process (compiler and cache faults).
    check : callable (paths) -> None, optional
        Checks of the result of an ok or warn case (the output's content).
    absent : tuple of str
        Paths, relative to the case's folder, that must not exist afterwards (an error's
        outputs).
    kept : tuple of str
        Glob patterns of files that may remain in the folder (a sweep's resumable partial).
    warning : str
        Regex of a warning that an error case must also print (before its error line).
    mutable : tuple of str
        Patterns of the names of made files or folders (in the case's folder) that the run
        may change or remove (a cache it repairs, a dead run's temporary).
    """

    id: str
    argv: tuple[str, ...]
    expect: str
    code: int = 0
    message: str = ""
    files: dict[str, Callable[[Path], Path]] = field(default_factory=dict)
    patch: Callable | None = None
    env: dict[str, str] = field(default_factory=dict)
    process: bool = False
    check: Callable[[dict], None] | None = None
    absent: tuple[str, ...] = ()
    kept: tuple[str, ...] = ()
    warning: str = ""
    mutable: tuple[str, ...] = ()


@dataclass(frozen=True)
class ApiCase:
    """A call of the Python API and the library error it must raise (or None: it works).

    ``call(paths)`` gets the case's files as for ``Case``; ``error`` is the exact class
    expected (``InputError``, ``InputTypeError``...), ``builtin`` the builtin it must also be.
    """

    id: str
    call: Callable[[dict], object]
    error: type | None
    message: str = ""
    builtin: type | None = None
    files: dict[str, Callable[[Path], Path]] = field(default_factory=dict)


def _state(path: Path):
    """What must not change about an input: type, inode, content or link target."""
    st = os.lstat(path)
    if stat.S_ISLNK(st.st_mode):
        return ("link", os.readlink(path))
    if stat.S_ISREG(st.st_mode):
        return ("file", st.st_ino, st.st_mtime_ns, path.read_bytes())
    return ("special", stat.S_IFMT(st.st_mode), st.st_ino)


def _snapshot(folder: Path) -> dict[Path, object]:
    out = {}
    for root, dirs, names in os.walk(folder):
        for name in dirs + names:
            p = Path(root, name)
            if not p.is_dir() or p.is_symlink():
                out[p] = _state(p)
    return out


def make_files(case, folder: Path) -> dict[str, Path]:
    paths = {"tmp": folder}
    for name, maker in case.files.items():
        paths[name] = maker(folder)
    for path in folder.rglob("*"):       # in the past: a rewrite would show in the mtime
        if path.is_file() and not path.is_symlink():
            os.utime(path, ns=(1_000_000_000, 1_000_000_000))
    return paths


def _argv(case: Case, paths: dict) -> list[str]:
    names = {k: str(v) for k, v in paths.items()}
    return [a.format(**names) for a in case.argv]


def _lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line and not line.startswith(NOTICES)]


def run_cli(case: Case, paths: dict, monkeypatch) -> tuple[int, str]:
    """Exit code and stderr of the case's command."""
    argv = _argv(case, paths)
    if case.process:
        env = dict(os.environ, **{k: v.format(**{n: str(p) for n, p in paths.items()})
                                  for k, v in case.env.items()})
        done = subprocess.run([sys.executable, "-m", "gsfric.cli", *argv], capture_output=True,
                              text=True, env=env, cwd=paths["tmp"])
        return done.returncode, done.stderr
    if case.patch is not None:
        case.patch(monkeypatch, paths)
    monkeypatch.chdir(paths["tmp"])
    result = CliRunner().invoke(main, argv, catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception                    # a traceback: the case fails here
    return result.exit_code, result.stderr


def check_case(case: Case, folder: Path, monkeypatch) -> None:
    paths = make_files(case, folder)
    before = {p: s for p, s in _snapshot(folder).items()}
    code, stderr = run_cli(case, paths, monkeypatch)
    assert "Traceback" not in stderr, stderr
    lines = _lines(stderr)
    errors = [line for line in lines if line.startswith("gsfric: error: ")]
    warned = [line for line in lines if line.startswith("gsfric: warning: ")]
    if case.expect == ERROR:
        assert code == case.code, (code, stderr)
        assert len(errors) == 1 and lines[-1] == errors[0], stderr
        assert re.search(case.message, errors[0][len("gsfric: error: "):]), errors[0]
        if case.warning:
            assert any(re.search(case.warning, w) for w in warned), stderr
        if case.check is not None:
            case.check(paths)
    else:
        assert code == 0 and not errors, (code, stderr)
        if case.expect == WARN:
            assert any(re.search(case.message, w) for w in warned), stderr
        else:
            assert not warned, stderr
        if case.check is not None:
            case.check(paths)
    after = _snapshot(folder)
    changed = [str(p) for p, s in before.items() if after.get(p) != s and not any(
        fnmatch.fnmatch(p.relative_to(folder).parts[0], m) for m in case.mutable)]
    assert not changed, f"inputs changed: {changed}"
    for name in case.absent:
        assert not (folder / name).exists(), f"{name} was written"
    left = [p.name for p in folder.rglob("*") if ".gsfric-" in p.name or
            (p.name.endswith(".partial") and not any(p.match(k) for k in case.kept))]
    assert not left, f"leftovers: {left}"


def check_api_case(case: ApiCase, folder: Path) -> None:
    paths = make_files(case, folder)
    before = _snapshot(folder)
    if case.error is None:
        case.call(paths)
    else:
        with pytest.raises(GsfricError) as info:
            case.call(paths)
        assert type(info.value) is case.error, repr(info.value)
        if case.builtin is not None:
            assert isinstance(info.value, case.builtin)
        text = str(info.value)
        assert "\n" not in text and text, repr(text)
        assert re.search(case.message, text), text
    assert _snapshot(folder) == before
