"""A long fuzz run of the file readers and the command line: 10,000 seeded CSV and TOML inputs
(``make test-slow``).

Each input is a valid trajectory or platform file damaged by a seeded generator (cells,
rows, header, bytes, truncation; values such as NaN, 2^70, 1e999, text, tables) or random
bytes. Each must give a valid result or one ``InputError`` of one line naming the file; never
another exception, a warning other than a one-line ``GsfricWarning``, or a hang (each input
has ``LIMIT`` seconds). One input in ``CLI_EVERY`` also goes through ``gsfric simulate`` or
``gsfric export --platform`` in this process: exit 0 or 2, one error line, no traceback, the
input unchanged and nothing left behind.
"""

from __future__ import annotations

import contextlib
import signal
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from makers import base_csv, platform_text

from gsfric.cli import main
from gsfric.errors import GsfricWarning, InputError
from gsfric.io.readers import read_trajectory
from gsfric.platform.description import Platform

INPUTS = 5_000
"""Inputs of each kind (CSV and TOML): 10,000 in all."""
LIMIT = 20
"""Seconds an input may take (a hang fails the run instead of stalling it)."""
CLI_EVERY = 25
"""One input in this many also goes through the command line."""

TOKENS = ["", "nan", "NaN", "inf", "-inf", "1e999", "-1e999", "1e308", "2e-308", "5e-324",
          str(2**70), str(-2**63), "abc", '"', "'", ",", ",,", ";", "\t", "NULL", "None",
          "1,5", "0x1p3", "\x00", "é", "#", "\r", "true", "[]", "{}", "[1, 2]", "{a = 1}",
          "1_000", "+1", "-0", "0.0.1", "1e", "e1", " 1 ", "∞", "\ufeff"]
"""Values put in place of a cell or a TOML value."""


@contextlib.contextmanager
def time_limit(seconds: int):
    def stop(signum, frame):
        raise TimeoutError(f"an input took more than {seconds} s")

    previous = signal.signal(signal.SIGALRM, stop)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def damaged_csv(rng: np.random.Generator) -> bytes:
    lines = base_csv().splitlines()[:rng.integers(2, 60)]
    for _ in range(rng.integers(1, 5)):
        i = int(rng.integers(0, len(lines)))
        kind = rng.integers(0, 8)
        if kind == 0:
            cells = lines[i].split(",")
            cells[rng.integers(0, len(cells))] = TOKENS[rng.integers(0, len(TOKENS))]
            lines[i] = ",".join(cells)
        elif kind == 1 and len(lines) > 1:
            del lines[i]
        elif kind == 2:
            lines.insert(i, lines[i])
        elif kind == 3 and i > 1:
            lines[i], lines[i - 1] = lines[i - 1], lines[i]
        elif kind == 4:
            names = lines[0].split(",")
            names[rng.integers(0, len(names))] = ["", "x", "t", "qw", "F1", "gamma", "T "][
                rng.integers(0, 7)]
            lines[0] = ",".join(names)
        elif kind == 5:
            lines = lines[:i + 1]
            lines[i] = lines[i][:rng.integers(0, len(lines[i]) + 1)]
        elif kind == 6:
            lines.insert(i, TOKENS[rng.integers(0, len(TOKENS))])
        else:
            cells = lines[i].split(",")
            k = rng.integers(0, len(cells))
            with contextlib.suppress(ValueError):
                cells[k] = repr(float(cells[k]) * 10.0 ** rng.integers(-300, 300))
            lines[i] = ",".join(cells)
    data = ("\n".join(lines) + "\n").encode("utf-8", "surrogatepass")
    return _bytes_damage(rng, data)


def _bytes_damage(rng: np.random.Generator, data: bytes) -> bytes:
    """Sometimes a flipped byte, random bytes, or nothing at all."""
    roll = rng.random()
    if roll < 0.05:
        return bytes(rng.integers(0, 256, rng.integers(0, 400), dtype=np.uint8))
    if roll < 0.15 and data:
        raw = bytearray(data)
        raw[rng.integers(0, len(raw))] = int(rng.integers(0, 256))
        return bytes(raw)
    return data


