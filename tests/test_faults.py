"""Fault injection: full disks, signals, a broken or missing compiled model.

Each test provokes one failure and checks what the user gets (one line, the documented exit
code) and what is left on disk (nothing partial, earlier outputs unchanged, no temporary file).
See docs/explanation/robustness.md, section 8.
"""

from __future__ import annotations

import errno
import os
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from click.testing import CliRunner
from helpers import trajectory_frame

from gsfric import models
from gsfric.cli import _stop_in_chain, main
from gsfric.compiled import native
from gsfric.errors import InputError, Interrupted, LibraryError, OutputError
from gsfric.io.files import output_folder, remove_stale_temporaries
from gsfric.io.readers import read_trajectory
from gsfric.io.tables import read_table, write_table

ROOT = Path(__file__).resolve().parent.parent


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def one_error(stderr: str, code: int, result_code: int) -> str:
    assert result_code == code, (result_code, stderr)
    got = [line for line in stderr.splitlines()
           if line and not line.startswith("gsfric: warning: generated/ is stale")]
    assert len(got) == 1, stderr
    assert got[0].startswith("gsfric: error: "), got[0]
    return got[0][len("gsfric: error: "):]


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob("*") if ".gsfric-" in p.name)


def env(**changes) -> dict:
    out = dict(os.environ)
    for key, value in changes.items():
        if value is None:
            out.pop(key, None)
        else:
            out[key] = str(value)
    return out


# -- a full disk: injected ENOSPC ---------------------------------------------------------------


@pytest.fixture
def disk_full(monkeypatch):
    """Every fsync fails with ENOSPC, as on a full disk (data written, then not flushable)."""
    def fsync(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", fsync)


def test_full_disk_table_one_line_old_file_kept(tmp_path, disk_full):
    out = tmp_path / "o.csv"
    out.write_text("earlier\n")
    with pytest.raises(OutputError) as info:
        write_table(trajectory_frame(20), out)
    assert str(info.value) == (f"{out}: cannot write (No space left on device); nothing was "
                               "written, an earlier file of that name is unchanged")
    assert out.read_text() == "earlier\n" and leftovers(tmp_path) == []


def _trajectory_file(tmp_path: Path, n: int = 400) -> Path:
    path = tmp_path / "t.csv"
    trajectory_frame(n).to_csv(path, index=False)
    return path


def test_full_disk_paper_leaves_no_partial_set(tmp_path, monkeypatch):
    """A later file fails: neither the earlier ones nor the folder appear."""
    out = tmp_path / "pp"
    real, calls = os.fsync, []

    def fsync(fd):
        calls.append(fd)
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    result = run("paper", "--out", out, "--no-plots")
    message = one_error(result.stderr, 3, result.exit_code)
    assert message.startswith(f"{out}/table2.csv: cannot write (No space left on device)")
    assert not out.exists() and leftovers(tmp_path) == []


def test_full_disk_paper_into_existing_folder_keeps_earlier_set(tmp_path, monkeypatch):
    out = tmp_path / "pp"
    assert run("paper", "--out", out, "--no-plots").exit_code == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "notes.txt").write_text("mine")
    real, calls = os.fsync, []

    def fsync(fd):
        if stat.S_ISREG(os.fstat(fd).st_mode):
            calls.append(fd)
            if len(calls) == 3:                    # the third file of the set
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    result = run("paper", "--out", out, "--no-plots", "--mode", "kinematic")
    one_error(result.stderr, 3, result.exit_code)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.name != "notes.txt"} == before
    assert (out / "notes.txt").read_text() == "mine" and leftovers(tmp_path) == []


def test_output_folder_moves_the_whole_set_or_nothing(tmp_path):
    out = tmp_path / "set"
    with pytest.raises(RuntimeError):
        with output_folder(out) as folder:
            (folder / "a.txt").write_text("a")
            raise RuntimeError("stop")
    assert not out.exists() and leftovers(tmp_path) == []
    with output_folder(out) as folder:
        (folder / "a.txt").write_text("a")
        (folder / "b.txt").write_text("b")
    assert sorted(p.name for p in out.iterdir()) == ["a.txt", "b.txt"]
    assert leftovers(tmp_path) == []


