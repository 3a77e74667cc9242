"""C code that evaluates a CasADi function on several steps at once (SIMD over steps).

CasADi's own C code evaluates one step per call: a long chain of scalar operations. Here the
same chain of operations (CasADi's instruction list) is printed so that every value holds
``GSFRIC_LANES`` steps and every operation acts on a vector of them, which the compiler turns
into vector instructions. Each value is the same arithmetic as CasADi's code (the same
operations in the same order), except ``exp``, which is a vector polynomial here (within 2 ulp
of the C library's, see ``v_exp``), and divisions: a square root used only as a divisor is
printed as its reciprocal (``v_rsqrt``) and the divisions by it as products, a divisor of
several divisions of the loop, or one that is loop invariant, as one reciprocal and products
(the rewriting ``-freciprocal-math`` allows the compiler), and a division on its own as
``v_div`` (see ``_DIVIDER``: on AVX-512 these do not use the divider). The operations'
text, the reading of the instruction list and the reciprocal rule are those of
``gsfric.compiled.instructions``, which the export's printer (gsfric/export/folded.py) reads too.

The lane width is chosen when the C is compiled, for the CPU it is compiled for: 8 with
AVX-512F, 4 with AVX, otherwise 1 (scalar vectors; ``-DGSFRIC_LANES=n`` overrides). The
printed code does not depend on it.

The parameter inputs (every input but the first) are the same for every step of a call: the
instructions that depend only on them and on constants are hoisted out of the step loop and
evaluated once per call (each gets a name of its own, so CasADi's reuse of work slots inside
the loop cannot overwrite it).

Outputs computed on request (``on_request``, derive/model.py's ``ON_REQUEST``): the
instructions whose values only these outputs need are printed after the others, in a block
that runs only when the call asks for one of them (their own values named once each, the loop
body's values they read copied where they are computed, since later instructions may reuse
the work slot); their entries of the transposed outputs come last.

Generated function, for CasADi function ``f`` with inputs k and outputs j:

    void <prefix>_batch(const double **in, const long long *in_stride,
                        double **out, const long long *out_stride, long long n,
                        long long *bad)

Step s reads input 0 at ``in[0] + s * in_stride[0]`` and every other input k at ``in[k]``
(its stride must be 0: the caller uses CasADi's per-step function otherwise), and writes
output j at ``out[j] + s * out_stride[j]`` (a NULL output is skipped). A group of steps is
read into, and its outputs written from, small transposed arrays (one vector per entry) by
short loops, which keeps the loop body's code small. With 8 lanes on AVX-512, a full group's
rows of an output (8 steps x its size, contiguous when its stride is its size) are written as
whole 64-byte vectors gathered from the transposed array (``v_store_rows``), non-temporal when
the batch is long and the output starts on a 64-byte boundary. Unless ``bad`` is NULL,
``bad[s]`` is set to 1 where some output of step s is infinite or NaN, else 0.
"""

from __future__ import annotations

import casadi as ca

from gsfric.compiled.instructions import (
    OPERATIONS,
    Instruction,
    divisors,
    opcode_names,
    read,
    reciprocal,
)

# recorded in the manifest: the printed code is the same for every lane width
LANES = "chosen when compiled: 8 (AVX-512F), 4 (AVX), 1"

# lane by lane through the C library (rare operations)
_LANEWISE = {
    "v_pow": "pow(a[i], b[i])", "v_atan2": "atan2(a[i], b[i])",
    "v_copysign": "copysign(a[i], b[i])",
}
_LANEWISE_UNARY = {
    "v_log": "log(a[i])", "v_sin": "sin(a[i])", "v_cos": "cos(a[i])",
    "v_tan": "tan(a[i])", "v_tanh": "tanh(a[i])", "v_floor": "floor(a[i])",
    "v_ceil": "ceil(a[i])",
}

