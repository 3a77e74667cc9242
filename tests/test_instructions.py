"""The one reading of CasADi's instruction list (gsfric.compiled.instructions) and its two
printers: the batch code of derive/simd.py and the export's straight-line C."""

from __future__ import annotations

import math
import re

import casadi as ca
import numpy as np
import pytest

from derive import simd
from gsfric.compiled.instructions import divisors, opcode_names, read, reciprocal
from gsfric.errors import GsfricError
from gsfric.export import folded

_NUMPY = {"OP_ADD": np.add, "OP_SUB": np.subtract, "OP_MUL": np.multiply,
          "OP_DIV": np.divide, "OP_NEG": np.negative, "OP_SQ": np.square,
          "OP_SQRT": np.sqrt, "OP_EXP": np.exp, "OP_SIN": np.sin, "OP_COS": np.cos,
          "OP_TWICE": lambda a: 2.0 * a}


def _probe() -> ca.Function:
    """Outputs of x (4,) and a parameter p (1,): a divisor of two divisions (d), one of a
    single division (x1 + 7), a constant one (3), a parameter one (p), long enough that
    CasADi reuses its work slots."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 1)
    d = x[0] * x[0] + 1.5
    chain = x[2]
    for k in range(12):
        chain = ca.sin(chain + k) * ca.cos(x[k % 4]) - ca.exp(-x[3] * k)
    first = ca.vertcat(x[1] / d, x[2] / d, x[3] / 3.0, x[0] / (x[1] + 7.0), x[1] / p)
    return ca.Function("probe", [x, p], [first, chain * ca.sqrt(d)])


def _interpret(fn: ca.Function, inputs: list[np.ndarray]) -> list[np.ndarray]:
    """The outputs of ``fn`` computed from ``read``'s operands alone (no work slots)."""
    program = read(fn, opcode_names(ca))
    values: dict[int, float] = {}
    out = [np.zeros(fn.numel_out(j)) for j in range(fn.n_out())]
    for item in program:
        if item.op == "OP_OUTPUT":
            out[item.slot][item.entry] = values[item.args[0]]
        elif item.op == "OP_INPUT":
            values[item.index] = inputs[item.source][item.entry]
        elif item.op == "OP_CONST":
            values[item.index] = item.constant
        else:
            values[item.index] = _NUMPY[item.op](*(values[a] for a in item.args))
    return out


def test_operands_resolve_reused_work_slots():
    fn = _probe()
    assert fn.sz_w() < fn.n_instructions()       # slots are reused
    x, p = np.array([0.3, -1.2, 0.7, 2.0]), np.array([0.25])
    expected = [np.asarray(v).ravel() for v in fn(x, p)]
    for got, want in zip(_interpret(fn, [x, p]), expected):
        np.testing.assert_allclose(got, want, rtol=1e-15, atol=0.0)


def test_invariance_follows_the_parameter_inputs():
    program = read(_probe(), opcode_names(ca))
    by_op = {}
    for item in program:
        by_op.setdefault(item.op, []).append(item)
    assert all(i.invariant == (i.source != 0) for i in by_op["OP_INPUT"])
    assert all(i.invariant for i in by_op["OP_CONST"])
    uses = divisors(program)
    found = {(uses[i.args[1]].divisions, program[i.args[1]].invariant,
              reciprocal(program[i.args[1]], uses[i.args[1]])) for i in by_op["OP_DIV"]}
    # d: two divisions; x1 + 7: one, in the loop; 3 and p: invariant
    assert found == {(2, False, True), (1, False, False), (1, True, True)}


def test_both_printers_take_the_same_reciprocals():
    fn = _probe()
    batch = simd.batch_source(fn, "probe")
    assert batch.count("v_rcp(") == 1          # d, in the loop
    assert len(re.findall(r"const vd r\d+ = 1\.0 / h\d+;", batch)) == 2   # 3 and p, hoisted
    assert batch.count("v_div(") == 1          # x1 + 7
    x = ca.SX.sym("x", 4)
    single = ca.Function("single", [x], [fn(x, 0.25)[0]])     # p folded in, as an export
    text = folded.function_text(folded.statements(single, ["0"]), "single")
    assert text.count("= 1./") == 1            # d
    assert len(re.findall(r"\(x\[0\]/v\d+\)", text)) == 1  # x0 / (x1 + 7)
    assert "*0.3333333333333333)" in text and "*4.0)" in text   # 3 and p: products


def test_an_operation_without_text_is_named():
    x = ca.SX.sym("x", 2)
    fn = ca.Function("odd", [x], [ca.erf(x[0]) + x[1]])
    with pytest.raises(NotImplementedError, match="odd: no SIMD translation for OP_ERF"):
        simd.batch_source(fn, "odd")
    assert "erf(" in folded.function_text(folded.statements(fn, ["0"]), "odd")
    names = {**opcode_names(ca), ca.OP_ERF: "OP_UNKNOWN"}
    with pytest.raises(GsfricError, match="odd: operation OP_UNKNOWN has no C text"):
        read(fn, names)
    assert math.isfinite(float(fn(np.array([0.1, 0.2]))))
