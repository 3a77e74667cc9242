"""The folded build of an export: the model with the platform's numbers folded in, as C.

For an exported library the platform's parameters are constants, so ``folded_function`` calls
the generated function (CasADi's, as serialized in generated/) on a symbolic state with the
parameter vector P and the effect vector Q as numbers: every value that depends on the
platform only (geometry, inertia, friction coefficients, effects that are off) is computed once,
by CasADi in double precision, and what remains depends on the state. Repeated subexpressions
are then merged (``casadi.cse``: the same operation on the same operands, so the same value).

``statements`` prints such a function as straight-line C, one ``const double`` per value in
CasADi's order of operations, with CasADi's own C text for each operation (its helpers, e.g.
``casadi_sq``, come from generated/gsfric_model.c, ``source.helper_text``); ``function_text``
makes a C function of the statements some of the outputs need, so that the one-step function
of ``<prefix>_actuator_forces`` computes its outputs with exactly the statements of the full
evaluation. Divisions are the costly operations of the model (a division takes the time of
several products); by the rule of the batch code of ``gsfric simulate`` (derive/simd.py), the
same reading of the instruction list (``gsfric.compiled.instructions``), a divisor of several
divisions is printed as one reciprocal and products, and a constant divisor as a product with
its reciprocal: the rewriting ``-freciprocal-math`` allows a compiler, which changes a quotient
by about an ulp. Nothing else differs from CasADi's code: no reassociation,
no contraction into fused multiply-adds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gsfric._optional import optional
from gsfric.compiled.instructions import (
    OPERATIONS,
    Instruction,
    Uses,
    divisors,
    opcode_names,
    read,
    reciprocal,
)
from gsfric.compiled.native import serialized
from gsfric.errors import GsfricError
from gsfric.evaluation.parameters import effect_vector, parameter_vector
from gsfric.export.text import number
from gsfric.platform.description import Platform


def folded_function(name: str, platform: Platform, outputs: list[str]):
    """Generated function ``gsfric_model_<name>`` of the state alone, ``platform`` folded in.

    Parameters
    ----------
    name : str
        A generated function of inputs (x, P, Q), e.g. ``eval_coupled``.
    platform : Platform
        Gives P (``parameter_vector``) and Q (``effect_vector``), as numbers.
    outputs : list of str
        The outputs kept, in this order (dense).

    Returns
    -------
    casadi.Function
        ``x (24,) -> outputs``, repeated subexpressions merged.
    """
    casadi = optional("casadi")
    fn = serialized(name)
    numbers = {"P": parameter_vector(platform), "Q": effect_vector(platform)}
    x = casadi.SX.sym("x", fn.size1_in(0))
    args = [x]
    for k in range(1, fn.n_in()):
        if fn.name_in(k) not in numbers:
            raise GsfricError(f"{fn.name()}: input {fn.name_in(k)} cannot be folded")
        args.append(casadi.DM(np.asarray(numbers[fn.name_in(k)], dtype=float)))
    values = fn.call(args)
    names = fn.name_out()
    missing = [o for o in outputs if o not in names]
    if missing:
        raise GsfricError(f"{fn.name()} has no output {missing[0]}; run `gsfric derive`")
    kept = casadi.cse([casadi.densify(values[names.index(o)]) for o in outputs])
    return casadi.Function(f"{name}_folded", [x], kept, ["x"], list(outputs))


@dataclass(frozen=True)
class Statement:
    """One line of straight-line C.

    Attributes
    ----------
    name : str
        The value it defines (``v12``, a reciprocal ``r12``), or "" for a store to an output.
    uses : tuple of str
        The values it reads.
    output : int
        The output it stores into (-1: none).
    text : str
        The C statement.
    """

    name: str
    uses: tuple[str, ...]
    output: int
    text: str


@dataclass(frozen=True)
class _Value:
    """A value's C text, the instruction that made it, its number if it is a constant, and
    the statement values it reads (its own name, or none for a constant or an input)."""

    text: str
    index: int
    constant: float | None = None
    name: tuple[str, ...] = ()


def _constant(value: float) -> str:
    if math.isnan(value):
        return "NAN"
    if math.isinf(value):
        return "HUGE_VAL" if value > 0 else "(-HUGE_VAL)"
    text = number(value, "constant")
    return f"({text})" if text.startswith("-") else text


def _division(a: _Value, b: _Value, item: Instruction, uses: Uses, reciprocals: dict,
              statements: list[Statement]) -> tuple[str, tuple[str, ...]]:
    """(C text, values read) of a / b: a product by a reciprocal where
    ``instructions.reciprocal`` says so (a constant's computed here, when finite)."""
    if b.index not in reciprocals:
        if not reciprocal(item, uses):
            return f"({a.text}/{b.text})", a.name + b.name
        if b.constant is not None:
            if b.constant == 0 or not math.isfinite(1.0 / b.constant):
                return f"({a.text}/{b.text})", a.name + b.name
            reciprocals[b.index] = _Value(_constant(1.0 / b.constant), b.index)
        else:
            name = f"r{b.index}"
            statements.append(Statement(name, b.name, -1, f"const double {name} = 1./{b.text};"))
            reciprocals[b.index] = _Value(name, b.index, None, (name,))
    r = reciprocals[b.index]
    return f"({a.text}*{r.text})", a.name + r.name


def statements(fn, output_index: list[str], arg: str = "x") -> list[Statement]:
    """``fn`` (a function of one dense input ``arg``) as straight-line C statements.

    Parameters
    ----------
    fn : casadi.Function
        SX function of one dense input, e.g. ``folded_function``.
    output_index : list of str
        The C index into ``res`` of each output of ``fn``: its values are stored as
        ``res[<index>][j] = ...;``.
    arg : str
        The C name of the input (a ``const double *``).
    """
    try:
        program = read(fn, opcode_names(optional("casadi")))
    except GsfricError as exc:
        raise GsfricError(f"{exc} in the specialised build; export with --code generic") from None
    uses, reciprocals = divisors(program), {}
    values: dict[int, _Value] = {}
    out: list[Statement] = []
    for item in program:
        i = item.index
        if item.op == "OP_OUTPUT":
            value = values[item.args[0]]
            out.append(Statement("", value.name, item.slot,
                                 f"res[{output_index[item.slot]}][{item.entry}] = {value.text};"))
            continue
        if item.op == "OP_INPUT":
            values[i] = _Value(f"{arg}[{item.entry}]", i)
            continue
        if item.op == "OP_CONST":
            values[i] = _Value(_constant(item.constant), i, item.constant)
            continue
        a = [values[k] for k in item.args]
        if item.op == "OP_DIV":
            expr, read_ = _division(a[0], a[1], program[item.args[1]], uses[item.args[1]],
                                    reciprocals, out)
        else:
            expr = OPERATIONS[item.op].scalar.format(*(v.text for v in a))
            read_ = tuple(n for v in a for n in v.name)
        out.append(Statement(f"v{i}", read_, -1, f"const double v{i} = {expr};"))
        values[i] = _Value(f"v{i}", i, None, (f"v{i}",))
    return out


def function_text(body: list[Statement], c_name: str, outputs=None) -> str:
    """``static void c_name(const double *x, double **res)`` of the statements ``body``
    that the outputs ``outputs`` need (indices of ``fn``'s outputs; None: all), in order.
    The outputs it stores into must not be NULL."""
    keep = [s.output >= 0 and (outputs is None or s.output in outputs) for s in body]
    needed: set[str] = set()
    for k in range(len(body) - 1, -1, -1):
        if keep[k] or body[k].name in needed:
            keep[k] = True
            needed.update(body[k].uses)
    lines = [f"    {s.text}" for s, kept in zip(body, keep) if kept]
    return "\n".join([f"static void {c_name}(const double *x, double **res)", "{", *lines,
                      "}"]) + "\n"
