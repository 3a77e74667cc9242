"""The hot path of an earlier source against the current one, in one run.

Usage::

    .venv/bin/python benchmarks/hot_path_history.py [--ref ef651e9] [--steps 100000]
                                                     [--rounds 3] [--calls 15]

The earlier source (``git archive`` of ``--ref``) is unpacked once into ``--workdir`` (default
``$TMPDIR/gsfric-history-<commit>``) and compiles its library into a cache of its own there, so
that neither source's cache sees the other's build. Then, in interleaved rounds, each variant
runs in a fresh process with its own source first on ``sys.path``:

* ``<ref> default``: the earlier source's ``reference_platform()`` (at ``ef651e9`` its default
  friction model was the paper's post-hoc one);
* ``current paper``: this source's ``reference_platform("paper")`` (``actuator_posthoc``);
* ``current coupled``: this source's ``reference_platform()`` (``actuator_coupled``);
* with ``--ref-paper``, ``<ref> paper``: the earlier source's ``reference_platform("paper")``.

Each process times ``Evaluator(platform).actuator_forces(x, out)`` on one thread at N steps of
the same states (one array, written once by this script), ``--calls`` calls, and reports the
fastest call's time of the calling thread's CPU (``time.thread_time``), which other load on the
machine disturbs less than the wall clock. The best of the rounds gives the steps per CPU second
of each variant, and the ratios to the earlier source. The forces of the earlier default and
of the current paper model are compared too: the same friction model, but the reference
platform's legs and joints have changed since ``ef651e9`` (``models.reference_leg``), so they
differ by far more than rounding; the time per step hardly depends on the parameters' values.

``--paths`` also times, in the same processes, ``gsfric.evaluate`` at N steps with fresh result
arrays and into reused ones (``evaluate_quiet(buffers=...)``), and the README's control loop (a
new ``Evaluator`` and ``forces`` on a 40-step motion: the median of 15 runs of 1000 calls), per
CPU second; for a ``--ref`` that has these (e.g. the source a change started from)::

    .venv/bin/python benchmarks/hot_path_history.py --ref 224f3ea --paths
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

import numpy as np

from gsfric.bench import cases as bench

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
import json, sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
import gsfric
from gsfric import models
from gsfric.evaluation.evaluator import Evaluator
assert gsfric.__file__.startswith(sys.argv[1]), gsfric.__file__
model, states, calls, forces = sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
x = np.load(states)
platform = models.reference_platform() if model == "default" else models.reference_platform(model)
ev = Evaluator(platform, n_threads=1)
out = np.empty((len(x), 6))
ev.actuator_forces(x, out)
best = float("inf")
for _ in range(calls):
    t0 = time.thread_time()
    ev.actuator_forces(x, out)
    best = min(best, time.thread_time() - t0)
if forces != "-":
    np.save(forces, out)
res = {"cpu_s": best}
if len(sys.argv) > 6:  # the paths around the hot path (a source with Evaluator.forces)
    from gsfric.bench.cases import bench_motion
    motion = bench_motion(len(x))
    def fastest(f, calls):
        f()
        times = []
        for _ in range(calls):
            t0 = time.thread_time()
            f()
            times.append(time.thread_time() - t0)
        return times
    res["evaluate_cpu_s"] = min(fastest(lambda: gsfric.evaluate(platform, motion), 5))
    buffers = {}
    res["reused_cpu_s"] = min(fastest(lambda: ev.evaluate_quiet(motion, buffers=buffers), 5))
    m40 = bench_motion(40)
    args = (m40.position, m40.rotation, m40.velocity, m40.omega, m40.acceleration, m40.alpha)
    loop = fastest(lambda: [Evaluator(platform).forces(*args) for _ in range(1000)], 15)
    res["control_40_cpu_s"] = sorted(loop)[len(loop) // 2] / 1000
print(json.dumps(res))
"""


def _unpack(ref: str, workdir: Path) -> Path:
    """The source of ``ref`` under workdir/src (unpacked once)."""
    src = workdir / "src"
    if not (src / "gsfric" / "__init__.py").exists():
        workdir.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref], check=True,
                                 capture_output=True).stdout
        tmp = Path(tempfile.mkdtemp(dir=workdir))
        with tarfile.open(fileobj=__import__("io").BytesIO(archive)) as tar:
            tar.extractall(tmp, filter="data")
        tmp.rename(src)
    return src


