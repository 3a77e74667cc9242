"""The package as a user installs it: a wheel built from the checkout, installed outside it.

The wheel is built from the editable install's own build folder (meson-python's), so that the
compiled model is not compiled a second time: the build only packs what is built. It is
installed into a fresh virtual environment in a temporary directory, and the commands run there
with no C compiler anywhere (PATH holds only that environment, CC points nowhere, HOME is
empty). To keep this fast and offline, the fresh environment borrows the test environment's
dependencies (numpy, casadi, ...) through a .pth entry: gsfric itself comes only from the
wheel (the checkout is not on its path and the editable install's finder is not loaded).
The sdist is checked for what a build from it needs.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import sysconfig
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest
from helpers import build_folder_lock, editable_build_folder

from gsfric.compiled import native

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

ROOT = Path(__file__).resolve().parent.parent

# lines that builds print on this kind of machine and that say nothing about the package
_HARMLESS = (re.compile(r"^WARNING: Location '.*' is ignored"),)


def _pip(*args, cwd: Path) -> str:
    # the build backend's meson and ninja live beside this Python: found when the suite is
    # run with that Python directly rather than through `make` (which puts them on PATH)
    path = os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")])
    run = subprocess.run([sys.executable, "-m", "pip", *args], capture_output=True, text=True,
                         cwd=cwd, env={**os.environ, "PATH": path})
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    return run.stdout + run.stderr


@pytest.fixture(autouse=True)
def build_folder_in_use():
    """The wheel's build reconfigures the build folder: it holds the folder's lock exclusively
    while it does (``helpers.build_folder_lock``), not shared for the whole test."""
    yield


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> tuple[Path, str]:
    """The wheel (from the editable install's build folder when there is one) and its log."""
    out = tmp_path_factory.mktemp("dist")
    folder = editable_build_folder()
    settings = [f"-Cbuild-dir={folder}", "--no-build-isolation"] if folder else []
    with build_folder_lock(exclusive=True):
        log = _pip("wheel", "--no-deps", "--wheel-dir", str(out), *settings, str(ROOT),
                   cwd=out)
    return next(out.glob("gsfric-*.whl")), log


def _check_no_warnings(log: str) -> None:
    warnings = [line for line in log.splitlines() if re.search(r"(?i)warn", line)
                and not any(p.search(line.strip()) for p in _HARMLESS)]
    assert warnings == []


def _check_wheel(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    manifest = ROOT / "generated" / "manifest.json"
    for name in json.loads(manifest.read_text())["files"]:
        assert f"gsfric/_generated/{name}" in names
    assert "gsfric/_generated/manifest.json" in names
    assert "gsfric/compiled/batch.c" in names
    built = {n.split("/")[-1].split(".")[0] for n in names if n.startswith("gsfric/compiled/_model")}
    assert {module for isa, module in native.BUILDS.items()
            if native.build_path(isa) is not None} == built
    assert {f"gsfric/export/templates/{t}.in" for t in ("library.h", "library.c", "example.c",
                                                        "Makefile", "CMakeLists.txt",
                                                        "README.md", "verify.c")} <= names
    assert {f"gsfric/data/paper_table{k}.csv" for k in (1, 2, 3)} <= names
    assert not [n for n in names if "__pycache__" in n or n.endswith((".pyc", ".o", ".a"))]
    tops = {n.split("/")[0] for n in names}
    assert not [t for t in tops if t not in ("gsfric",) and not t.endswith(".dist-info")]


def _fresh_venv(where: Path, wheel: Path) -> Path:
    """A new venv with the wheel installed (no deps) and the test env's packages borrowed."""
    venv.EnvBuilder(with_pip=False).create(where)
    python = where / "bin" / "python"
    site = Path(subprocess.check_output(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['platlib'])"],
        text=True).strip())
    # our own site-packages, minus the editable gsfric (its finder is loaded by a .pth file,
    # which a directory named in another .pth does not run)
    (site / "borrowed.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--no-index", "--target", str(site), str(wheel)], check=True,
                   capture_output=True, text=True)
    return python


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory):
    """A function running the installed wheel's Python in a work folder with no compiler."""
    base = tmp_path_factory.mktemp("installed")
    python = _fresh_venv(base / "venv", wheel[0])
    work, home = base / "work", base / "home"
    work.mkdir()
    home.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "GSFRIC_GENERATED", "GSFRIC_ISA")}
    env.update(PYTHONNOUSERSITE="1", PATH=str(python.parent), CC="/nonexistent/cc",
               HOME=str(home))

    def run(*args, code: int = 0):
        done = subprocess.run([str(python), *args], capture_output=True, text=True, cwd=work,
                              env=env)
        assert done.returncode == code, done.stderr[-3000:]
        return done

    run.work = work
    return run