def test_small_filesystem_really_full(tmp_path):
    """A 64 kB tmpfs (needs the right to mount; skipped otherwise)."""
    mount = tmp_path / "small"
    mount.mkdir()
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mount)],
                          capture_output=True)
    if made.returncode:
        pytest.skip("cannot mount a small tmpfs here")
    try:
        path = _trajectory_file(tmp_path, 3000)
        out = mount / "o.csv"
        result = run("simulate", "--trajectory", path, "--out", out)
        message = one_error(result.stderr, 3, result.exit_code)
        assert message.startswith(f"{out}: cannot write (No space left on device)")
        assert list(mount.iterdir()) == []
    finally:
        subprocess.run(["umount", str(mount)], check=False)


# -- unwritable paths, links, inputs as outputs -------------------------------------------------


def test_paper_refuses_to_overwrite_its_platform_input(tmp_path):
    out = tmp_path / "pp"
    out.mkdir()
    source = out / "platform.toml"
    models.reference_platform().to_toml(source)
    text = source.read_text() + "# my comment\n"
    source.write_text(text)
    result = run("paper", "--out", out, "--platform", source, "--no-plots")
    message = one_error(result.stderr, 2, result.exit_code)
    assert message == (f"{out}: holds the platform file {source}, an input of the run; "
                       "choose another output directory")
    assert source.read_text() == text
    assert sorted(p.name for p in out.iterdir()) == ["platform.toml"]
    assert leftovers(tmp_path) == []


def test_out_link_writes_the_target_and_keeps_the_link(tmp_path):
    target = tmp_path / "real.csv"
    target.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    write_table(trajectory_frame(10), link)
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert len(read_table(target)) == 10