# whole-vector operations: comparisons give masks of all ones (true) or zeros per lane
_VECTOR = r"""
#define ONE_BITS ((vl)v_splat(1.0))
static inline vd v_splat(double c) { vd r; for (int i = 0; i < GSFRIC_LANES; ++i) r[i] = c; return r; }
static inline vd v_mask(vl m) { return (vd)(m & ONE_BITS); }
static inline vd v_lt(vd a, vd b) { return v_mask((vl)(a < b)); }
static inline vd v_le(vd a, vd b) { return v_mask((vl)(a <= b)); }
static inline vd v_eq(vd a, vd b) { return v_mask((vl)(a == b)); }
static inline vd v_ne(vd a, vd b) { return v_mask((vl)(a != b)); }
static inline vd v_and(vd a, vd b) { return v_mask((vl)(a != 0.0) & (vl)(b != 0.0)); }
static inline vd v_or(vd a, vd b) { return v_mask((vl)(a != 0.0) | (vl)(b != 0.0)); }
static inline vd v_not(vd a) { return v_mask((vl)(a == 0.0)); }
static inline vd v_if_else_zero(vd a, vd b) { return (vd)((vl)(a != 0.0) & (vl)b); }
static inline vd v_sign(vd a) { return v_mask((vl)(a > 0.0)) - v_mask((vl)(a < 0.0)); }
static inline vd v_fabs(vd a) { return (vd)((vl)a & ~(vl)v_splat(-0.0)); }
/* fmax/fmin as the C library's: a NaN operand gives the other one */
static inline vd v_fmax(vd a, vd b) { vl m = (vl)(a > b) | (vl)(b != b); return (vd)((m & (vl)a) | (~m & (vl)b)); }
static inline vd v_fmin(vd a, vd b) { vl m = (vl)(a < b) | (vl)(b != b); return (vd)((m & (vl)a) | (~m & (vl)b)); }
/* exp: x = k ln2 + r (Cody-Waite), exp(r) by its Taylor polynomial of degree 13 (|r| <= ln2/2,
 * truncation below 2e-16 relative), times 2^k put in the exponent bits. Within 2 ulp of the C
 * library's exp; below -708.39 (results under the smallest normal number) it gives 0. */
static inline vd v_exp(vd x)
{
    const vd hi = v_splat(709.782712893384), lo = v_splat(-708.3964185322641);
    vd xc = v_fmin(v_fmax(x, lo), hi);
    vd k = xc * 1.4426950408889634;
    vd kr;
    for (int i = 0; i < GSFRIC_LANES; ++i) kr[i] = __builtin_round(k[i]);
    vd r = (xc - kr * 0.6931471803691238) - kr * 1.9082149292705877e-10;
    vd p = v_splat(1.0 / 6227020800.0);
    p = p * r + 1.0 / 479001600.0;
    p = p * r + 1.0 / 39916800.0;
    p = p * r + 1.0 / 3628800.0;
    p = p * r + 1.0 / 362880.0;
    p = p * r + 1.0 / 40320.0;
    p = p * r + 1.0 / 5040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    p = p * r + 1.0;
    /* 2^k in two halves so that k = 1024 (near the overflow limit) stays representable */
    vl kh = __builtin_convertvector(kr, vl) >> 1;
    vl kl = __builtin_convertvector(kr, vl) - kh;
    vd s1 = (vd)((kh + 1023) << 52), s2 = (vd)((kl + 1023) << 52);
    vd y = p * s1 * s2;
    y = (vd)(((vl)(x > hi) & (vl)v_splat(1.0 / 0.0)) | (~(vl)(x > hi) & (vl)y));
    y = (vd)(~(vl)(x < lo) & (vl)y);
    return (vd)(((vl)(x != x) & (vl)x) | (~(vl)(x != x) & (vl)y));
}
"""

