"""C code that evaluates a CasADi function on several steps at once (SIMD over steps).

CasADi's own C code evaluates one step per call: a long chain of scalar operations. Here the
same chain of operations (CasADi's instruction list, with its work-vector slots) is printed so
that every slot holds ``LANES`` steps and every operation is a short loop over them, which the
compiler turns into vector instructions. The result is bit-for-bit the same arithmetic as
CasADi's code (the same operations in the same order) on ``LANES`` steps in parallel.

Generated function, for CasADi function ``f`` with inputs k and outputs j:

    void <prefix>_batch(const double **in, const long long *in_stride,
                        double **out, const long long *out_stride, long long n)

Step s reads input k at ``in[k] + s * in_stride[k]`` (stride 0 broadcasts) and writes output j
at ``out[j] + s * out_stride[j]`` (a NULL output is skipped).
"""

from __future__ import annotations

LANES = 4

_BINARY = {
    "OP_ADD": "{a} + {b}", "OP_SUB": "{a} - {b}", "OP_MUL": "{a} * {b}",
    "OP_DIV": "{a} / {b}", "OP_POW": "v_pow({a}, {b})", "OP_CONSTPOW": "v_pow({a}, {b})",
    "OP_FMIN": "v_fmin({a}, {b})", "OP_FMAX": "v_fmax({a}, {b})",
    "OP_ATAN2": "v_atan2({a}, {b})", "OP_LT": "v_lt({a}, {b})", "OP_LE": "v_le({a}, {b})",
    "OP_EQ": "v_eq({a}, {b})", "OP_NE": "v_ne({a}, {b})", "OP_AND": "v_and({a}, {b})",
    "OP_OR": "v_or({a}, {b})", "OP_IF_ELSE_ZERO": "v_if_else_zero({a}, {b})",
    "OP_COPYSIGN": "v_copysign({a}, {b})",
}
_UNARY = {
    "OP_ASSIGN": "{a}", "OP_NEG": "-{a}", "OP_EXP": "v_exp({a})", "OP_LOG": "v_log({a})",
    "OP_SQRT": "v_sqrt({a})", "OP_SQ": "{a} * {a}", "OP_TWICE": "{a} + {a}",
    "OP_SIN": "v_sin({a})", "OP_COS": "v_cos({a})", "OP_TAN": "v_tan({a})",
    "OP_FABS": "v_fabs({a})", "OP_INV": "v_inv({a})", "OP_TANH": "v_tanh({a})",
    "OP_SIGN": "v_sign({a})", "OP_NOT": "v_not({a})", "OP_FLOOR": "v_floor({a})",
    "OP_CEIL": "v_ceil({a})",
}

_LANEWISE = {
    "v_pow": "pow(a[i], b[i])", "v_fmin": "fmin(a[i], b[i])", "v_fmax": "fmax(a[i], b[i])",
    "v_atan2": "atan2(a[i], b[i])", "v_lt": "(double)(a[i] < b[i])",
    "v_le": "(double)(a[i] <= b[i])", "v_eq": "(double)(a[i] == b[i])",
    "v_ne": "(double)(a[i] != b[i])", "v_and": "(double)(a[i] && b[i])",
    "v_or": "(double)(a[i] || b[i])", "v_if_else_zero": "(a[i] ? b[i] : 0.0)",
    "v_copysign": "copysign(a[i], b[i])",
}
_LANEWISE_UNARY = {
    "v_exp": "exp(a[i])", "v_log": "log(a[i])", "v_sqrt": "sqrt(a[i])", "v_sin": "sin(a[i])",
    "v_cos": "cos(a[i])", "v_tan": "tan(a[i])", "v_fabs": "fabs(a[i])", "v_inv": "1.0 / a[i]",
    "v_tanh": "tanh(a[i])", "v_sign": "(double)((a[i] > 0) - (a[i] < 0))",
    "v_not": "(double)(!a[i])", "v_floor": "floor(a[i])", "v_ceil": "ceil(a[i])",
}


def _header() -> str:
    lines = ["/* SIMD-over-steps evaluation of gsfric's generated functions: see derive/simd.py. */",
             "#include <math.h>", "",
             f"typedef double v4 __attribute__((vector_size({8 * LANES})));", ""]
    for name, body in _LANEWISE.items():
        lines.append(f"static inline v4 {name}(v4 a, v4 b) {{ v4 r; "
                     f"for (int i = 0; i < {LANES}; ++i) r[i] = {body}; return r; }}")
    for name, body in _LANEWISE_UNARY.items():
        lines.append(f"static inline v4 {name}(v4 a) {{ v4 r; "
                     f"for (int i = 0; i < {LANES}; ++i) r[i] = {body}; return r; }}")
    return "\n".join(lines) + "\n"


def _opnames():
    import casadi as ca

    return {getattr(ca, n): n for n in dir(ca) if n.startswith("OP_")
            and isinstance(getattr(ca, n), int)}


def batch_source(f, prefix: str) -> str:
    """C source of ``<prefix>_batch`` for the CasADi SX function ``f``."""
    names = _opnames()
    n_w = max(f.sz_w(), 1)
    lines = [
        f"void {prefix}_batch(const double **in, const long long *in_stride,",
        "                    double **out, const long long *out_stride, long long n)",
        "{",
        "    " + " ".join(f"v4 w{k};" for k in range(n_w)),
        f"    for (long long s0 = 0; s0 < n; s0 += {LANES}) {{",
        f"        long long idx[{LANES}];",
        f"        int m = (int)(n - s0 < {LANES} ? n - s0 : {LANES});",
        f"        for (int l = 0; l < {LANES}; ++l) idx[l] = s0 + (l < m ? l : m - 1);",
    ]
    for k in range(f.n_instructions()):
        op = names[f.instruction_id(k)]
        i = f.instruction_input(k)
        o = f.instruction_output(k)
        if op == "OP_INPUT":
            src = f"in[{i[0]}]"
            stride = f"in_stride[{i[0]}]"
            lanes = ", ".join(f"{src}[idx[{l}] * {stride} + {i[1]}]" for l in range(LANES))
            lines.append(f"        w{o[0]} = (v4){{{lanes}}};")
        elif op == "OP_OUTPUT":
            lines.append(f"        if (out[{o[0]}]) for (int l = 0; l < m; ++l) "
                         f"out[{o[0]}][(s0 + l) * out_stride[{o[0]}] + {o[1]}] = w{i[0]}[l];")
        elif op == "OP_CONST":
            c = repr(float(f.instruction_constant(k)))
            lines.append(f"        w{o[0]} = (v4){{{', '.join([c] * LANES)}}};")
        elif op in _BINARY:
            lines.append(f"        w{o[0]} = " + _BINARY[op].format(a=f"w{i[0]}", b=f"w{i[1]}")
                         + ";")
        elif op in _UNARY:
            lines.append(f"        w{o[0]} = " + _UNARY[op].format(a=f"w{i[0]}") + ";")
        else:
            raise NotImplementedError(f"{f.name()}: no SIMD translation for {op}")
    lines += ["    }", "}", ""]
    return "\n".join(lines)


def batch_file(functions) -> str:
    """One C file with a ``_batch`` function for each CasADi function."""
    return _header() + "\n" + "\n".join(batch_source(f, f.name()) for f in functions)