def _run(source: Path, cache: Path, model: str, states: Path, calls: int,
         forces: str = "-", paths: bool = False) -> dict:
    env = dict(os.environ, GSFRIC_CACHE=str(cache), OMP_NUM_THREADS="1")
    env.pop("PYTHONPATH", None)
    env.pop("GSFRIC_GENERATED", None)
    run = subprocess.run([sys.executable, "-c", CHILD, str(source), model, str(states),
                          str(calls), forces] + (["paths"] if paths else []), env=env,
                         capture_output=True, text=True, cwd=str(states.parent))
    if run.returncode:
        raise SystemExit(f"{source} ({model}): {run.stderr.strip().splitlines()[-1]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ref", default="ef651e9", help="the earlier source (a git commit)")
    parser.add_argument("--steps", type=int, default=100_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--calls", type=int, default=15)
    parser.add_argument("--workdir", type=Path, default=None)
    parser.add_argument("--ref-paper", action="store_true",
                        help="also time the earlier source's reference_platform(\"paper\") "
                             "(a --ref whose reference_platform takes the friction model)")
    parser.add_argument("--paths", action="store_true",
                        help="also time gsfric.evaluate (fresh and reused arrays) and the "
                             "README's 40-step control loop of each source (a --ref that has "
                             "Evaluator.forces)")
    args = parser.parse_args(argv)

    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", args.ref],
                            check=True, capture_output=True, text=True).stdout.strip()
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip() or "?"
    workdir = args.workdir or Path(tempfile.gettempdir()) / f"gsfric-history-{commit}"
    old_src = _unpack(commit, workdir)
    old_cache = workdir / "cache"
    new_cache = Path(os.environ.get("GSFRIC_CACHE") or workdir / "cache-current")

    states = workdir / f"states-{args.steps}.npy"
    np.save(states, bench.states(args.steps))

    variants = {
        f"{commit} reference_platform()": (old_src, old_cache, "default"),
        "current paper (actuator_posthoc)": (ROOT, new_cache, "paper"),
        "current coupled (actuator_coupled)": (ROOT, new_cache, "coupled"),
    }
    if args.ref_paper:
        variants[f"{commit} paper"] = (old_src, old_cache, "paper")
    # a first pass builds (or finds) each source's library and keeps the forces to compare
    names = list(variants)
    saved = {}
    for name in names[:2]:
        src, cache, model = variants[name]
        saved[name] = workdir / f"forces-{model}-{'old' if src != ROOT else 'new'}.npy"
        _run(src, cache, model, states, 1, str(saved[name]))
    for name in names[2:]:
        _run(*variants[name], states, 1)
    old_f, new_f = (np.load(saved[n]) for n in names[:2])
    diff = float(np.max(np.abs(old_f - new_f) / (1.0 + np.abs(old_f))))

    keys = ("cpu_s", "evaluate_cpu_s", "reused_cpu_s", "control_40_cpu_s")
    best = {name: dict.fromkeys(keys, np.inf) for name in names}
    for r in range(args.rounds):
        order = names if r % 2 == 0 else names[::-1]
        for name in order:
            res = _run(*variants[name], states, args.calls, paths=args.paths)
            for key, value in res.items():
                best[name][key] = min(best[name][key], value)
            print(f"round {r + 1}: {name}: {res}", file=sys.stderr, flush=True)
    timings = best
    best = {name: timings[name]["cpu_s"] for name in names}
    base = best[names[0]]
    print(f"hot path Evaluator.actuator_forces(x, out), N = {args.steps:,}, one thread; "
          f"{commit} against {head}; steps per CPU second, best of {args.rounds} interleaved "
          f"rounds x {args.calls} calls, each round a fresh process per variant")
    for name in names:
        print(f"  {name:<36} {args.steps / best[name] / 1e6:6.3f} M   "
              f"{base / best[name]:.2f}x {commit}")
    print(f"  forces of {names[0]} against current paper: largest |difference| / (1 N + |F|) "
          f"= {diff:.1e} (a different platform unless the earlier default is the same)")
    if args.paths:
        print(f"paths (best of the rounds; per CPU second): gsfric.evaluate N = {args.steps:,} "
              "fresh arrays / into reused arrays (evaluate_quiet(buffers=...)), and the README's "
              "control loop (new Evaluator + forces, 40 steps, median of 15 x 1000 calls)")
        for name in names:
            t = timings[name]
            print(f"  {name:<36} evaluate {args.steps / t['evaluate_cpu_s'] / 1e6:.3f} M, "
                  f"reused {args.steps / t['reused_cpu_s'] / 1e6:.3f} M, control loop "
                  f"{t['control_40_cpu_s'] * 1e6:.2f} us")


if __name__ == "__main__":
    main()
