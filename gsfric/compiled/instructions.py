"""CasADi's instruction list as C: the one table of operations and the one reading of the list.

A CasADi SX function is a list of instructions, each writing one work slot from the slots
(or the input entries, or a constant) it reads; CasADi reuses the slots, so an operand is the
value of the last instruction that wrote its slot. ``read`` resolves that once and gives each
instruction its operands as instruction indices; ``divisors`` counts how each value is used
as a divisor, and ``reciprocal`` is the rule by which a divisor is printed as one reciprocal
and products (the rewriting ``-freciprocal-math`` allows a compiler: about an ulp per
quotient).

Two printers read it: the batch code of ``gsfric simulate`` (derive/simd.py: every value a
vector of steps, the ``vector`` text of ``OPERATIONS``) and the specialised build of
``gsfric export`` (``gsfric.export.folded``: one step, straight-line C, the ``scalar`` text:
CasADi's own code generator's).
"""

from __future__ import annotations

from dataclasses import dataclass

from gsfric.errors import GsfricError


@dataclass(frozen=True)
class Operation:
    """The C text of one CasADi operation, ``{0}`` and ``{1}`` its operands.

    Attributes
    ----------
    arity : int
        1 or 2.
    scalar : str
        CasADi's C text (its code generator's; helpers such as ``casadi_sq`` come from
        generated/gsfric_model.c).
    vector : str or None
        The text on vectors of steps (the ``v_*`` functions of the batch code's header), or
        None where the batch code has none.
    """

    arity: int
    scalar: str
    vector: str | None = None


def _unary(scalar: str, vector: str | None = None) -> Operation:
    return Operation(1, scalar, vector)


def _binary(scalar: str, vector: str | None = None) -> Operation:
    return Operation(2, scalar, vector)


OPERATIONS = {
    "OP_ASSIGN": _unary("{0}", "{0}"), "OP_NEG": _unary("(-{0})", "-{0}"),
    "OP_EXP": _unary("exp({0})", "v_exp({0})"), "OP_LOG": _unary("log({0})", "v_log({0})"),
    "OP_SQRT": _unary("sqrt({0})", "v_sqrt({0})"),
    "OP_SQ": _unary("casadi_sq({0})", "{0} * {0}"),
    "OP_TWICE": _unary("(2.*{0})", "{0} + {0}"),
    "OP_SIN": _unary("sin({0})", "v_sin({0})"), "OP_COS": _unary("cos({0})", "v_cos({0})"),
    "OP_TAN": _unary("tan({0})", "v_tan({0})"), "OP_ASIN": _unary("asin({0})"),
    "OP_ACOS": _unary("acos({0})"), "OP_ATAN": _unary("atan({0})"),
    "OP_NOT": _unary("(!{0})", "v_not({0})"),
    "OP_FLOOR": _unary("floor({0})", "v_floor({0})"),
    "OP_CEIL": _unary("ceil({0})", "v_ceil({0})"),
    "OP_FABS": _unary("casadi_fabs({0})", "v_fabs({0})"),
    "OP_SIGN": _unary("casadi_sign({0})", "v_sign({0})"), "OP_ERF": _unary("erf({0})"),
    "OP_INV": _unary("(1./{0})", "v_inv({0})"), "OP_SINH": _unary("sinh({0})"),
    "OP_COSH": _unary("cosh({0})"), "OP_TANH": _unary("tanh({0})", "v_tanh({0})"),
    "OP_ASINH": _unary("asinh({0})"), "OP_ACOSH": _unary("acosh({0})"),
    "OP_ATANH": _unary("atanh({0})"), "OP_LOG1P": _unary("casadi_log1p({0})"),
    "OP_EXPM1": _unary("casadi_expm1({0})"),
    "OP_ADD": _binary("({0}+{1})", "{0} + {1}"), "OP_SUB": _binary("({0}-{1})", "{0} - {1}"),
    "OP_MUL": _binary("({0}*{1})", "{0} * {1}"), "OP_DIV": _binary("({0}/{1})", "{0} / {1}"),
    "OP_POW": _binary("pow({0},{1})", "v_pow({0}, {1})"),
    "OP_CONSTPOW": _binary("pow({0},{1})", "v_pow({0}, {1})"),
    "OP_LT": _binary("({0}<{1})", "v_lt({0}, {1})"),
    "OP_LE": _binary("({0}<={1})", "v_le({0}, {1})"),
    "OP_EQ": _binary("({0}=={1})", "v_eq({0}, {1})"),
    "OP_NE": _binary("({0}!={1})", "v_ne({0}, {1})"),
    "OP_AND": _binary("({0}&&{1})", "v_and({0}, {1})"),
    "OP_OR": _binary("({0}||{1})", "v_or({0}, {1})"), "OP_FMOD": _binary("fmod({0},{1})"),
    "OP_COPYSIGN": _binary("copysign({0},{1})", "v_copysign({0}, {1})"),
    "OP_IF_ELSE_ZERO": _binary("({0}?{1}:0)", "v_if_else_zero({0}, {1})"),
    "OP_FMIN": _binary("casadi_fmin({0},{1})", "v_fmin({0}, {1})"),
    "OP_FMAX": _binary("casadi_fmax({0},{1})", "v_fmax({0}, {1})"),
    "OP_ATAN2": _binary("atan2({0},{1})", "v_atan2({0}, {1})"),
    "OP_HYPOT": _binary("casadi_hypot({0},{1})"),
    "OP_REMAINDER": _binary("remainder({0},{1})"),
}
"""Every operation a printer knows, by the name of its CasADi opcode."""


