"""Hot-path throughput of the lane widths and the portable build, in one run.

Usage::

    python benchmarks/bench_lanes.py [--steps 100000]

Each variant is a separate build of the same sources (``GSFRIC_LANES``, ``GSFRIC_MARCH``; cached
like any build) timed in its own subprocess, one after the other, in interleaved rounds so that
a change of load on the machine hits every variant alike: ``Evaluator.actuator_forces(x, out)``
on one thread, steps per second of the calling thread's CPU time (best call of each round, best
round).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

VARIANTS = {
    "native (default)": {},
    "native, 4 lanes": {"GSFRIC_LANES": "4"},
    "native, 1 lane (scalar)": {"GSFRIC_LANES": "1"},
    "portable x86-64-v3": {"GSFRIC_MARCH": "x86-64-v3"},
}

CHILD = """
import json, sys, time
import numpy as np
from gsfric.compiled import native
from gsfric.bench.cases import states
from gsfric.evaluation.evaluator import Evaluator
import gsfric
n = int(sys.argv[1])
x = states(n)
ev = Evaluator(gsfric.reference_platform())
out = np.empty((n, 6))
ev.actuator_forces(x, out)
best = min((lambda t0: (ev.actuator_forces(x, out), time.thread_time() - t0)[1])(time.thread_time())
           for _ in range(7))
print(json.dumps({"lanes": native._library().gsfric_simd_lanes(), "cpu_s": best}))
"""


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100_000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args(argv)
    best: dict[str, dict] = {}
    for _ in range(args.rounds):
        for name, env in VARIANTS.items():
            run = subprocess.run([sys.executable, "-c", CHILD, str(args.steps)],
                                 env=dict(os.environ, **env), capture_output=True, text=True,
                                 check=True)
            res = json.loads(run.stdout.strip().splitlines()[-1])
            if name not in best or res["cpu_s"] < best[name]["cpu_s"]:
                best[name] = res
    base = best["native (default)"]["cpu_s"]
    print(f"hot path, N = {args.steps:,}, one thread, steps per CPU second (best of "
          f"{args.rounds} rounds x 7 calls)")
    for name, res in best.items():
        print(f"  {name:<26} lanes {res['lanes']}: {args.steps / res['cpu_s']:.3g} "
              f"({base / res['cpu_s']:.2f}x the default)")


if __name__ == "__main__":
    main()