# Division, reciprocal and reciprocal square root. With 8 lanes on AVX-512 they do not queue
# on the divider (one vdivpd or vsqrtpd of 8 lanes occupies it for about 16-24 cycles): a 14-bit
# estimate (vrcp14pd, vrsqrt14pd) refined by Newton-Raphson (Goldschmidt for the square root)
# steps in FMA, ended by one correction step on the residual computed exactly by an FMA
# (Markstein). ``v_div`` equals the divider's correctly rounded quotient; ``v_rcp`` and
# ``v_rsqrt`` are within 1 ulp of 1 / b and of 1 / sqrt (two roundings), equal to them but where
# the significand is near 2: tests/test_lanes.py checks them on random operands of every
# magnitude and on the special values. Lanes whose operand or result is outside the range where the residual is
# exact (0, below 2^-960, subnormal, infinite, NaN, negative for the square root) take the
# divider's instruction instead. A square root that is not only a divisor keeps vsqrtpd (see
# docs/explanation/performance.md). With other lane widths they are the C operators and the C library's
# sqrt, lane by lane.
_DIVIDER = r"""
#if GSFRIC_LANES == 8 && defined(__AVX512F__)
/* fpclass categories: 0x01 QNaN, 0x02 +0, 0x04 -0, 0x08 +inf, 0x10 -inf, 0x20 subnormal,
 * 0x40 negative, 0x80 SNaN */
#define NOT_NORMAL 0xBF            /* zero, subnormal, infinite or NaN */
#define NOT_POSITIVE_NORMAL 0xFF   /* the same, or negative */
/* below this the residuals of the correction steps underflow (would cost up to 2 ulp) */
#define TINY 0x1p-960
/* 1/b to 56 bits: the estimate's relative error e0 < 2^-14 squares at each step */
static inline __m512d z_rcp_nr(__m512d b)
{
    const __m512d one = _mm512_set1_pd(1.0);
    __m512d y = _mm512_rcp14_pd(b);
    y = _mm512_fmadd_pd(y, _mm512_fnmadd_pd(b, y, one), y);
    return _mm512_fmadd_pd(y, _mm512_fnmadd_pd(b, y, one), y);
}
static inline __m512d z_div(__m512d a, __m512d b)
{
    __m512d y = z_rcp_nr(b), q = _mm512_mul_pd(a, y);
    q = _mm512_fmadd_pd(_mm512_fnmadd_pd(b, q, a), y, q);
    __mmask8 k = _mm512_fpclass_pd_mask(q, NOT_NORMAL) | _mm512_fpclass_pd_mask(y, NOT_NORMAL)
                 | _mm512_cmp_pd_mask(_mm512_abs_pd(a), _mm512_set1_pd(TINY), _CMP_LT_OQ);
    if (__builtin_expect(k != 0, 0)) q = _mm512_mask_div_pd(q, k, a, b);
    return q;
}
static inline __m512d z_rcp(__m512d b)
{
    const __m512d one = _mm512_set1_pd(1.0);
    __m512d y = z_rcp_nr(b);
    y = _mm512_fmadd_pd(y, _mm512_fnmadd_pd(b, y, one), y);
    __mmask8 k = _mm512_fpclass_pd_mask(y, NOT_NORMAL);
    if (__builtin_expect(k != 0, 0)) y = _mm512_mask_div_pd(y, k, one, b);
    return y;
}
/* sqrt(a) as g and 1/(2 sqrt(a)) as h (Goldschmidt), each step squaring the relative error;
 * then g corrected by the exact residual a - g^2 */
static inline __m512d z_sqrt_gh(__m512d a, __m512d *h)
{
    const __m512d half = _mm512_set1_pd(0.5);
    __m512d y = _mm512_rsqrt14_pd(a), g = _mm512_mul_pd(a, y), hh = _mm512_mul_pd(half, y);
    for (int i = 0; i < 2; ++i) {
        __m512d r = _mm512_fnmadd_pd(g, hh, half);
        g = _mm512_fmadd_pd(g, r, g);
        hh = _mm512_fmadd_pd(hh, r, hh);
    }
    *h = hh;
    return _mm512_fmadd_pd(_mm512_fnmadd_pd(g, g, a), hh, g);
}
static inline __mmask8 z_sqrt_special(__m512d a)
{
    return _mm512_fpclass_pd_mask(a, NOT_POSITIVE_NORMAL)
           | _mm512_cmp_pd_mask(a, _mm512_set1_pd(TINY), _CMP_LT_OQ);
}
/* 1/sqrt(a): 2h, corrected as a reciprocal of the corrected square root g */
static inline __m512d z_rsqrt(__m512d a)
{
    const __m512d one = _mm512_set1_pd(1.0);
    __m512d h, g = z_sqrt_gh(a, &h), y = _mm512_add_pd(h, h);
    y = _mm512_fmadd_pd(y, _mm512_fnmadd_pd(g, y, one), y);
    __mmask8 k = z_sqrt_special(a);
    if (__builtin_expect(k != 0, 0)) y = _mm512_mask_div_pd(y, k, one, _mm512_sqrt_pd(a));
    return y;
}
static inline vd v_div(vd a, vd b) { return (vd)z_div((__m512d)a, (__m512d)b); }
static inline vd v_rcp(vd b) { return (vd)z_rcp((__m512d)b); }
/* a square root used otherwise keeps vsqrtpd: its 1 instruction in place of about 15 is
 * faster in these long bodies, whose time is spent on instructions more than on the divider */
static inline vd v_sqrt(vd a) { return (vd)_mm512_sqrt_pd((__m512d)a); }
static inline vd v_rsqrt(vd a) { return (vd)z_rsqrt((__m512d)a); }
#else
static inline vd v_div(vd a, vd b) { return a / b; }
static inline vd v_rcp(vd b) { return 1.0 / b; }
static inline vd v_sqrt(vd a)
{
    vd r;
    for (int i = 0; i < GSFRIC_LANES; ++i) r[i] = sqrt(a[i]);
    return r;
}
static inline vd v_rsqrt(vd a) { return 1.0 / v_sqrt(a); }
#endif
static inline vd v_inv(vd a) { return v_rcp(a); }
"""