def damaged_toml(rng: np.random.Generator) -> bytes:
    lines = platform_text().splitlines()
    for _ in range(rng.integers(1, 4)):
        if not lines:
            break
        i = int(rng.integers(0, len(lines)))
        kind = rng.integers(0, 6)
        if kind == 0 and "=" in lines[i]:
            key = lines[i].split("=")[0]
            lines[i] = f"{key}= {TOKENS[rng.integers(0, len(TOKENS))]}"
        elif kind == 1:
            del lines[i]
        elif kind == 2:
            lines.insert(i, lines[i])
        elif kind == 3 and "=" in lines[i]:
            key = lines[i].split("=")[0].strip()
            lines[i] = f"{key[:-1] or 'x'} = 1.0"
        elif kind == 4:
            lines = lines[:i + 1]
        elif "=" in lines[i]:
            key = lines[i].split("=")[0]
            lines[i] = f"{key}= {rng.choice(['2e70', '1e308', '-1.0', '0.0', 'nan', '-0.0'])}"
    data = ("\n".join(lines) + "\n").encode()
    return _bytes_damage(rng, data)


def _outcome(function, path: Path):
    """The result, or None after a one-line InputError naming ``path``; warnings checked."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with time_limit(LIMIT):
                return function()
        except InputError as error:
            message = str(error)
            assert message and "\n" not in message, message
            assert message.startswith(str(path)), message
            return None
        finally:
            for w in caught:
                assert issubclass(w.category, GsfricWarning), (w.category, str(w.message))
                assert "\n" not in str(w.message)


def _cli(argv: list[str], folder: Path, source: Path) -> None:
    before = source.read_bytes() if source.is_file() else None
    with time_limit(LIMIT):
        result = CliRunner().invoke(main, argv, catch_exceptions=False)
    # 1: a check failed, the share of flagged steps above its limit (a damaged pose)
    assert result.exit_code in (0, 1, 2), (result.exit_code, result.output)
    lines = [x for x in result.stderr.splitlines() if x]
    assert all(x.startswith(("gsfric: error:", "gsfric: warning:")) for x in lines), lines
    errors = [x for x in lines if x.startswith("gsfric: error:")]
    assert len(errors) == (result.exit_code != 0)
    assert result.exit_code != 1 or "are flagged by the model" in errors[0]
    assert (source.read_bytes() if source.is_file() else None) == before
    assert not [p for p in folder.iterdir() if ".gsfric-" in p.name]


@pytest.mark.slow
@pytest.mark.parametrize("part", range(10))
def test_damaged_csv_files(tmp_path, part):
    def finite(motion):
        assert np.isfinite(motion.acceleration).all() and np.isfinite(motion.alpha).all()

    _fuzz(tmp_path, [20261127, part], damaged_csv, "t{k}.csv", read_trajectory, finite,
          lambda path, out: ["simulate", "--trajectory", str(path), "--out", str(out),
                             "--no-progress"], tmp_path / "o.csv")


@pytest.mark.slow
@pytest.mark.parametrize("part", range(10))
def test_damaged_toml_files(tmp_path, part):
    def plausible(platform):
        assert 0 <= platform.gravity <= 100

    _fuzz(tmp_path, [20261128, part], damaged_toml, "p{k}.toml", Platform.from_toml, plausible,
          lambda path, out: ["export", "--platform", str(path), "--out", str(out)],
          tmp_path / "x")


def _fuzz(folder: Path, seed, damage, name: str, load, check, command, out: Path) -> None:
    """``INPUTS // 10`` damaged files (``damage(rng)``, named ``name.format(k=k)``): each
    loads and passes ``check``, or fails in one line (``_outcome``); every ``CLI_EVERY``-th
    one also goes through the command line (``command(path, out)``, ``_cli``), its output
    ``out`` removed after."""
    rng = np.random.default_rng(seed)
    for k in range(INPUTS // 10):
        path = folder / name.format(k=k)
        path.write_bytes(damage(rng))
        loaded = _outcome(lambda: load(path), path)
        if loaded is not None:
            check(loaded)
        if k % CLI_EVERY == 0:
            _cli(command(path, out), folder, path)
            _rmtree(out)
        path.unlink()


def _rmtree(path: Path) -> None:
    """Remove a file or a folder, if there."""
    if not path.is_dir():
        path.unlink(missing_ok=True)
        return
    for child in sorted(path.rglob("*"), reverse=True):
        child.rmdir() if child.is_dir() else child.unlink()
    path.rmdir()