def test_symlink_loop_is_named(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.symlink_to(b)
    b.symlink_to(a)
    with pytest.raises(InputError, match=r"a\.csv: symbolic link loop"):
        read_trajectory(a)
    with pytest.raises(InputError, match=r"a\.csv: symbolic link loop"):
        write_table(trajectory_frame(10), a)


def test_out_in_a_file_not_a_directory(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="is not a directory"):
        write_table(trajectory_frame(10), tmp_path / "file" / "o.csv")


# -- temporary files of dead processes ----------------------------------------------------------


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_stale_temporaries_of_dead_runs_are_removed(tmp_path):
    out = tmp_path / "o.csv"
    dead = tmp_path / f".o.csv.gsfric-{_dead_pid()}-abc123.tmp"
    dead.write_text("partial")
    dead_folder = tmp_path / f".o.csv.gsfric-{_dead_pid()}-def456.tmp"
    dead_folder.mkdir()
    (dead_folder / "x").write_text("partial")
    alive = tmp_path / f".o.csv.gsfric-{os.getpid()}-zzz999.tmp"
    alive.write_text("a run still writing")
    other = tmp_path / f".p.csv.gsfric-{_dead_pid()}-abc123.tmp"
    other.write_text("another output's")
    write_table(trajectory_frame(10), out)
    assert not dead.exists() and not dead_folder.exists()
    assert alive.exists() and other.exists()
    assert remove_stale_temporaries(tmp_path / "p.csv") == [other]


# -- signals to a running command ---------------------------------------------------------------

SLOW_SIMULATE = textwrap.dedent("""
    import sys, time
    import gsfric.simulate.run
    original = gsfric.simulate.run.evaluate_outputs
    def slow(*args, **kwargs):
        time.sleep(0.3)
        return original(*args, **kwargs)
    gsfric.simulate.run.evaluate_outputs = slow
    from gsfric.cli import main
    main(sys.argv[1:])
""")


def _interruptible() -> None:
    """In the child: SIGINT as an interactive shell leaves it. A suite started in the
    background (``make test &``, nohup) ignores SIGINT, and the child would inherit that."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start_slow_simulate(tmp_path: Path) -> tuple[subprocess.Popen, Path]:
    path = _trajectory_file(tmp_path, 3000)
    out = tmp_path / "o.csv"
    out.write_text("earlier output\n")
    proc = subprocess.Popen([sys.executable, "-c", SLOW_SIMULATE, "simulate", "--trajectory",
                             str(path), "--out", str(out), "--chunk", "100", "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_interruptible)
    while not leftovers(tmp_path):     # polled: a busy machine only makes this slower
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    return proc, out


@pytest.mark.integration  # a process of its own, stopped by a signal
@pytest.mark.parametrize("sig, code, name", [(signal.SIGTERM, 143, "SIGTERM"),
                                             (signal.SIGHUP, 129, "SIGHUP"),
                                             (signal.SIGINT, 130, None)])
def test_signal_removes_the_temporary_and_keeps_the_old_output(tmp_path, sig, code, name):
    proc, out = _start_slow_simulate(tmp_path)
    proc.send_signal(sig)
    _, stderr = proc.communicate()
    message = one_error(stderr, code, proc.returncode)
    if name:
        assert message == f"stopped by {name}; no output was left half-written"
    assert out.read_text() == "earlier output\n"
    assert leftovers(tmp_path) == []


@pytest.mark.integration
def test_sigkill_leaves_a_temporary_that_the_next_run_removes(tmp_path):
    proc, out = _start_slow_simulate(tmp_path)
    proc.kill()
    proc.communicate()
    assert len(leftovers(tmp_path)) == 1          # unavoidable: nothing runs on SIGKILL
    result = run("simulate", "--trajectory", tmp_path / "t.csv", "--out", out)
    assert result.exit_code == 0, result.output
    assert leftovers(tmp_path) == [] and len(read_table(out)) == 3000


def test_closed_stdout_exits_quietly(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "gsfric.cli", "derive", "--check"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    proc.stdout.close()                            # the reader went away (`| head -c 0`)
    stderr = proc.stderr.read().decode()
    proc.wait()
    if proc.returncode == 1 and "generated/ is stale" in stderr:   # derive/ being edited
        pytest.skip("generated/ is stale in this checkout")
    assert proc.returncode == 141 and stderr == ""


# -- the compiled model installed with the package -----------------------------------------------

@pytest.fixture
def fresh_library():
    """The loaded builds forgotten before and after the test (``native`` caches them)."""
    for cached in (native.library, native.get):
        cached.cache_clear()
    yield
    for cached in (native.library, native.get):
        cached.cache_clear()


@pytest.mark.parametrize("content", [b"", b"not a shared library", b"\x7fELF" + bytes(200)])
def test_a_broken_compiled_model_is_one_line_naming_the_file(tmp_path, monkeypatch,
                                                             fresh_library, content):
    broken = tmp_path / "_model.abi3.so"
    broken.write_bytes(content)
    monkeypatch.setattr(native, "build_path", lambda isa: broken)
    with pytest.raises(LibraryError) as caught:
        native.library("baseline")
    message = str(caught.value)
    assert message.startswith(f"{broken}: the compiled model cannot be loaded (")
    assert "\n" not in message and message.endswith("`make install` in a source checkout)")
    result = run("paper", "--out", tmp_path / "pp", "--no-plots")
    assert result.exit_code == 3 and str(broken) in result.output
    assert not (tmp_path / "pp").exists()


def test_a_missing_compiled_model_says_how_to_reinstall(monkeypatch, fresh_library):
    monkeypatch.setattr(native, "build_path", lambda isa: None)
    with pytest.raises(LibraryError, match=r"^the compiled model gsfric\.compiled\._model is "
                                            r"missing from this install of gsfric; reinstall"):
        native.library("baseline")


def test_a_stop_inside_an_import_is_still_a_stop():
    """A signal that lands inside an import surfaces as the ImportError it caused there; the
    CLI finds the stop in the exception's chain (exit 130 or 128 + signal, not a traceback)."""
    def raised(inner: BaseException) -> BaseException:
        try:
            try:
                raise inner
            except BaseException:
                raise ImportError("numpy._core.multiarray failed to import")
        except ImportError as exc:
            return exc

    assert isinstance(_stop_in_chain(raised(KeyboardInterrupt())), KeyboardInterrupt)
    stop = _stop_in_chain(raised(Interrupted(signal.SIGTERM)))
    assert isinstance(stop, Interrupted) and stop.signum == signal.SIGTERM
    assert _stop_in_chain(raised(ValueError("a real import problem"))) is None


STOP_INSIDE_AN_EXTENSION_IMPORT = textwrap.dedent("""
    import os, signal, sys
    from gsfric.errors import Interrupted
    from gsfric.evaluation.evaluator import Evaluator
    stop = getattr(signal, sys.argv.pop(1))
    def stopped_inside_an_import(self, *args, **kwargs):
        try:
            os.kill(os.getpid(), stop)
        except (Interrupted, KeyboardInterrupt):
            pass
        # what a Cython module's init makes of it: a new error, not chained to the stop
        raise ImportError('PyCapsule_Import could not import module "pandas"')
    Evaluator.__init__ = stopped_inside_an_import     # in the main thread, output open
    from gsfric.cli import main
    main(sys.argv[1:])
""")


@pytest.mark.integration
@pytest.mark.parametrize("name, code", [("SIGTERM", 143), ("SIGINT", 130)])
def test_a_stop_that_an_import_turned_into_an_unchained_error_is_still_a_stop(tmp_path, name,
                                                                              code):
    path = _trajectory_file(tmp_path, 300)
    out = tmp_path / "o.csv"
    out.write_text("earlier output\n")
    proc = subprocess.run([sys.executable, "-c", STOP_INSIDE_AN_EXTENSION_IMPORT, name,
                           "simulate", "--trajectory", str(path), "--out", str(out),
                           "--no-progress"],
                          capture_output=True, text=True, preexec_fn=_interruptible)
    message = one_error(proc.stderr, code, proc.returncode)
    assert message.startswith("stopped by SIGTERM" if name == "SIGTERM" else "interrupted")
    assert out.read_text() == "earlier output\n" and leftovers(tmp_path) == []


STOP_SWALLOWED = textwrap.dedent("""
    import os, signal, sys
    from gsfric.errors import Interrupted
    from gsfric.evaluation.evaluator import Evaluator
    stop = getattr(signal, sys.argv.pop(1))
    original = Evaluator.__init__
    def swallowed(self, *args, **kwargs):
        try:
            os.kill(os.getpid(), stop)
        except (Interrupted, KeyboardInterrupt):
            pass        # as when it is raised in a callback: "Exception ignored in ..."
        original(self, *args, **kwargs)
    Evaluator.__init__ = swallowed      # in the main thread, output open
    from gsfric.cli import main
    main(sys.argv[1:])
""")


@pytest.mark.integration
@pytest.mark.parametrize("name, code", [("SIGTERM", 143), ("SIGINT", 130)])
def test_a_stop_whose_exception_was_swallowed_still_keeps_the_old_output(tmp_path, name, code):
    """The run goes on to its end, but what it wrote does not replace the earlier output."""
    path = _trajectory_file(tmp_path, 300)
    out = tmp_path / "o.csv"
    out.write_text("earlier output\n")
    proc = subprocess.run([sys.executable, "-c", STOP_SWALLOWED, name, "simulate",
                           "--trajectory", str(path), "--out", str(out), "--no-progress"],
                          capture_output=True, text=True, preexec_fn=_interruptible)
    message = one_error(proc.stderr, code, proc.returncode)
    assert message.startswith("stopped by SIGTERM" if name == "SIGTERM" else "interrupted")
    assert out.read_text() == "earlier output\n" and leftovers(tmp_path) == []