CLI = ("-c", "import sys; from gsfric.cli import main; sys.argv[0] = 'gsfric'; main()")


def test_the_wheel_builds_without_warnings_and_holds_the_compiled_model(wheel):
    _check_no_warnings(wheel[1])
    _check_wheel(wheel[0])


def test_the_installed_wheel_runs_without_a_compiler(installed):
    where = installed("-c", "import gsfric, gsfric.compiled.manifest as m; "
                            "print(gsfric.__file__); print(m.generated_dir())").stdout.split()
    assert not Path(where[0]).is_relative_to(ROOT)
    assert Path(where[1]).parts[-2:] == ("gsfric", "_generated")
    installed(*CLI, "paper", "--out", "paper", "--no-plots")
    assert (installed.work / "paper" / "table1.csv").exists()
    installed("-c", "import numpy as np; from gsfric import models, io; "
                    "io.write_table(models.sinusoidal(np.linspace(0, 2, 401)).to_frame(), "
                    "'m.csv')")
    installed(*CLI, "simulate", "--trajectory", "m.csv", "--out", "f.parquet", "--quiet")
    out = installed("-c", "import pandas as pd; f = pd.read_parquet('f.parquet'); "
                          "print(len(f), f['F1'].abs().max())").stdout.split()
    assert int(out[0]) == 401 and float(out[1]) > 0
    # the derivation is not installed: the command says so in one line, exit 2
    done = installed(*CLI, "derive", "--check", code=2)
    assert "source checkout" in done.stderr and len(done.stderr.strip().splitlines()) == 1
    # the throughput table needs only the package; the other benchmarks are in a checkout
    done = installed(*CLI, "bench", "--quick")
    assert done.stdout.splitlines()[1].startswith("machine: ")
    done = installed(*CLI, "bench", "--all", code=2)
    assert "source checkout" in done.stderr and len(done.stderr.strip().splitlines()) == 1
    # export writes C for the user's compiler; --verify says in one line that it needs one
    installed(*CLI, "export", "--out", "ctrl")
    assert (installed.work / "ctrl" / "gsfric.c").is_file()
    done = installed(*CLI, "export", "--verify", "ctrl", code=3)
    assert "no C compiler" in done.stderr and len(done.stderr.strip().splitlines()) == 1


def test_the_installed_wheel_evaluates_where_fcntl_cannot_be_imported(installed):
    """Nothing on the evaluation's path needs POSIX file locks (fcntl is missing on
    Windows)."""
    done = installed("-c", "import sys; sys.modules['fcntl'] = None\n"
                           "import numpy as np, gsfric\n"
                           "r = gsfric.evaluate(gsfric.reference_platform(), "
                           "gsfric.models.paper_motion())\n"
                           "print(np.isfinite(r.F).all(), 'fcntl' in sys.modules and "
                           "sys.modules['fcntl'] is not None)")
    assert done.stdout.split() == ["True", "False"]


def test_the_sdist_holds_what_a_build_needs(tmp_path):
    """An sdist compiles nothing: it is made in a build folder of its own (meson-python's
    temporary one), leaving the editable install's alone."""
    build = pytest.importorskip("build")
    run = subprocess.run([sys.executable, "-m", "build", "--sdist", "--no-isolation",
                          "--outdir", str(tmp_path), str(ROOT)],
                         capture_output=True, text=True, cwd=tmp_path)
    assert build and run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    names = tarfile.open(next(tmp_path.glob("gsfric-*.tar.gz"))).getnames()
    root = names[0].split("/")[0]
    for path in ("derive/build.py", "generated/manifest.json", "generated/gsfric_model.c",
                 "gsfric/__init__.py", "gsfric/compiled/batch.c", "gsfric/compiled/module.c",
                 "meson.build", "pyproject.toml", "Makefile", "tests/conftest.py"):
        assert f"{root}/{path}" in names, path
