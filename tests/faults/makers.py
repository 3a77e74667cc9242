"""Makers of the fault cases' files: ``maker(folder) -> Path`` writes one file (or link, FIFO,
folder) into the case's folder."""

from __future__ import annotations

import functools
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
from helpers import trajectory_frame

from gsfric import models

Maker = Callable[[Path], Path]
ROWS = 100
"""Rows of the base trajectory file: enough for the differentiation, quick to evaluate."""


@functools.cache
def base_frame():
    """The base file's columns: a trajectory (t, x, y, z, a quaternion) and measured forces
    F1..F6 (N) at 100 Hz."""
    frame = trajectory_frame(ROWS)
    rng = np.random.default_rng(7)
    for i in range(1, 7):
        frame[f"F{i}"] = 40.0 + rng.normal(0, 1, ROWS)
    return frame


@functools.cache
def base_csv() -> str:
    return base_frame().to_csv(index=False)


@functools.cache
def platform_text() -> str:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder, "p.toml")
        models.reference_platform().to_toml(path)
        return path.read_text()


def content(name: str, data: str | bytes | Callable[[], str | bytes]) -> Maker:
    """A file ``name`` holding ``data`` (or what ``data()`` returns)."""
    def make(folder: Path) -> Path:
        value = data() if callable(data) else data
        path = folder / name
        if isinstance(value, bytes):
            path.write_bytes(value)
        else:
            path.write_text(value)
        return path
    return make


def csv_edit(name: str, edit: Callable[[list[str]], list[str]], newline: str = "\n") -> Maker:
    """The base CSV with its lines (header first) passed through ``edit``."""
    return content(name, lambda: newline.join(edit(base_csv().splitlines())) + newline)


def cell(row: int, column: str, value: str) -> Callable[[list[str]], list[str]]:
    """A CSV edit (for ``csv_edit``): data row ``row`` (1-based) of ``column`` set to
    ``value``."""
    def edit(lines):
        header = lines[0].split(",")
        cells = lines[row].split(",")
        cells[header.index(column)] = value
        return [*lines[:row], ",".join(cells), *lines[row + 1:]]
    return edit


def frame_edit(name: str, edit: Callable) -> Maker:
    """The base frame through ``edit(frame) -> frame``, written as CSV or Parquet by name."""
    def make(folder: Path) -> Path:
        frame = edit(base_frame().copy())
        path = folder / name
        if name.endswith(".parquet"):
            frame.to_parquet(path, index=False)
        else:
            frame.to_csv(path, index=False)
        return path
    return make


def trajectory(name: str = "t.csv") -> Maker:
    return frame_edit(name, lambda f: f)


def long_trajectory(name: str = "t.csv", rows: int = 5000) -> Maker:
    """A trajectory of ``rows`` rows (enough for several threads: 2048 steps each)."""
    def make(folder: Path) -> Path:
        trajectory_frame(rows).to_csv(folder / name, index=False)
        return folder / name
    return make


def platform(name: str = "p.toml", edit: Callable[[str], str] | None = None) -> Maker:
    return content(name, lambda: (edit or (lambda t: t))(platform_text()))


def set_key(key: str, value: str) -> Callable[[str], str]:
    """A TOML edit: the first line ``key = ...`` set to ``value``."""
    def edit(text: str) -> str:
        lines = text.splitlines()
        for k, line in enumerate(lines):
            if line.split("=")[0].strip() == key:
                lines[k] = f"{key} = {value}"
                return "\n".join(lines) + "\n"
        raise KeyError(key)
    return edit


def folder(name: str) -> Maker:
    def make(base: Path) -> Path:
        (base / name).mkdir()
        return base / name
    return make


def missing(name: str) -> Maker:
    return lambda base: base / name


def symlink(name: str, target: str) -> Maker:
    def make(base: Path) -> Path:
        (base / name).symlink_to(base / target)
        return base / name
    return make


def fifo(name: str) -> Maker:
    def make(base: Path) -> Path:
        os.mkfifo(base / name)
        return base / name
    return make


def old_output(name: str, text: str = "earlier output\n") -> Maker:
    """An earlier output of the same name (a file the run may replace on success only)."""
    return content(name, text)


def rig(name: str = "r.toml") -> Maker:
    """A rig TOML (``gsfric platform --template --rig``): the reference platform's sizes."""
    from gsfric.platform.rig import Rig, rig_toml
    return content(name, lambda: rig_toml(Rig.from_platform(models.reference_platform())))


def column_map(name: str = "map.toml") -> Maker:
    """A column-map TOML that maps the base file's columns to themselves."""
    return content(name, '[columns]\nt = "t"\nx = "x"\n')


def workspace(name: str = "ws.toml") -> Maker:
    """A workspace TOML (its content is not read by the cases that use it)."""
    return content(name, "[pose]\n")


def inside(folder_name: str, maker: Maker) -> Maker:
    """``maker``'s file made inside the folder ``folder_name`` (created) of the case's
    folder."""
    def make(base: Path) -> Path:
        (base / folder_name).mkdir(exist_ok=True)
        return maker(base / folder_name)
    return make
