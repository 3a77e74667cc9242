"""No command writes over one of its inputs, and no output replaces a device or FIFO.

An output that is the same file as an input (the same path, a symbolic link to it, a hard link
to it) is refused with one line naming both, before anything is written; a character device or
FIFO given as an output is written into (``/dev/null`` as a sink), other special files are
refused; the node is never unlinked or renamed over (``gsfric.io.files``)."""

from __future__ import annotations

import os
import re
import socket
import stat
import threading
from pathlib import Path

import pytest
from click.testing import CliRunner
from helpers import trajectory_frame

from gsfric import models
from gsfric.cli import main
from gsfric.discovery import discover
from gsfric.errors import InputError
from gsfric.io.files import atomic_write, check_outputs, output_folder, same_file
from gsfric.io.tables import write_table
from gsfric.sweep import sweep

STALE = ("gsfric: warning: generated/ is stale", "gsfric: compiling")
LINKS = ("same", "symlink", "hardlink")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def one_error(result, code: int = 2) -> str:
    """The one-line reason of a failed command (without ``gsfric: error: ``)."""
    assert result.exit_code == code, (result.exit_code, result.output)
    got = [line for line in result.stderr.splitlines() if line and not line.startswith(STALE)]
    assert len(got) == 1 and got[0].startswith("gsfric: error: "), result.stderr
    assert "Traceback" not in result.output
    return got[0][len("gsfric: error: "):]


@pytest.fixture
def files(tmp_path) -> dict[str, Path]:
    """A trajectory CSV and a platform TOML, with mtimes in the past (a rewrite would show)."""
    trajectory, platform = tmp_path / "t.csv", tmp_path / "p.toml"
    write_table(trajectory_frame(60, 50.0), trajectory)
    models.reference_platform().to_toml(platform)
    for path in (trajectory, platform):
        os.utime(path, ns=(1_000_000_000, 1_000_000_000))
    return {"trajectory": trajectory, "platform": platform}


def state(path: Path) -> tuple[bytes, int, int]:
    status = os.stat(path)
    return path.read_bytes(), status.st_mtime_ns, status.st_ino


def alias(source: Path, how: str, name: str) -> Path:
    """``source`` itself, a symbolic link to it, or a hard link to it, named ``name``."""
    if how == "same":
        return source
    path = source.parent / name
    if how == "symlink":
        path.symlink_to(source)
    else:
        os.link(source, path)
    return path


def refused(result, out: Path, source: Path, code: int = 2) -> str:
    message = one_error(result, code)
    assert str(out) in message
    return message


# -- an output that is an input ------------------------------------------------------------------


@pytest.mark.parametrize("how", LINKS)
def test_simulate_breakdown_onto_an_input_or_the_output(files, tmp_path, how):
    before = {k: state(p) for k, p in files.items()}
    out = tmp_path / "o.csv"
    target = alias(files["platform"], how, "b.csv")
    result = run("simulate", "--trajectory", files["trajectory"], "--platform",
                 files["platform"], "--out", out, "--breakdown", target)
    expected = "is the platform file itself" if how == "same" else \
        f"is the same file as the platform file {files['platform']}"
    assert refused(result, target, files["platform"]) == \
        f"{target}: {expected}; choose another output"
    assert not out.exists()
    result = run("simulate", "--trajectory", files["trajectory"], "--out", out,
                 "--breakdown", out)
    assert one_error(result) == f"{out}: is the same file as the output {out}; give each " \
                                "output its own file"
    assert not out.exists()
    assert {k: state(p) for k, p in files.items()} == before


@pytest.mark.parametrize("how", LINKS)
@pytest.mark.parametrize("command", ["sweep", "discover", "paper", "export"])
def test_folder_commands_out_onto_an_input(files, how, command):
    before = {k: state(p) for k, p in files.items()}
    source = files["platform"] if command in ("paper", "export") else files["trajectory"]
    out = alias(source, how, "o.out")
    args = {"sweep": ("--trajectories", files["trajectory"]),
            "discover": ("--measured", files["trajectory"]),
            "paper": ("--platform", files["platform"], "--no-plots"),
            "export": ("--platform", files["platform"])}[command]
    one_error(run(command, "--out", out, *args))
    assert {k: state(p) for k, p in files.items()} == before


@pytest.mark.parametrize("how", LINKS[1:])
def test_folder_functions_name_both_paths(files, how):
    """The library checks before its work (the command line's option parsing checks first)."""
    out = alias(files["trajectory"], how, "o.out")
    expected = re.escape(f"{out}: is the same file as the trajectory file "
                         f"{files['trajectory']}; choose another output")
    with pytest.raises(InputError, match=expected):
        sweep(out, trajectories=str(files["trajectory"]))
    with pytest.raises(InputError, match="the measured-data file"):
        discover(files["trajectory"], out=out)
    assert state(files["trajectory"])[0] == files["trajectory"].read_bytes()


