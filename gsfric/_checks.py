"""Validation helpers shared by the platform, trajectory and I/O modules (private)."""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from gsfric.errors import InputError, InputTypeError

INT64_MAX = 2**63 - 1
"""The largest integer a file may hold (TOML's integers are 64-bit; a larger one is a typo or
garbage, never a physical value)."""


def short(value: object, limit: int = 40) -> str:
    """``repr(value)``, cut to ``limit`` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def suggest(name: str, choices: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``choices`` (case-insensitive), or ``""``."""
    choices = list(choices)
    lowered = {c.lower(): c for c in choices}
    match = difflib.get_close_matches(str(name).lower(), list(lowered), n=1, cutoff=0.6)
    return f" (did you mean {lowered[match[0]]!r}?)" if match else ""


def is_number(value: object) -> bool:
    """True for a real number (int, float, NumPy integer or floating); False for bool."""
    if isinstance(value, (bool, np.bool_)):
        return False
    return isinstance(value, (int, float, np.integer, np.floating))


def as_float(value: object, name: str, *, minimum: float | None = None) -> float:
    """A finite float from ``value``; ``InputError`` naming ``name`` otherwise
    (``InputTypeError`` when ``value`` is not a number at all).

    ``minimum``, if given, is an inclusive lower bound.
    """
    if isinstance(value, np.ndarray) and value.shape == ():
        value = value[()]
    if not is_number(value):
        raise InputTypeError(f"{name}: expected a number, got {short(value)}")
    if isinstance(value, int) and abs(value) > INT64_MAX:
        raise InputError(f"{name}: integer too large ({short(value)}, beyond 64 bits)")
    try:
        result = float(value)
    except OverflowError:
        raise InputError(f"{name}: number too large: {short(value)}") from None
    if not math.isfinite(result):
        raise InputError(f"{name}: must be finite, got {result}")
    if minimum is not None and result < minimum:
        raise InputError(f"{name}: must be >= {minimum:g}, got {result:g}")
    return result


def as_count(value: object, name: str, *, minimum: int = 1, maximum: int | None = None) -> int:
    """An integer in [minimum, maximum] from ``value`` (int or NumPy integer, not bool).

    Raises
    ------
    InputTypeError
        ``value`` is not an integer (a float, a string, None, a bool), naming ``name``.
    InputError
        ``value`` is outside the range, naming ``name`` and the range.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InputTypeError(f"{name}: expected an integer, got {short(value)}")
    value = int(value)
    if value < minimum or (maximum is not None and value > maximum):
        bound = f">= {minimum}" if maximum is None else f"from {minimum} to {maximum}"
        raise InputError(f"{name}: must be an integer {bound}, got {value}")
    return value


def as_flag(value: object, name: str) -> bool:
    """``value`` as a bool (bool or NumPy bool only); ``InputTypeError`` naming ``name``."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputTypeError(f"{name}: expected True or False, got {short(value)}")
    return bool(value)


def as_path(value: object, name: str) -> Path:
    """``value`` (str or os.PathLike, not empty) as a Path; ``InputTypeError`` naming ``name``."""
    if isinstance(value, bytes) or not isinstance(value, (str, os.PathLike)):
        raise InputTypeError(f"{name}: expected a file path (str or pathlib.Path), "
                             f"got {short(value)}")
    path = Path(value)
    if str(value) == "":
        raise InputError(f"{name}: the path is empty")
    return path


def _shape_text(shape: tuple[int | None, ...]) -> str:
    parts = ["N" if n is None else str(n) for n in shape]
    return "(" + ", ".join(parts) + ("," if len(parts) == 1 else "") + ")"


def _check_leaves(value: object, depth: int, ndim: int, name: str, shape_text: str) -> None:
    if isinstance(value, (list, tuple)):
        if depth >= ndim:
            raise InputError(f"{name}: expected an array of shape {shape_text}, nested too deeply")
        for item in value:
            _check_leaves(item, depth + 1, ndim, name, shape_text)
    elif not is_number(value):
        raise InputTypeError(f"{name}: expected an array of shape {shape_text} of numbers, "
                             f"found {short(value)}")
    elif isinstance(value, int) and abs(value) > INT64_MAX:
        raise InputError(f"{name}: integer too large ({short(value)}, beyond 64 bits)")


def as_array(value: object, shape: tuple[int | None, ...], name: str) -> np.ndarray:
    """A read-only float64 array of ``shape`` (``None`` matches any length) with finite entries.

    Accepts NumPy arrays of integer or floating type and nested lists or tuples of numbers;
    anything else raises an ``InputTypeError``, a different shape or a non-finite entry an
    ``InputError``, naming ``name``.
    """
    shape_text = _shape_text(shape)
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf":
            raise InputTypeError(f"{name}: expected an array of numbers, got dtype "
                                 f"{value.dtype}")
        array = np.array(value, dtype=float)
    else:
        _check_leaves(value, 0, len(shape), name, shape_text)
        try:
            array = np.array(value, dtype=float)
        except OverflowError:
            raise InputError(f"{name}: number too large") from None
        except (ValueError, TypeError):
            raise InputError(f"{name}: expected an array of shape {shape_text}, "
                             "got rows of different lengths") from None
    if array.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(array.shape, shape)
    ):
        raise InputError(f"{name}: expected an array of shape {shape_text}, got {array.shape}")
    bad = np.argwhere(~np.isfinite(array))
    if len(bad):
        index = "".join(f"[{i}]" for i in bad[0])
        raise InputError(f"{name}{index}: must be finite, got {array[tuple(bad[0])]}")
    array.setflags(write=False)
    return array


def fields_equal(a: object, b: object) -> bool:
    """Field-by-field equality of two dataclass instances, arrays compared with array_equal."""
    if type(a) is not type(b):
        return False
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if not (isinstance(x, np.ndarray) and isinstance(y, np.ndarray)
                    and x.shape == y.shape and np.array_equal(x, y)):
                return False
        elif x != y:
            return False
    return True
