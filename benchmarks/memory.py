"""The memory a call adds, each measured in a fresh process (``gsfric bench``'s memory figures).

The figure is the rise of the peak resident set size over the call: on Linux from
``/proc/self/status`` after resetting the peak to the current size, elsewhere from
``resource.getrusage``'s maximum (a lower bound); for the NumPy engines also the peak of
``tracemalloc``.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np

import gsfric
from benchmarks.cases import CHECKOUT, bench_motion, implementation_call


def _status_kib(key: str) -> int | None:
    """A ``/proc/self/status`` figure in KiB (VmRSS, VmHWM), None where there is none."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def _reset_peak_rss() -> bool:
    """Reset this process's peak resident set size to the current one (Linux); True if done."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        return False
    return _status_kib("VmHWM") is not None


def _max_rss_kib() -> int:
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return rss // 1024 if sys.platform == "darwin" else rss


def memory_child(implementation: str, threads: int, path: str) -> dict:
    """In a fresh process: the memory one call adds, in MiB (run by ``memory_case``).

    The states are read from ``path``; the evaluator, its output buffer and the compiled library
    are set up before the baseline. On Linux the peak resident set size is reset to the current
    one first, so the figure is the call's own peak above what was resident before it;
    elsewhere it is the rise of ``getrusage``'s maximum resident set size (a lower bound).
    """

    x = np.load(path)
    fn = implementation_call(implementation, threads, x)
    implementation_call(implementation, threads, x[:2])()
    if _reset_peak_rss():
        before = _status_kib("VmRSS")
        fn()
        rise = _status_kib("VmHWM") - before
    else:
        before = _max_rss_kib()
        fn()
        rise = _max_rss_kib() - before
    result = {"rss_mib": rise / 1024, "tracemalloc_mib": None}
    if not implementation.startswith("compiled"):
        tracemalloc.start()
        fn()
        result["tracemalloc_mib"] = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
    return result


def memory_case(implementation: str, threads: int, x: np.ndarray, folder: Path) -> dict:
    """Run ``memory_child`` for one case in a subprocess; returns its result."""
    path = folder / f"x{x.shape[0]}.npy"
    if not path.exists():
        np.save(path, x)
    code = ("import json, sys; from benchmarks.memory import memory_child; "
            f"print(json.dumps(memory_child({implementation!r}, {threads}, {str(path)!r})))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=CHECKOUT)
    if run.returncode != 0:
        raise RuntimeError(f"memory case {implementation} N={x.shape[0]} failed: "
                           f"{run.stderr.strip().splitlines()[-1:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def evaluate_memory_child(n: int) -> dict:
    """In a fresh process: the peak memory ``gsfric.evaluate`` adds at n steps, in GiB."""

    motion = bench_motion(n)
    platform = gsfric.reference_platform()
    gsfric.evaluate(platform, bench_motion(50))
    if _reset_peak_rss():
        before = _status_kib("VmRSS")
        result = gsfric.evaluate(platform, motion)
        rise = _status_kib("VmHWM") - before
    else:
        before = _max_rss_kib()
        result = gsfric.evaluate(platform, motion)
        rise = _max_rss_kib() - before
    kept = result.arrays.kept()      # the detail outputs are computed only when read
    size = sum(v.nbytes for v in kept.values()) + result.flag.nbytes
    return {"peak_gib": rise / 2**20, "results_gib": size / 2**30, "arrays": len(kept),
            "values_per_step": sum(v[0].size for v in kept.values())}