@pytest.mark.parametrize("how", ["symlink", "hardlink"])
@pytest.mark.parametrize("command", ["paper", "export"])
def test_a_file_in_the_output_folder_that_is_an_input(files, tmp_path, how, command):
    """An input inside the output folder is refused, under any name: as a name written
    there (a link to the input) and as a file of its own."""
    folder = tmp_path / "folder"
    folder.mkdir()
    link = folder / "platform.toml"
    if how == "symlink":
        link.symlink_to(files["platform"])
    else:
        os.link(files["platform"], link)
    before = state(files["platform"])
    args = ("--no-plots",) if command == "paper" else ()
    message = one_error(run(command, "--out", folder, "--platform", files["platform"], *args))
    assert message == (f"{folder}: writing platform.toml would replace the input file "
                       f"{files['platform']}; choose another output directory")
    assert state(files["platform"]) == before
    folder = tmp_path / "with-input"
    folder.mkdir()
    inside = folder / "mine.toml"
    models.reference_platform().to_toml(inside)
    before = state(inside)
    message = one_error(run(command, "--out", folder, "--platform", inside, *args))
    assert message == (f"{folder}: holds the platform file {inside}, an input of the run; "
                       "choose another output directory")
    assert state(inside) == before and not (folder / "platform.toml").exists()


# -- devices and FIFOs ---------------------------------------------------------------------------


def read_fifo(path: Path) -> tuple[threading.Thread, list[bytes]]:
    """A FIFO at ``path`` and a thread reading it to the end."""
    os.mkfifo(path)
    got: list[bytes] = []

    def reader():
        with open(path, "rb") as handle:
            got.append(handle.read())

    thread = threading.Thread(target=reader, daemon=True)
    thread.start()
    return thread, got


@pytest.mark.parametrize(("name", "command"), [
    ("template.toml", ("platform", "--template")),
    ("m.csv", ("synth", "--samples", "40")),
    ("m.parquet", ("synth", "--samples", "40")),
    ("o.csv", ("simulate",)),
])
def test_a_fifo_is_written_into(files, tmp_path, name, command):
    path = tmp_path / name
    thread, got = read_fifo(path)
    extra = ("--trajectory", files["trajectory"]) if command[0] == "simulate" else ()
    result = run(*command, *extra, "--out", path)
    thread.join()
    assert stat.S_ISFIFO(os.lstat(path).st_mode)
    assert result.exit_code == 0, result.output
    assert len(got) == 1 and len(got[0]) > 100
    assert sorted(p.name for p in tmp_path.iterdir() if ".gsfric-" in p.name) == []


def test_a_character_device_named_like_a_table(files, tmp_path):
    """A ``null.csv`` node (the device of /dev/null, made only where mknod is allowed)."""
    node = tmp_path / "null.csv"
    try:
        os.mknod(node, 0o666 | stat.S_IFCHR, os.stat("/dev/null").st_rdev)
    except OSError:
        pytest.skip("mknod is not allowed here")
    if os.stat(node).st_rdev != os.stat("/dev/null").st_rdev:
        node.unlink()
        pytest.skip("could not make a node of /dev/null's device")
    for args in [("simulate", "--trajectory", files["trajectory"]),
                 ("synth", "--samples", "40"), ("platform", "--template")]:
        result = run(*args, "--out", node)
        assert result.exit_code == 0, (args, result.output)
        assert stat.S_ISCHR(os.lstat(node).st_mode)
    for args in [("paper", "--no-plots"), ("sweep", "--trajectories", files["trajectory"])]:
        one_error(run(*args, "--out", node))
        assert stat.S_ISCHR(os.lstat(node).st_mode)


def test_a_socket_is_refused_and_kept(tmp_path):
    path = tmp_path / "s.csv"
    server = socket.socket(socket.AF_UNIX)
    try:
        server.bind(str(path))
    except OSError:
        pytest.skip("no Unix sockets here")
    try:
        with pytest.raises(InputError, match=r"s\.csv: is a socket; give a file name"):
            write_table(trajectory_frame(10), path)
        assert stat.S_ISSOCK(os.lstat(path).st_mode)
    finally:
        server.close()


def test_output_folder_on_a_fifo_is_refused_and_kept(tmp_path):
    path = tmp_path / "out"
    os.mkfifo(path)
    with pytest.raises(InputError, match="exists and is not a directory"):
        with output_folder(path):
            pass
    assert stat.S_ISFIFO(os.lstat(path).st_mode)


# -- the rule itself -----------------------------------------------------------------------------


def test_same_file_and_check_outputs(tmp_path):
    a = tmp_path / "a.csv"
    a.write_text("x\n")
    (tmp_path / "link.csv").symlink_to(a)
    os.link(a, tmp_path / "hard.csv")
    assert same_file(a, tmp_path / "link.csv") and same_file(a, tmp_path / "hard.csv")
    assert same_file(tmp_path / "new.csv", tmp_path / "sub" / ".." / "new.csv")
    assert not same_file(a, tmp_path / "new.csv")
    check_outputs(["/dev/null", "/dev/null"], [a])        # a sink may take several outputs
    check_outputs([tmp_path / "o.csv"], [a, None])
    with pytest.raises(InputError, match=r"hard\.csv: is the same file as the input file"):
        check_outputs([tmp_path / "hard.csv"], [a])
    with pytest.raises(InputError, match=r"is the same file as the output"):
        check_outputs([tmp_path / "n.csv", tmp_path / "n.csv"])
    with pytest.raises(InputError, match=r"a\.csv: is the input file itself"):
        with atomic_write(a, inputs=[a, tmp_path / "hard.csv"]) as handle:
            handle.write("y\n")
    assert a.read_text() == "x\n"
