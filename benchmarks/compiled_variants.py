"""Variants of the compiled combined map, measured against the library gsfric builds.

Usage::

    python benchmarks/compiled_variants.py [--out results.json]

Builds, in a temporary folder, from the current generated/gsfric_model.c:

* ``current``: the library as ``gsfric.compiled.build`` builds it (its cached copy), called the way
  ``CompiledFunction`` calls it (through the SIMD-over-steps function of derive/simd.py where
  the library has one, else the per-step driver);
* ``per-step``: the same library through the per-step driver ``gsfric_batch`` (CasADi's scalar
  function, one step per call);
* ``flags``: the same sources compiled with ``EXTRA_FLAGS`` added (``-fno-semantic-interposition``
  lets the compiler inline CasADi's helpers ``casadi_sq``/``casadi_fabs``, which ``-fPIC``
  otherwise calls through the PLT at every use; ``-fno-math-errno`` lets ``sqrt`` compile to one
  instruction without an errno branch; results change only by rounding), called as ``current``;
* ``block``: the actuator function rewritten as a loop over a block of steps, inputs transposed
  to one array per input entry (structure of arrays), under ``#pragma omp simd`` so that the
  compiler evaluates several steps in one vector register; same flags plus
  ``-mprefer-vector-width=256``, and glibc's vector ``exp`` (libmvec) where available.

For each: steps per second at N = 1e5 and 1e6 on one and two threads (wall clock, fastest of
several calls; for one thread also per second of the calling thread's CPU time, which other
load on the machine disturbs less), the latency of a 40-step call through a lean ctypes path (no
per-call argument conversion), and the largest difference from ``Evaluator.actuator_forces``
relative to the largest force. Also the time of a one-step call through
``Evaluator.actuator_forces`` and through the lean path (the difference is the Python overhead
per call).
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from gsfric import models
from gsfric.bench import cases as bench
from gsfric.compiled import build as compiled_build
from gsfric.compiled import functions
from gsfric.compiled.manifest import BASENAME, generated_dir
from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.parameters import effect_vector, parameter_vector

EXTRA_FLAGS = ("-fno-semantic-interposition", "-fno-math-errno")
BLOCK = 64

BLOCK_DRIVER = r"""
void gsfric_actuator_block(const double *x, const double *P, const double *Q, double *F,
                           long long n, int n_threads)
{
#pragma omp parallel num_threads(n_threads) if (n_threads > 1)
    {
        double xt[24 * BLK] __attribute__((aligned(64)));
        double Ft[6 * BLK] __attribute__((aligned(64)));
#pragma omp for schedule(static)
        for (long long s = 0; s < n; s += BLK) {
            int nb = (n - s < BLK) ? (int)(n - s) : BLK;
            for (int j = 0; j < nb; ++j)
                for (int k = 0; k < 24; ++k) xt[k * BLK + j] = x[(s + j) * 24 + k];
            block(xt, P, Q, Ft, nb);
            for (int j = 0; j < nb; ++j)
                for (int k = 0; k < 6; ++k) F[(s + j) * 6 + k] = Ft[k * BLK + j];
        }
    }
}
"""


def _function_body(source: str, name: str) -> list[str]:
    """The statements of the CasADi function exported as ``name``."""
    inner = re.search(rf"int {name}\(const casadi_real\*\* arg.*?return (casadi_f\d+)\(",
                      source, re.S).group(1)
    start = source.index(f"static int {inner}(")
    end = source.index("\n}\n", start)
    return source[start:end].splitlines()[1:]


def block_source(source: str) -> str:
    """The actuator function as a vectorisable loop over a block of steps (C source)."""
    body = []
    for line in _function_body(source, f"{BASENAME}_actuator"):
        s = line.strip()
        load = re.fullmatch(r"(a\d+)=arg\[(\d)\]\? arg\[\d\]\[(\d+)\] : 0;", s)
        store = re.fullmatch(r"if \(res\[0\]!=0\) res\[0\]\[(\d+)\]=(a\d+);", s)
        if s.startswith("casadi_real "):
            body.append(s.replace("casadi_real", "double"))
        elif load:
            var, block, entry = load.groups()
            body.append(f"{var}=" + {"0": f"xt[{entry}*BLK+j]", "1": f"P[{entry}]",
                                      "2": f"Q[{entry}]"}[block] + ";")
        elif store:
            body.append(f"Ft[{store.group(1)}*BLK+j]={store.group(2)};")
        elif re.match(r"a\d+=", s):
            body.append(s.replace("casadi_sq(", "SQ(").replace("casadi_fabs(", "fabs(")
                        .replace("casadi_fmax(", "FMAX("))
        elif s != "return 0;":
            raise ValueError(f"unexpected statement in the generated code: {s}")
    head = [
        "#include <math.h>",
        f"#define BLK {BLOCK}",
        "#define SQ(x) ((x)*(x))",
        "static inline double FMAX(double x, double y) { return (x > y || y != y) ? x : y; }",
        "#ifdef VECTOR_EXP",
        "#pragma omp declare simd notinbranch",
        "extern double exp(double);",
        "#endif",
        "static void block(const double *restrict xt, const double *restrict P,",
        "                  const double *restrict Q, double *restrict Ft, int nb)",
        "{",
        "#pragma omp simd",
        "    for (int j = 0; j < nb; ++j) {",
    ]
    return "\n".join(head + ["        " + s for s in body] + ["    }", "}", BLOCK_DRIVER])


def _compile(cmd: list[str]) -> bool:
    run = subprocess.run(cmd, capture_output=True, text=True)
    return run.returncode == 0


def build(folder: Path) -> dict[str, Path]:
    """Compile the variants into ``folder``; returns name -> shared library."""
    cc = compiled_build._compiler()
    src = generated_dir() / f"{BASENAME}.c"
    sources = [str(compiled_build.DRIVER)] + [str(p) for p in sorted(generated_dir().glob("*.c"))]
    current = compiled_build.build_library()
    libs = {"current": current, "per-step": current}
    flags = folder / "libflags.so"
    extra = [f for f in EXTRA_FLAGS if f not in compiled_build.CFLAGS]
    if _compile(cc + list(compiled_build.CFLAGS) + extra + ["-shared"] + sources
                + ["-o", str(flags), "-lm"]):
        libs["flags"] = flags
    block_c = folder / "block.c"
    block_c.write_text(block_source(src.read_text()))
    block = folder / "libblock.so"
    common = cc + list(compiled_build.CFLAGS) + extra + ["-shared", "-mprefer-vector-width=256",
                                                 str(block_c), "-o", str(block)]
    if _compile(common[:1] + ["-DVECTOR_EXP"] + common[1:] + ["-lmvec", "-lm"]) or \
            _compile(common + ["-lm"]):
        libs["block"] = block
    return libs


class _Batch:
    """A lean caller of one variant: ctypes arguments prepared once, no conversion per call.

    ``kind``: "block" (``gsfric_actuator_block``), "per-step" (``gsfric_run`` without the
    SIMD function) or "auto" (``gsfric_run`` with the SIMD-over-steps function when the
    library has one, else per-step).
    """

    def __init__(self, path: Path, P: np.ndarray, Q: np.ndarray, kind: str) -> None:
        lib = ctypes.CDLL(str(path))
        self.P, self.Q = P, Q
        simd = getattr(lib, f"{BASENAME}_actuator_batch", None) if kind == "auto" else None
        self.kind = "block" if kind == "block" else "simd" if simd is not None else "per-step"
        self.in_ptrs = (ctypes.c_void_p * 3)(0, P.ctypes.data, Q.ctypes.data)
        self.in_strides = (ctypes.c_longlong * 3)(24, 0, 0)
        self.out_ptrs = (ctypes.c_void_p * 1)()
        self.out_strides = (ctypes.c_longlong * 1)(6)
        if self.kind == "block":
            self.fn = lib.gsfric_actuator_block
        else:
            self.fn = lib.gsfric_run
            self.fn.restype = ctypes.c_longlong
            self.desc = functions._Fn(
                ctypes.cast(simd, ctypes.c_void_p) if self.kind == "simd" else None,
                ctypes.cast(getattr(lib, f"{BASENAME}_actuator"), ctypes.c_void_p),
                ctypes.cast(getattr(lib, f"{BASENAME}_actuator_work"), ctypes.c_void_p), 3, 1)

    def __call__(self, x: np.ndarray, out: np.ndarray, threads: int) -> None:
        n = ctypes.c_longlong(x.shape[0])
        if self.kind == "block":
            self.fn(ctypes.c_void_p(x.ctypes.data), ctypes.c_void_p(self.P.ctypes.data),
                    ctypes.c_void_p(self.Q.ctypes.data), ctypes.c_void_p(out.ctypes.data), n,
                    ctypes.c_int(threads))
            return
        self.in_ptrs[0] = x.ctypes.data
        self.out_ptrs[0] = out.ctypes.data
        failed = self.fn(ctypes.byref(self.desc), self.in_ptrs, self.in_strides, self.out_ptrs,
                         self.out_strides, n, ctypes.c_int(threads), None, None)
        if failed:
            raise RuntimeError("evaluation failed")


def _best(fn, budget: float, min_calls: int = 3) -> tuple[float, float]:
    """Fastest call: wall-clock seconds and process CPU seconds."""
    cpu: list[float] = []
    times = bench.time_calls(fn, budget, min_calls, 200_000, cpu)
    return min(times), min(cpu)


def measure(budget: float = 2.0) -> dict:
    """Build and time every variant; returns the figures (see the module docstring)."""
    platform = models.reference_platform()
    evaluator = Evaluator(platform)
    P, Q = parameter_vector(platform), effect_vector(platform)
    x = bench.states(1_000_000)
    expected = evaluator.actuator_forces(x[:100_000])
    results = {"load_average_start": list(os.getloadavg()), "variants": {}}
    with tempfile.TemporaryDirectory(prefix="gsfric-variants-") as tmp:
        libs = build(Path(tmp))
        for name, path in libs.items():
            call = _Batch(path, P, Q, {"block": "block", "per-step": "per-step"}.get(name,
                                                                                    "auto"))
            row = {"entry": call.kind}
            out = np.zeros((x.shape[0], 6))
            call(x[:100_000], out[:100_000], 1)
            row["max_relative_difference"] = float(np.max(np.abs(out[:100_000] - expected))
                                                   / np.max(np.abs(expected)))
            for n, threads in ((100_000, 1), (1_000_000, 1), (1_000_000, 2)):
                xs, o = x[:n], out[:n]
                wall, cpu = _best(lambda: call(xs, o, threads), budget)
                row[f"steps_per_s_{n}_{threads}t"] = n / wall
                if threads == 1:
                    row[f"steps_per_cpu_s_{n}_{threads}t"] = n / cpu
            x40, o40 = np.ascontiguousarray(x[:40]), np.zeros((40, 6))
            times = bench.time_calls(lambda: call(x40, o40, 1), budget, 100, 200_000)
            row["latency_40_us_best"] = min(times) * 1e6
            row["latency_40_us_median"] = float(np.median(times)) * 1e6
            row["two_vs_one_core_1e6"] = (row["steps_per_s_1000000_2t"]
                                          / row["steps_per_s_1000000_1t"])
            results["variants"][name] = row
            print(name, ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                              for k, v in row.items()), flush=True)
        results["call_overhead"] = call_overhead(evaluator, _Batch(libs["current"], P, Q,
                                                                   "auto"), x[:1])
        print("call overhead", ", ".join(f"{k} {v:.3g}" for k, v in
                                         results["call_overhead"].items()), flush=True)
    results["load_average_end"] = list(os.getloadavg())
    return results


def call_overhead(evaluator: Evaluator, lean: _Batch, x1: np.ndarray,
                  calls: int = 20_000) -> dict:
    """Median microseconds of a one-step call through ``Evaluator.actuator_forces`` and through
    the lean ctypes path (same library), the two calls alternating so that both see the same
    load on the machine."""
    out = np.zeros((1, 6))
    paths = {"evaluator_us": lambda: evaluator.actuator_forces(x1, out=out),
             "lean_ctypes_us": lambda: lean(x1, out, 1)}
    samples: dict[str, list[float]] = {name: [] for name in paths}
    for _ in range(calls):
        for name, fn in paths.items():
            samples[name] += bench.time_calls(fn, 0.0, 1, 1)
    times = {name: float(np.median(v)) * 1e6 for name, v in samples.items()}
    times["python_overhead_us"] = times["evaluator_us"] - times["lean_ctypes_us"]
    return times


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="write the figures as JSON")
    args = parser.parse_args(argv)
    results = measure()
    if args.out:
        args.out.write_text(json.dumps(results, indent=2) + "\n")
        print(f"wrote {args.out}")


if __name__ == "__main__":
    sys.exit(main())