@dataclass(frozen=True)
class Instruction:
    """One instruction of a CasADi SX function, its operands resolved.

    Attributes
    ----------
    index : int
        Its place in the list (the name of the value it defines).
    op : str
        The opcode's name: ``OP_INPUT``, ``OP_CONST``, ``OP_OUTPUT`` or a key of ``OPERATIONS``.
    args : tuple of int
        The instructions whose values it reads (an output: the one it stores).
    slot : int
        The work slot it writes (an output: the output's index).
    entry : int
        For an input or an output, the entry of it (-1 otherwise).
    source : int
        For an input, the input's index (-1 otherwise).
    constant : float or None
        For a constant, its value.
    invariant : bool
        Its value depends on constants and on inputs other than input 0 only (the same for
        every step of a batch).
    """

    index: int
    op: str
    args: tuple[int, ...]
    slot: int
    entry: int = -1
    source: int = -1
    constant: float | None = None
    invariant: bool = False


def read(fn, opnames: dict[int, str]) -> list[Instruction]:
    """The instructions of the CasADi SX function ``fn``, operands resolved (see the module).

    ``opnames`` maps CasADi's opcode numbers to their names (``opcode_names(casadi)``).
    ``GsfricError`` names an operation that ``OPERATIONS`` does not know.
    """
    writer: dict[int, int] = {}          # work slot -> the instruction that wrote it last
    out: list[Instruction] = []
    for k in range(fn.n_instructions()):
        op = opnames[fn.instruction_id(k)]
        i, o = fn.instruction_input(k), fn.instruction_output(k)
        if op == "OP_OUTPUT":
            a = writer[i[0]]
            out.append(Instruction(k, op, (a,), o[0], o[1], -1, None, out[a].invariant))
            continue
        if op == "OP_INPUT":
            item = Instruction(k, op, (), o[0], i[1], i[0], None, i[0] != 0)
        elif op == "OP_CONST":
            item = Instruction(k, op, (), o[0], constant=float(fn.instruction_constant(k)),
                               invariant=True)
        elif op in OPERATIONS:
            args = tuple(writer[i[j]] for j in range(OPERATIONS[op].arity))
            item = Instruction(k, op, args, o[0],
                               invariant=all(out[a].invariant for a in args))
        else:
            raise GsfricError(f"{fn.name()}: operation {op} has no C text")
        writer[o[0]] = k
        out.append(item)
    return out


def opcode_names(casadi) -> dict[int, str]:
    """CasADi's opcode numbers -> names (``OP_ADD``, ...), of the module ``casadi``."""
    return {getattr(casadi, n): n for n in dir(casadi)
            if n.startswith("OP_") and isinstance(getattr(casadi, n), int)}


@dataclass(frozen=True)
class Uses:
    """How the value of one instruction is used.

    Attributes
    ----------
    uses : int
        Reads of it (by instructions and outputs).
    divisions : int
        Reads as the divisor of a division.
    varying : int
        Of those, divisions that are not invariant (in a batch, done at every step).
    """

    uses: int
    divisions: int
    varying: int


def divisors(instructions: list[Instruction]) -> list[Uses]:
    """The ``Uses`` of every instruction's value, by instruction index."""
    count = [[0, 0, 0] for _ in instructions]
    for item in instructions:
        for pos, a in enumerate(item.args):
            count[a][0] += 1
            if item.op == "OP_DIV" and pos == 1:
                count[a][1] += 1
                count[a][2] += not item.invariant
    return [Uses(*c) for c in count]


def reciprocal(item: Instruction, uses: Uses) -> bool:
    """Whether the divisor ``item`` is printed as one reciprocal and products: when it is
    invariant (computed once, outside a batch's loop) and divides a value that is not, or when
    it divides two values or more."""
    if item.invariant:
        return uses.varying > 0
    return uses.divisions >= 2