def _header(probes: bool = True) -> str:
    """The file's definitions; with ``probes``, the functions the tests call (one file of a
    module has them)."""
    lines = [
        "/* SIMD-over-steps evaluation of gsfric's generated functions: see derive/simd.py. */",
        "#include <math.h>",
        "",
        "#ifndef GSFRIC_LANES",
        "#if defined(__AVX512F__)",
        "#define GSFRIC_LANES 8",
        "#elif defined(__AVX__)",
        "#define GSFRIC_LANES 4",
        "#else",
        "#define GSFRIC_LANES 1",
        "#endif",
        "#endif",
        "",
        "typedef double vd __attribute__((vector_size(8 * GSFRIC_LANES)));",
        "typedef long long vl __attribute__((vector_size(8 * GSFRIC_LANES)));",
        "",
        "/* Long batches write their outputs past the caches (non-temporal stores: no read of",
        " * the lines first); short ones, a control loop's, leave them in the cache. */",
        "#define STREAM_STEPS 4096",
        "#if defined(__SSE2__) && defined(__x86_64__)",
        "#include <immintrin.h>",
        "#define STREAM(p, v) _mm_stream_si64((long long *)(p), (union { double d; long long i; }){v}.i)",
        "#define STREAM_FENCE() _mm_sfence()",
        "#else",
        "#define STREAM(p, v) (*(p) = (v))",
        "#define STREAM_FENCE() ((void)0)",
        "#endif",
        "",
        "/* With 8 lanes on AVX-512, a full group's rows of one output (8 steps of `size` values:",
        " * 8 * size doubles, contiguous in the output) are written as `size` whole vectors, each",
        " * gathered from the group's transposed outputs y (entry o of lane l at y[8 o + l]) by an",
        " * index table (idx[f] = 8 (f % size) + f / size for flat entry f of the rows): one",
        " * 64-byte store per vector instead of eight scalar ones; non-temporal where the rows are",
        " * 64-byte aligned. */",
        "#if GSFRIC_LANES == 8 && defined(__AVX512F__)",
        "#define VSTORE 1",
        "#include <stdint.h>",
        "static inline void v_store_rows(double *dst, const double *y, const long long *idx,",
        "                                int size, int stream)",
        "{",
        "    for (int q = 0; q < size; ++q) {",
        "        __m512d v = _mm512_i64gather_pd(_mm512_loadu_si512(idx + 8 * q), y, 8);",
        "        if (stream)",
        "            _mm512_stream_pd(dst + 8 * q, v);",
        "        else",
        "            _mm512_storeu_pd(dst + 8 * q, v);",
        "    }",
        "}",
        "#endif",
    ]
    lines.append(_VECTOR)
    lines.append(_DIVIDER)
    for name, body in _LANEWISE.items():
        lines.append(f"static inline vd {name}(vd a, vd b) {{ vd r; "
                     f"for (int i = 0; i < GSFRIC_LANES; ++i) r[i] = {body}; return r; }}")
    for name, body in _LANEWISE_UNARY.items():
        lines.append(f"static inline vd {name}(vd a) {{ vd r; "
                     f"for (int i = 0; i < GSFRIC_LANES; ++i) r[i] = {body}; return r; }}")
    if not probes:
        return "\n".join(lines) + "\n"
    lines += [
        "",
        "/* The lane width this file was compiled with, and its vector exp (for the tests). */",
        "int gsfric_simd_lanes(void) { return GSFRIC_LANES; }",
        "void gsfric_simd_exp(const double *x, double *y, long long n)",
        "{",
        "    for (long long s = 0; s < n; s += GSFRIC_LANES) {",
        "        vd a;",
        "        for (int l = 0; l < GSFRIC_LANES; ++l) a[l] = x[s + l < n ? s + l : n - 1];",
        "        vd r = v_exp(a);",
        "        for (int l = 0; l < GSFRIC_LANES && s + l < n; ++l) y[s + l] = r[l];",
        "    }",
        "}",
        "/* y = a / b (op 0), 1 / b (1), sqrt(a) (2), 1 / sqrt(a) (3) as the generated code",
        " * computes them (for the tests) */",
        "void gsfric_simd_divider(int op, const double *a, const double *b, double *y,",
        "                         long long n)",
        "{",
        "    for (long long s = 0; s < n; s += GSFRIC_LANES) {",
        "        vd u, v, r;",
        "        for (int l = 0; l < GSFRIC_LANES; ++l) {",
        "            u[l] = a[s + l < n ? s + l : n - 1];",
        "            v[l] = b[s + l < n ? s + l : n - 1];",
        "        }",
        "        r = op == 0 ? v_div(u, v) : op == 1 ? v_rcp(v)",
        "            : op == 2 ? v_sqrt(u) : v_rsqrt(u);",
        "        for (int l = 0; l < GSFRIC_LANES && s + l < n; ++l) y[s + l] = r[l];",
        "    }",
        "}",
    ]
    return "\n".join(lines) + "\n"


