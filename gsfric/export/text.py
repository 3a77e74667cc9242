"""The C text of an export that depends on the platform and the manifest: constants, layouts.

Every offset and size comes from the manifest (``gsfric.compiled.manifest``); numbers are
written with ``repr`` (the shortest text that reads back as the same double), so the baked-in
parameters are the platform's bit for bit.
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass

import numpy as np

from gsfric.compiled.manifest import function, layout
from gsfric.errors import InputError
from gsfric.evaluation import flags


@dataclass(frozen=True)
class Output:
    """One output of the exported evaluation, as a member of ``<prefix>_outputs``.

    Attributes
    ----------
    name : str
        The manifest's name (a C identifier), e.g. ``R_E``.
    index : int
        Its place among the generated function's outputs.
    size : int
        Values per step.
    shape : tuple of int
        Its shape per step (``()`` a scalar), row-major in the flat output.
    unit, description : str
        From the manifest.
    """

    name: str
    index: int
    size: int
    shape: tuple[int, ...]
    unit: str
    description: str

    def declaration(self) -> str:
        """The struct member: ``double R_E[6][3];`` with a comment."""
        dims = "".join(f"[{n}]" for n in self.shape) or "[1]"
        return f"    double {self.name}{dims};  /* {self.unit or '1'}: {self.description} */"

    def pointer(self, owner: str) -> str:
        """An expression for the first value of this member of ``owner`` (a pointer)."""
        zeros = "[0]" * max(len(self.shape), 1)
        return f"&{owner}->{self.name}{zeros}"


def outputs(function_name: str) -> list[Output]:
    """The outputs of generated function ``function_name`` (manifest order)."""
    return [Output(o["name"], k, int(o["size"]), tuple(o.get("shape") or ()), o.get("unit", ""),
                   o.get("description", ""))
            for k, o in enumerate(function(function_name)["outputs"])]


def number(value: float, what: str) -> str:
    """A double as C text that reads back bit for bit; ``InputError`` when not finite."""
    value = float(value)
    if not math.isfinite(value):
        raise InputError(f"{what}: {value} cannot be exported (not a finite number)")
    text = repr(value)
    return text if any(c in text for c in ".en") else text + ".0"


def initializer(function_name: str, input_name: str, vector: np.ndarray) -> str:
    """A brace initializer of a packed input, one block of the layout a line with its name."""
    lines = []
    for block in layout(function_name, input_name):
        start = block["offset"]
        stop = start + math.prod(block["shape"])
        values = ", ".join(number(v, f"{input_name}.{block['name']}")
                           for v in vector[start:stop])
        unit = block.get("unit") or "1"
        lines.append(f"    {values}, /* {block['name']} ({unit}) */")
    return "{ \\\n" + " \\\n".join(lines) + " \\\n}"


def state_macros(prefix: str) -> str:
    """``#define PREFIX_STATE_<BLOCK> offset`` for every block of the state x, with its unit."""
    upper = prefix.upper()
    lines = []
    for block in layout("eval", "x"):
        shape = "x".join(str(n) for n in block["shape"])
        lines.append(f"#define {upper}_STATE_{block['name'].upper()} {block['offset']}"
                     f"  /* [{shape}] {block.get('unit') or '1'}: {block['description']} */")
    return "\n".join(lines)


def flag_macros(prefix: str) -> str:
    """``#define PREFIX_FLAG_<NAME> bit`` for every step flag, with what it means."""
    upper = prefix.upper()
    return "\n".join(f"#define {upper}_FLAG_{name} {bit}  /* {flags.FLAG_NAMES[bit]} */"
                     for name, bit in flags.FLAG_BITS.items())


def flag_settings(spec) -> str:
    """The initializer of the C ``gsfric_flags`` from a ``FlagSpec`` (its fields in order)."""
    values = []
    for name, kind in spec._fields_:
        value = getattr(spec, name)
        values.append(number(value, f"flag setting {name}") if kind is ctypes.c_double
                      else str(int(value)))
    return "{" + ", ".join(values) + "}"


def comment(text: str) -> str:
    """``text`` as the lines of a C block comment (`` * `` before each, ``*/`` broken)."""
    return "\n".join((" * " + line.replace("*/", "* /")).rstrip()
                     for line in text.splitlines())
