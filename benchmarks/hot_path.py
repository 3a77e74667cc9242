"""The hot path's rate: ``Evaluator.actuator_forces`` of the reference platform (coupled
friction) over 100,000 steps into a preallocated array (64-byte aligned, as ``evaluate``'s
outputs: the rate of an unaligned one depends on where it starts), on one thread.

Prints the best of several calls as steps per CPU second of the calling thread (what other load
on the machine disturbs least) and per wall second, with the build loaded. Run it with the
Python of the install to measure (a wheel in a fresh environment, a checkout, an older commit's
worktree); ``GSFRIC_ISA`` picks another build. Compare two installs by running both in turn,
several times, in one session::

    for k in 1 2 3; do
        OLD/python benchmarks/hot_path.py; NEW/python benchmarks/hot_path.py
    done
"""

from __future__ import annotations

import json
import time

import numpy as np

import gsfric
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.memory import aligned_empty
from gsfric.models import random_motion

STEPS = 100_000
CALLS = 30
RATE = 1000.0
"""Sampling rate of the motion, Hz."""
SEED = 20261122
"""The motion's seed (the one of benchmarks/cases.py)."""


def main() -> None:
    x = np.ascontiguousarray(state_array(random_motion(np.random.default_rng(SEED),
                                                           np.arange(STEPS) / RATE)))
    evaluator = Evaluator(gsfric.reference_platform(), n_threads=1)
    out = aligned_empty(STEPS, 6)     # whole cache lines: the vector stores' fast path
    evaluator.actuator_forces(x, out)                  # warm-up: load, first touch
    cpu, wall = [], []
    for _ in range(CALLS):
        c0, t0 = time.thread_time(), time.perf_counter()
        evaluator.actuator_forces(x, out)
        cpu.append(time.thread_time() - c0)
        wall.append(time.perf_counter() - t0)
    try:
        from gsfric.compiled import native
        build = native.chosen_build()
    except (ImportError, AttributeError):
        build = "compiled at first use"
    print(json.dumps({"build": build, "steps_per_cpu_s": STEPS / min(cpu),
                      "steps_per_wall_s": STEPS / min(wall),
                      "checksum": float(np.abs(out).sum())}))


if __name__ == "__main__":
    main()
