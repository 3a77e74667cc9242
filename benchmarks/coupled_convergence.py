"""Convergence of the coupled friction solve against mu r, and its cost, for one generated model.

For each mu r of a grid, the reference platform and 11 random platforms around it
(``tests/helpers_validation.random_platform``), with ``joint_coulomb = mu r / 0.05`` at
``joint_radius = 0.05``, each on a 60-step random motion: the largest last change of the axial
forces relative to ``1 N + |F0|`` (the flag's measure, ``COUPLING_TOLERANCE`` = 1e-6) and how many
steps are flagged 16 (``FLAG_COUPLING``). Then the combined map's throughput per CPU second, one
thread, N = 1e5, both friction models (best of 15 calls)::

    .venv/bin/python benchmarks/coupled_convergence.py
    .venv/bin/python benchmarks/coupled_convergence.py --mu-r 0.005 0.01 --no-timing

To compare variants of the solve (``N_ITERATIONS``, ``ACCELERATE`` in derive/coupled.py), copy
generated/ after each ``gsfric derive`` and run this script on each copy in turn, alternating,
with ``GSFRIC_GENERATED=<copy>``; docs/explanation/friction.md has the table of one such session.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from helpers_validation import random_platform  # noqa: E402

import gsfric  # noqa: E402
from benchmarks import cases as bench  # noqa: E402
from gsfric import models  # noqa: E402
from gsfric.evaluation.evaluator import Evaluator  # noqa: E402
from gsfric.evaluation.flags import FLAG_COUPLING  # noqa: E402

MU_R = (0.002, 0.003, 0.004, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03)
PLATFORMS = 12
STEPS = 60


def convergence(mu_r: float, platforms: int = PLATFORMS) -> tuple[float, int, int]:
    """(largest |coupling_change| / (1 + |F0|), flagged steps, steps) at one mu r."""
    worst, flagged, total = 0.0, 0, 0
    for seed in range(platforms):
        rng = np.random.default_rng(seed)
        base = models.reference_platform() if seed == 0 else random_platform(rng)
        platform = base.with_friction(model="coupled", joint_radius=0.05,
                                      joint_coulomb=mu_r / 0.05)
        motion = models.random_motion(np.random.default_rng(1000 + seed),
                                      np.linspace(0.0, 3.0, STEPS))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = gsfric.evaluate(platform, motion, strict=False)
        worst = max(worst, float((np.abs(result.coupling_change)
                                  / (1.0 + np.abs(result.F0))).max()))
        flagged += int(np.count_nonzero(result.flag & FLAG_COUPLING))
        total += len(result)
    return worst, flagged, total


def throughput(model: str, n: int = 100_000, calls: int = 15) -> float:
    """Steps per CPU second of ``Evaluator.actuator_forces``, one thread, best of ``calls``."""
    x = bench.states(n)
    evaluator = Evaluator(models.reference_platform(model), n_threads=1)
    out = np.empty((n, 6))
    evaluator.actuator_forces(x, out=out)
    best = np.inf
    for _ in range(calls):
        start = time.thread_time()
        evaluator.actuator_forces(x, out=out)
        best = min(best, time.thread_time() - start)
    return n / best


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mu-r", type=float, nargs="+", default=list(MU_R), help="m")
    parser.add_argument("--no-timing", action="store_true")
    args = parser.parse_args(argv)
    for mu_r in args.mu_r:
        worst, flagged, total = convergence(mu_r)
        print(f"mu r = {mu_r:.4f} m: largest |change| / (1 + |F0|) = {worst:.2e}, "
              f"flagged {flagged} of {total}", flush=True)
    if not args.no_timing:
        for model in ("coupled", "paper"):
            print(f"{model}: {throughput(model) / 1e6:.3f} M steps per CPU second", flush=True)


if __name__ == "__main__":
    main()
