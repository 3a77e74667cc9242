"""The output columns of ``gsfric simulate``: the groups chosen, and each chunk's columns built from its evaluation.

The columns are those of the chosen groups (``DEFAULT_COLUMN_GROUPS`` unless told; the formats
are described in docs/reference/formats.md), ``t`` and ``flag`` always; a measured-data file's forces and
residuals and the kept input columns are appended (``with_carried``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsfric.errors import InputError
from gsfric.evaluation.columns import DEFAULT_GROUPS as DEFAULT_COLUMN_GROUPS
from gsfric.evaluation.columns import GROUPS as COLUMN_GROUPS

FLOAT32_RTOL = 2.0 ** -24
"""Relative rounding error of an output written as float32 (``--float32``): half an ulp."""

TRANSPOSE_BLOCK = 2048
"""Steps per block of the row-major to column-major copies of ``result_columns``: a block of a
Result array stays in the cache while its columns are written (twice as fast as one strided
copy of the whole array)."""


def parse_columns(text: str | None) -> tuple[str, ...]:
    """Output groups from ``--columns`` ("forces,friction"; None: ``DEFAULT_COLUMN_GROUPS``,
    "all": every group of ``COLUMN_GROUPS``)."""
    if text is None:
        return tuple(DEFAULT_COLUMN_GROUPS)
    if text.strip() == "all":
        return tuple(COLUMN_GROUPS)
    chosen = tuple(dict.fromkeys(g.strip() for g in text.split(",") if g.strip()))
    unknown = [g for g in chosen if g not in COLUMN_GROUPS]
    if unknown or not chosen:
        raise InputError(f"--columns: unknown group {unknown[0] if unknown else text!r}; "
                         f"choose from {', '.join(COLUMN_GROUPS)} (comma-separated) or all")
    return chosen


@dataclass
class ChunkOutputs:
    """What ``result_columns`` reads of a chunk's evaluation.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Times, s.
    arrays : dict of str -> ndarray (N, ...)
        The evaluated outputs by name (``evaluate_outputs``).
    flag : ndarray, shape (N,)
        Step flags.
    """

    t: np.ndarray
    arrays: dict[str, np.ndarray]
    flag: np.ndarray


def result_columns(result, plan, float32: bool = False, reuse: dict | None = None
                   ) -> dict[str, np.ndarray]:
    """The output columns of one Result (or ``ChunkOutputs``), each a contiguous 1-D array (one
    transposed copy per output array; nothing refers to the Result's buffers). ``plan``: the
    columns (``gsfric.evaluation.columns.plan``). ``reuse`` (a dict, filled on first use) lends
    the arrays of the columns from call to call: the columns are then valid until the next call
    with it."""
    n = len(result.t)
    dtype = np.float32 if float32 else np.float64
    keys = list(dict.fromkeys(key for _, key, _, _ in plan))
    blocks: dict[str, np.ndarray] = {}
    for key in keys:
        values = result.arrays[key].reshape(n, -1)
        buf = None if reuse is None else reuse.get(key)
        if buf is None or buf.shape[1] < n or buf.dtype != dtype:
            buf = np.empty((values.shape[1], n), dtype=dtype)
            if reuse is not None:
                reuse[key] = buf
        blocks[key] = buf[:, :n]
        _transpose_into(blocks[key], values)
    cols = {"t": np.array(result.t, dtype=np.float64)}
    cols.update((column, blocks[key][index]) for column, key, index, _ in plan)
    cols["flag"] = np.array(result.flag, dtype=np.int64)
    return cols


def _transpose_into(out: np.ndarray, rows: np.ndarray) -> None:
    """``out[:] = rows.T`` for rows (N, k) and out (k, N), block by block of steps."""
    n = rows.shape[0]
    for s in range(0, n, TRANSPOSE_BLOCK):
        np.copyto(out[:, s:s + TRANSPOSE_BLOCK], rows[s:s + TRANSPOSE_BLOCK].T,
                  casting="same_kind")


def delayed_columns(columns: dict[str, np.ndarray], plan, float32: bool,
                    carried: dict[str, np.ndarray], F: np.ndarray) -> dict[str, np.ndarray]:
    """A chunk's columns with the sensor's F (N, 6) in place of the mechanism's, and the
    carried columns appended (``with_carried``)."""
    dtype = np.float32 if float32 else np.float64
    columns = dict(columns)
    for column, key, index, _ in plan:
        if key == "F":
            columns[column] = np.array(F[:, index], dtype=dtype)
    return with_carried(columns, carried)


def with_carried(columns: dict[str, np.ndarray],
                 carried: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The output columns with measured forces, residuals (where the forces are written) and
    kept input columns appended."""
    extra = {}
    if "F1" in carried:
        for i in range(1, 7):
            extra[f"F{i}_measured"] = carried[f"F{i}"]
        if "F1" in columns:
            for i in range(1, 7):
                extra[f"F{i}_residual"] = carried[f"F{i}"] - columns[f"F{i}"]
    for key, values in carried.items():
        if key.startswith("keep:"):
            name = key[5:]
            if name in columns or name in extra:
                name = f"{name}_input"
            extra[name] = values
    return {**columns, **extra} if extra else columns