def _gather_tables(sizes: list[int]) -> list[str]:
    """C lines of ``gidx`` (the index tables of ``v_store_rows``, one per distinct output
    size, 8 entries per value) and ``goff`` (each output's table in it)."""
    distinct = sorted(set(sizes))
    start, table = {}, []
    for k in distinct:
        start[k] = len(table)
        table += [8 * (f % k) + f // k for f in range(8 * k)]
    rows = [", ".join(map(str, table[i:i + 16])) for i in range(0, len(table), 16)]
    return [f"    static const long long gidx[{len(table)}] __attribute__((aligned(64))) = {{",
            *[f"        {r}," for r in rows], "    };",
            f"    static const int goff[{len(sizes)}] = "
            f"{{{', '.join(str(start[k]) for k in sizes)}}};"]


def _on_request_only(program: list[Instruction], lazy: set[int]) -> set[int]:
    """The instructions whose values only the outputs ``lazy`` need."""
    consumers: dict[int, list[int]] = {}
    core: set[int] = set()
    values: set[int] = set()
    for item in program:
        if item.op == "OP_OUTPUT":
            if item.slot not in lazy:
                core.add(item.args[0])
            continue
        values.add(item.index)
        for a in item.args:
            consumers.setdefault(a, []).append(item.index)
    for k in range(len(program) - 1, -1, -1):
        if k not in core and any(c in core for c in consumers.get(k, ())):
            core.add(k)
    return values - core


def _vector_text(f, item: Instruction, args: list[str]) -> str:
    """The vector C text of the operation ``item`` on the operands ``args``."""
    text = OPERATIONS[item.op].vector
    if text is None:
        raise NotImplementedError(f"{f.name()}: no SIMD translation for {item.op}")
    return text.format(*args)


def batch_source(f, prefix: str, on_request=()) -> str:
    """C source of ``<prefix>_batch`` for the CasADi SX function ``f``; the outputs named in
    ``on_request`` are computed only in a call that asks for one of them."""
    program = read(f, opcode_names(ca))
    n_x = f.numel_in(0)
    sizes = [f.numel_out(j) for j in range(f.n_out())]
    lazy_out = {j for j in range(f.n_out()) if f.name_out(j) in on_request}
    lazy = _on_request_only(program, lazy_out)
    order = [j for j in range(f.n_out()) if j not in lazy_out] + sorted(lazy_out)
    base = {j: sum(sizes[q] for q in order[:order.index(j)]) for j in order}
    n_core = sum(sizes[j] for j in range(f.n_out()) if j not in lazy_out)
    uses = divisors(program)
    hoisted, body, later = [], [], []
    names: dict[int, str] = {}     # instruction -> the C name of its value
    rsqrt: set[int] = set()        # square roots held as their reciprocals
    recip: dict[int, str] = {}     # divisors -> the name of their reciprocal
    line_of: dict[int, int] = {}   # instruction -> its line in body
    copied: dict[int, int] = {}    # instruction -> its work slot, for a copy read by `later`

    def value(a: int, deferred: bool) -> str:
        """The value of instruction ``a``; in the deferred part a copy of a loop-body value,
        which later instructions of the body may overwrite."""
        if deferred and names[a].startswith("w"):
            copied[a] = program[a].slot
            return f"c{a}"
        return names[a]

    for item in program:
        k, op = item.index, item.op
        if op == "OP_OUTPUT":
            deferred = item.slot in lazy_out
            (later if deferred else body).append(
                f"        *(vd *)yt[{base[item.slot] + item.entry}] = "
                f"{value(item.args[0], deferred)};")
            continue
        deferred = k in lazy
        args = [value(a, deferred) for a in item.args]
        if op == "OP_INPUT":
            expr = (f"*(const vd *)xt[{item.entry}]" if item.source == 0
                    else f"v_splat(in[{item.source}][{item.entry}])")
        elif op == "OP_CONST":
            expr = f"v_splat({item.constant!r})"
        elif op == "OP_DIV" and not item.invariant:
            d = item.args[1]
            expr = (f"{args[0]} * {args[1]}" if d in rsqrt else f"{args[0]} * {recip[d]}"
                    if d in recip else f"v_div({args[0]}, {args[1]})")
        elif op == "OP_SQRT" and not item.invariant and uses[k].divisions == uses[k].uses > 0:
            expr = f"v_rsqrt({args[0]})"
            rsqrt.add(k)
        else:
            expr = _vector_text(f, item, args)
        if item.invariant:
            hoisted.append(f"    const vd h{k} = {expr};")
            names[k] = f"h{k}"
            if reciprocal(item, uses[k]):  # a divisor of the loop body's divisions: once
                hoisted.append(f"    const vd r{k} = 1.0 / h{k};")
                recip[k] = f"r{k}"
        elif deferred:
            later.append(f"        const vd l{k} = {expr};")
            names[k] = f"l{k}"
            if k not in rsqrt and reciprocal(item, uses[k]):
                later.append(f"        const vd r{k} = v_rcp(l{k});")
                recip[k] = f"r{k}"
        else:
            line_of[k] = len(body)
            body.append(f"        w{item.slot} = {expr};")
            names[k] = f"w{item.slot}"
            if k not in rsqrt and reciprocal(item, uses[k]):
                body.append(f"        const vd r{k} = v_rcp(w{item.slot});")
                recip[k] = f"r{k}"
    for d in sorted(copied, key=line_of.get, reverse=True):
        body.insert(line_of[d] + 1, f"        const vd c{d} = w{copied[d]};")
    slots = sorted({int(line.split("=")[0].strip()[1:]) for line in body
                    if line.lstrip().startswith("w")})
    lines = [
        f"void {prefix}_batch(const double **in, const long long *in_stride,",
        "                    double **out, const long long *out_stride, long long n,",
        "                    long long *bad)",
        "{",
        *hoisted,
        "    " + " ".join(f"vd w{s};" for s in slots),
        f"    static const int size[{len(sizes)}] = {{{', '.join(map(str, sizes))}}};",
        f"    static const int ybase[{len(sizes)}] = "
        f"{{{', '.join(str(base[j]) for j in range(len(sizes)))}}};",
        *(["    int lazy = " + " || ".join(f"out[{j}] != 0" for j in sorted(lazy_out))
           + ";  /* an output computed on request is asked for */"] if lazy_out else []),
        f"    double xt[{n_x}][GSFRIC_LANES] __attribute__((aligned(8 * GSFRIC_LANES)));",
        f"    double yt[{sum(sizes)}][GSFRIC_LANES] __attribute__((aligned(8 * GSFRIC_LANES)));",
        "    int stream = n >= STREAM_STEPS;",
        "#ifdef VSTORE",
        *_gather_tables(sizes),
        f"    int vec[{len(sizes)}];",
        f"    for (int j = 0; j < {len(sizes)}; ++j)  /* whole rows, aligned if streamed */",
        "        vec[j] = out[j] && out_stride[j] == size[j]",
        "                 && (!stream || ((uintptr_t)out[j] & 63) == 0);",
        "#endif",
        "    for (long long s0 = 0; s0 < n; s0 += GSFRIC_LANES) {",
        "        int m = (int)(n - s0 < GSFRIC_LANES ? n - s0 : GSFRIC_LANES);",
        "        for (int l = 0; l < GSFRIC_LANES; ++l) {",
        "            const double *row = in[0] + (s0 + (l < m ? l : m - 1)) * in_stride[0];",
        f"            for (int j = 0; j < {n_x}; ++j) xt[j][l] = row[j];",
        "        }",
        *body,
        *(["        if (lazy) {  /* the outputs computed on request, after the others */",
           *["    " + line for line in later], "        }"] if lazy_out else []),
        "        if (bad) {  /* 1 where some output is infinite or NaN: v * 0 is NaN there, else",
        "                       0, and a sum of them NaN when one is (four sums: one add each;",
        "                       the outputs computed on request come last) */",
        "            vd z0 = v_splat(0.0), z1 = z0, z2 = z0, z3 = z0;",
        f"            int k = 0, end = {f'lazy ? {sum(sizes)} : {n_core}' if lazy_out else n_core};",
        "            for (; k + 4 <= end; k += 4) {",
        "                z0 += *(const vd *)yt[k] * 0.0;",
        "                z1 += *(const vd *)yt[k + 1] * 0.0;",
        "                z2 += *(const vd *)yt[k + 2] * 0.0;",
        "                z3 += *(const vd *)yt[k + 3] * 0.0;",
        "            }",
        "            for (; k < end; ++k) z0 += *(const vd *)yt[k] * 0.0;",
        "            vd z = (z0 + z1) + (z2 + z3);",
        "            for (int l = 0; l < m; ++l) bad[s0 + l] = z[l] != z[l];",
        "        }",
        "        /* outputs: one loop, rows of each step written whole */",
        f"        for (int j = 0; j < {len(sizes)}; ++j) {{",
        "            int b = ybase[j];",
        "            if (!out[j]) continue;",
        "#ifdef VSTORE",
        "            if (m == GSFRIC_LANES && vec[j]) {",
        "                v_store_rows(out[j] + s0 * out_stride[j], yt[b], gidx + goff[j],",
        "                             size[j], stream);",
        "                continue;",
        "            }",
        "#endif",
        "            for (int l = 0; l < m; ++l) {",
        "                double *row = out[j] + (s0 + l) * out_stride[j];",
        "                if (stream)",
        "                    for (int o = 0; o < size[j]; ++o) STREAM(row + o, yt[b + o][l]);",
        "                else",
        "                    for (int o = 0; o < size[j]; ++o) row[o] = yt[b + o][l];",
        "            }",
        "        }",
        "    }",
        "    if (stream) STREAM_FENCE();",
        "}",
        "",
    ]
    return "\n".join(lines)


def batch_file(functions, on_request=(), probes: bool = True) -> str:
    """One C file with a ``_batch`` function for each CasADi function (``on_request``: see
    ``batch_source``); ``probes``: with the functions the tests call (``gsfric_simd_lanes``,
    ...), which only one file linked into a module may have."""
    return _header(probes) + "\n" + "\n".join(batch_source(f, f.name(), on_request)
                                              for f in functions)
