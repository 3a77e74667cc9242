"""Discovery on point-to-point translations with a fixed orientation (docs/explanation/discovery.md).

A test rig often moves the platform in translation only: minimum-jerk moves between random
targets, a rest after each, the orientation held. Each case draws a sampling rate (200, 500 or
1000 Hz), a move duration (0.3, 0.7 or 1.2 s), rests of 0.4-2.5 s, pose noise (0, 3 um or
10 um), force noise (0.05 or 0.2 N; white or AR(1) with phi 0.9 or 0.95) and either nothing
(a null) or one catalog effect at ``--size`` times the noise. The workflow reads the recorded
poses as the command line does. Prints, per effect, the share named alone with the verdict
``explained``, the nulls' false discoveries, and the records the workflow refuses as a data
problem (moves too short for the differentiator).

    python benchmarks/discovery_translations.py --model paper --cases 64 --size 3
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter

import numpy as np

from gsfric.discovery import discover
from gsfric.discovery.candidates import CANDIDATES
from gsfric.errors import InputError
from gsfric.models import minimum_jerk_moves, reference_platform
from gsfric.signal.rotations import rotation_from_quaternion
from gsfric.synth import synthesize
from gsfric.trajectory import Motion

EFFECTS = ("stribeck", "seal_friction", "quadratic_drag", "stroke_friction", "payload_offset",
           "sensor_bias", "force_scale", "time_offset", "joint_friction_coupling")


def effects_of(model: str) -> list[str]:
    """``EFFECTS`` that are candidates on the reference platform with friction ``model``
    (the coupled model has the joints' friction coupling of its own)."""
    platform = reference_platform(friction_model=model)
    return [c.name for c in CANDIDATES if c.name in EFFECTS and not c.applies(platform)]


def moves(rng, rate: float, move: float, rest: float) -> Motion:
    """Minimum-jerk translations between random targets, a rest after each, the orientation
    fixed (``models.minimum_jerk_moves``), over at least 8 s."""
    seconds = min(max(8.0, 12 * (move + rest)), 10000 / rate)
    t = np.arange(int(rate * seconds)) / rate
    period = move + rest
    count = int(t[-1] // period) + 2
    amplitude = rng.choice([0.01, 0.03])
    targets = np.c_[rng.uniform(-amplitude, amplitude, (count, 2)),
                    0.95 + rng.uniform(-0.02, 0.02, count)]
    return minimum_jerk_moves(t, targets, period, move)


def unit_effect(rng, name: str) -> tuple[dict[str, float], list[str]]:
    """Parameters of ``name`` of arbitrary size, and the ones that scale it."""
    if name == "sensor_bias":
        return {f"b{i}": float(v) for i, v in enumerate(rng.normal(size=6), 1)}, []
    if name == "force_scale":
        return {f"g{i}": float(v) for i, v in enumerate(rng.normal(0, 0.01, 6), 1)}, []
    if name == "payload_offset":
        v = rng.normal(size=3)
        return dict(zip("xyz", (0.01 * v / np.linalg.norm(v)).tolist())), []
    params = {"stribeck": {"static": 1.0, "velocity": float(rng.uniform(0.005, 0.03))},
              "seal_friction": {"force": 1.0}, "quadratic_drag": {"coefficient": 10.0},
              "stroke_friction": {"slope": 10.0}, "time_offset": {"delay": 0.005},
              "joint_friction_coupling": {"scale": 0.5}}[name]
    return params, [next(iter(params))]


def case(seed: int, model: str, name: str | None, size: float) -> dict:
    """One drawn record through ``discover``: what was drawn and what came out."""
    rng = np.random.default_rng(seed)
    rate = float(rng.choice([200.0, 500.0, 1000.0]))
    move, rest = float(rng.choice([0.3, 0.7, 1.2])), float(rng.uniform(0.4, 2.5))
    motion = moves(rng, rate, move, rest)
    pose = float(rng.choice([0.0, 3e-6, 1e-5]))
    sigma, phi = float(rng.choice([0.05, 0.2])), float(rng.choice([0.0, 0.9, 0.95]))
    platform = reference_platform(friction_model=model)
    params, keys = unit_effect(rng, name) if name is not None else ({}, [])
    for _ in range(4):     # the effects are close to linear in their scaled parameters
        data = synthesize(platform, {name: params} if name is not None else {}, motion=motion,
                          noise=sigma, noise_correlation=phi, pose_noise=pose, seed=seed)
        k = 1.0 if name is None else size / max(data.sizes[name], 1e-12)
        if abs(k - 1) < 0.03:
            break
        params = {p: v * k if not keys or p in keys else v for p, v in params.items()}
    f = data.frame
    position = f[["x", "y", "z"]].to_numpy()
    quaternion = f[["qw", "qx", "qy", "qz"]].to_numpy()
    recorded = Motion.from_samples(f.t.to_numpy(), position, quaternion=quaternion)
    out = {"seed": seed, "effect": name or "null", "rate": rate, "move": move,
           "rest": round(rest, 2), "pose": pose, "noise": sigma, "phi": phi}
    try:
        r = discover(recorded, f[[f"F{i}" for i in range(1, 7)]].to_numpy(), platform,
                     n_threads=1, poses=(position, rotation_from_quaternion(quaternion)))
    except InputError as error:
        return {**out, "refused": str(error)}
    except Exception as error:     # a failure of the workflow itself: counted, not fatal
        return {**out, "ok": False, "error": f"{type(error).__name__}: {error}"}
    expected = ([] if name is None else [name],
                "no_discrepancy" if name is None else "explained")
    return {**out, "size": round(data.sizes.get(name, 0.0), 2), "named": r.names,
            "verdict": r.verdict, "ok": (r.names, r.verdict) == expected,
            "rms_after/noise": round(r.rms_after / sigma, 3)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", choices=("paper", "coupled"), default="paper")
    parser.add_argument("--cases", type=int, default=60,
                        help="cases; a third of them nulls, the rest cycle through the effects")
    parser.add_argument("--size", type=float, default=3.0, help="effect-to-noise of the effects")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--verbose", action="store_true", help="one JSON line per case")
    args = parser.parse_args()
    start = time.perf_counter()
    done, named, refused = Counter(), Counter(), Counter()
    failures = []
    effects = effects_of(args.model)
    for i in range(args.cases):
        name = None if i % 3 == 0 else effects[(i - i // 3 - 1) % len(effects)]
        row = case(10_000 * args.seed + i, args.model, name, args.size)
        key = row["effect"]
        if args.verbose:
            print(json.dumps(row), flush=True)
        if "refused" in row:
            refused[key] += 1
            continue
        done[key] += 1
        named[key] += row["ok"]
        if not row["ok"]:
            failures.append(row)
    print(f"{args.cases} cases, base model {args.model}, effect-to-noise {args.size:g}, "
          f"seed {args.seed}, {time.perf_counter() - start:.0f} s")
    print(f"{'effect':26s} {'right':>7s} {'of':>4s} {'refused':>8s}")
    for key in ["null", *effects]:
        if done[key] or refused[key]:
            share = named[key] / done[key] if done[key] else float("nan")
            print(f"{key:26s} {share:7.0%} {done[key]:4d} {refused[key]:8d}")
    print("(null: right = nothing named, no_discrepancy; an effect: right = named alone, "
          "explained; refused: a data problem, too few sliding pairs)")
    for row in failures:
        print("  failed:", json.dumps(row))


if __name__ == "__main__":
    main()
