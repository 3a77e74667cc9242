"""The package as a user installs it: sdist and wheel built, installed outside the checkout.

``python -m build`` builds the sdist and then the wheel from that sdist (so both are checked);
the wheel is installed into a fresh virtual environment in a temporary directory, and the paper
run and a simulate run from there must work without the repository. To keep this fast and
offline-friendly, the fresh environment borrows the test environment's dependencies (numpy,
casadi, ...) through a .pth entry: gsfric itself comes only from the wheel (the checkout is not
on its path and the editable install's finder is not loaded), which is what is under test.
"""

from __future__ import annotations

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

ROOT = Path(__file__).resolve().parent.parent

# lines that builds print on this kind of machine and that say nothing about the package
_HARMLESS = (re.compile(r"byte-compiling is disabled"),
             re.compile(r"^WARNING: Location '.*' is ignored"))


def _build(tmp_path: Path):
    """sdist, then the wheel from it, built from a copy of the checkout (nothing left in it)."""
    pytest.importorskip("build")
    import shutil

    source = tmp_path / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", ".venv", "out", "build", "dist", "*.egg-info", "__pycache__", ".pytest_cache",
        ".hypothesis", ".ipynb_checkpoints"))
    out = tmp_path / "dist"
    run = subprocess.run([sys.executable, "-m", "build", "--outdir", str(out), str(source)],
                         capture_output=True, text=True, cwd=tmp_path, timeout=600)
    if run.returncode and "Could not find a version that satisfies" in run.stdout + run.stderr:
        pytest.skip("the build backend could not be installed (no package index)")
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    wheel = next(out.glob("gsfric-*.whl"))
    sdist = next(out.glob("gsfric-*.tar.gz"))
    return wheel, sdist, run.stdout + run.stderr


def _check_no_warnings(log):
    warnings = [line for line in log.splitlines() if re.search(r"(?i)warn", line)
                and not any(p.search(line.strip()) for p in _HARMLESS)]
    assert warnings == []


def _check_wheel(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    manifest = ROOT / "generated" / "manifest.json"
    import json

    for name in json.loads(manifest.read_text())["files"]:
        assert f"gsfric/_generated/{name}" in names
    assert "gsfric/_generated/manifest.json" in names
    assert "gsfric/compiled/batch.c" in names
    assert {f"gsfric/export/templates/{t}.in" for t in ("library.h", "library.c", "example.c",
                                                        "Makefile", "CMakeLists.txt",
                                                        "README.md", "verify.c")} <= names
    assert {f"gsfric/data/paper_table{k}.csv" for k in (1, 2, 3)} <= names
    tops = {n.split("/")[0] for n in names}
    assert not [t for t in tops if t not in ("gsfric",) and not t.endswith(".dist-info")]


def _check_sdist(sdist):
    names = tarfile.open(sdist).getnames()
    root = names[0].split("/")[0]
    for path in ("derive/build.py", "generated/manifest.json", "gsfric/__init__.py",
                 "pyproject.toml", "MANIFEST.in"):
        assert f"{root}/{path}" in names


def _fresh_venv(where: Path, wheel: Path) -> Path:
    """A new venv with the wheel installed (no deps) and the test env's packages borrowed."""
    venv.EnvBuilder(with_pip=False).create(where)
    python = where / "bin" / "python"
    site = Path(subprocess.check_output(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        text=True).strip())
    # our own site-packages, minus the editable gsfric (its finder is loaded by a .pth file,
    # which a directory named in another .pth does not run)
    (site / "borrowed.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--no-index", "--target", str(site), str(wheel)], check=True,
                   capture_output=True, text=True, timeout=300)
    return python


def test_sdist_and_wheel_build_without_warnings_install_and_run_outside_the_checkout(tmp_path):
    """One build (it takes a while): its log, the wheel's and sdist's contents, a smoke run."""
    wheel, sdist, log = _build(tmp_path)
    _check_no_warnings(log)
    _check_wheel(wheel)
    _check_sdist(sdist)
    python = _fresh_venv(tmp_path / "venv", wheel)
    work = tmp_path / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "GSFRIC_GENERATED")}
    env["PYTHONNOUSERSITE"] = "1"

    def run(*args):
        done = subprocess.run([str(python), *args], capture_output=True, text=True, cwd=work,
                              env=env, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
        return done.stdout

    where = run("-c", "import gsfric, gsfric.compiled.manifest as m; "
                      "print(gsfric.__file__); print(m.generated_dir())").split()
    assert not Path(where[0]).is_relative_to(ROOT)
    assert Path(where[1]).parts[-2:] == ("gsfric", "_generated")
    cli = ("-c", "import sys; from gsfric.cli import main; sys.argv[0] = 'gsfric'; main()")
    run(*cli, "paper", "--out", "paper", "--no-plots")
    table = (work / "paper" / "table1.csv")
    assert table.exists() or list((work / "paper").glob("*.csv"))
    run("-c", "import numpy as np; from gsfric import models, io; "
              "io.write_table(models.sinusoidal(np.linspace(0, 2, 401)).to_frame(), 'm.csv')")
    run(*cli, "simulate", "--trajectory", "m.csv", "--out", "f.parquet", "--quiet")
    out = run("-c", "import pandas as pd; f = pd.read_parquet('f.parquet'); "
                    "print(len(f), f['F1'].abs().max())").split()
    assert int(out[0]) == 401 and float(out[1]) > 0
    # the derivation is not installed: the command says so in one line, exit 2
    done = subprocess.run([str(python), *cli, "derive", "--check"], capture_output=True,
                          text=True, cwd=work, env=env, timeout=120)
    assert done.returncode == 2
    assert "source checkout" in done.stderr and len(done.stderr.strip().splitlines()) == 1
