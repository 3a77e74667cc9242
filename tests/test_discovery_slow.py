"""The discovery workflow's rates over many seeded trials (slow: ``pytest -m slow``).

For every catalog effect, 20 seeded trials (parameters from plausible ranges, effect sizes
drawn in [2, 10], white or AR(1) noise, pose noise, random excitation motions): the workflow
must name the effect in at least 95% of them, fit its parameters within 10% (size >= 5) or 25%
(size < 5), and bring rms_after to at most 1.15 times the noise level. Without a hidden effect
(white and strongly autocorrelated noise, 20 trials each) it must name nothing in at least 95%.
With two hidden effects it must name both.

Each test writes its trials to ``$GSFRIC_DISCOVERY_RESULTS/<test>.json`` when that variable is
set; ``python tests/test_discovery_slow.py DIR`` prints the confusion matrix and the rates as
Markdown (docs/explanation/discovery.md).
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_discovery import (
    NULL_POSE,
    RMS_LIMIT,
    make_case,
    parameter_error,
    run_case,
    tolerance,
)

from gsfric.discovery import CANDIDATE_NAMES

SEEDS = range(100, 120)
RATE = 0.95
PAIRS = (("stribeck", "sensor_bias"), ("seal_friction", "payload_offset"),
         ("quadratic_drag", "stroke_friction"), ("bushing_friction", "joint_friction_coupling"),
         ("leg_weight", "stribeck"))


def _trial(names, seed, **kwargs) -> dict:
    case = make_case(names, seed, **kwargs)
    start = time.perf_counter()
    result = run_case(case)
    elapsed = time.perf_counter() - start
    errors = {}
    for f in result.effects:
        if f.name in case.parameters:
            errors[f.name] = parameter_error(case, f.name, f.parameters)
    return {"hidden": list(names), "seed": seed, "phi": case.phi, "sigma": case.sigma,
            "pose_noise": case.pose_noise, "sizes": case.sizes, "found": result.names,
            "errors": errors, "fitted": {f.name: f.parameters for f in result.effects},
            "true": case.parameters, "rms_ratio": result.rms_after / case.sigma,
            "floor_ratio": case.floor / case.sigma,
            "rms_before_ratio": result.rms_before / case.sigma,
            "ambiguous": result.summary()["ambiguous"], "seconds": elapsed}


def _save(name: str, trials: list[dict]) -> None:
    folder = os.environ.get("GSFRIC_DISCOVERY_RESULTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        (Path(folder) / f"{name}.json").write_text(json.dumps(trials, indent=1))


@pytest.mark.slow
@pytest.mark.parametrize("name", CANDIDATE_NAMES)
def test_hidden_effect_rates(name):
    trials = [_trial([name], seed) for seed in SEEDS]
    _save(name, trials)
    named = np.mean([name in t["found"] for t in trials])
    exact = np.mean([t["found"] == [name] for t in trials])
    accurate = np.mean([t["errors"].get(name, np.inf) <= tolerance(t["sizes"][name])
                        for t in trials])
    closed = np.mean([t["rms_ratio"] <= RMS_LIMIT for t in trials])
    assert named >= RATE, trials
    assert exact >= RATE, trials
    assert accurate >= RATE, trials
    assert closed >= RATE, trials


@pytest.mark.slow
@pytest.mark.parametrize("phi", [0.0, 0.95])
def test_no_effect_rates(phi):
    trials = [_trial([], seed, phi=phi, sigma=0.2, pose=NULL_POSE) for seed in SEEDS]
    _save(f"none_phi{phi:g}", trials)
    assert np.mean([t["found"] == [] for t in trials]) >= RATE, trials


@pytest.mark.slow
def test_two_effect_rates():
    trials = [_trial(list(pair), seed) for pair in PAIRS for seed in list(SEEDS)[:4]]
    _save("pairs", trials)
    assert np.mean([sorted(t["found"]) == sorted(t["hidden"]) for t in trials]) >= RATE, trials


# -- the tables of docs/explanation/discovery.md -----------------------------------------------------------


def markdown(folder: str | os.PathLike[str]) -> str:
    """Confusion matrix and rates from the saved trials, as Markdown."""
    files = sorted(Path(folder).glob("*.json"))
    runs = {f.stem: json.loads(f.read_text()) for f in files}
    columns = list(CANDIDATE_NAMES) + ["(nothing)"]
    lines = ["| hidden \\ named | trials | " + " | ".join(columns) + " |",
             "|---|---|" + "---|" * len(columns)]
    rows = [n for n in CANDIDATE_NAMES if n in runs] + [k for k in runs if k.startswith("none")]
    for key in rows:
        trials = runs[key]
        counts = [sum(c in t["found"] for t in trials) for c in CANDIDATE_NAMES]
        counts.append(sum(not t["found"] for t in trials))
        label = key if not key.startswith("none") else \
            f"none, phi = {key.split('phi')[1]}"
        lines.append(f"| {label} | {len(trials)} | " + " | ".join(
            f"**{c}**" if (c and (col == key or (col == '(nothing)' and key.startswith('none'))))
            else str(c) for c, col in zip(counts, columns)) + " |")
    lines += ["", "| hidden effect | named | named alone | parameters within tolerance | "
              "median / worst parameter error | rms_after / noise: median / worst | "
              "true model / noise: worst | effect sizes | median time (s) |",
              "|---|---|---|---|---|---|---|---|---|"]
    for key in [n for n in CANDIDATE_NAMES if n in runs]:
        trials = runs[key]
        errors = [t["errors"].get(key, np.inf) for t in trials]
        ok = [e <= (0.10 if t["sizes"][key] >= 5 else 0.25) for e, t in zip(errors, trials)]
        ratios = [t["rms_ratio"] for t in trials]
        sizes = [t["sizes"][key] for t in trials]
        lines.append(
            f"| {key} | {sum(key in t['found'] for t in trials)}/{len(trials)} | "
            f"{sum(t['found'] == [key] for t in trials)}/{len(trials)} | "
            f"{sum(ok)}/{len(trials)} | {np.median(errors):.2%} / {max(errors):.2%} | "
            f"{np.median(ratios):.3f} / {max(ratios):.3f} | "
            f"{max(t['floor_ratio'] for t in trials):.3f} | "
            f"{min(sizes):.1f}-{max(sizes):.1f} | "
            f"{np.median([t['seconds'] for t in trials]):.1f} |")
    nulls = [k for k in runs if k.startswith("none")]
    if nulls:
        lines += ["", "| no hidden effect | trials | nothing named | false discoveries | "
                  "rms_after / noise: worst |", "|---|---|---|---|---|"]
        for key in nulls:
            trials = runs[key]
            wrong = sorted({n for t in trials for n in t["found"]})
            lines.append(f"| noise phi = {key.split('phi')[1]} | {len(trials)} | "
                         f"{sum(not t['found'] for t in trials)} | "
                         f"{', '.join(wrong) if wrong else 'none'} | "
                         f"{max(t['rms_ratio'] for t in trials):.3f} |")
    if "pairs" in runs:
        trials = runs["pairs"]
        lines += ["", "| hidden pair | trials | both named | only those named |",
                  "|---|---|---|---|"]
        for pair in PAIRS:
            sub = [t for t in trials if t["hidden"] == list(pair)]
            lines.append(f"| {' + '.join(pair)} | {len(sub)} | "
                         f"{sum(set(pair) <= set(t['found']) for t in sub)} | "
                         f"{sum(sorted(t['found']) == sorted(pair) for t in sub)} |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(markdown(sys.argv[1]))


REST_EFFECTS = {"stribeck": {"static": 1.0, "velocity": 0.01}, "seal_friction": {"force": 1.0},
                "stroke_friction": {"slope": 20.0}, "time_offset": {"delay": 0.01}}
"""Effects whose signature lives next to the starts and stops of moves (unit parameters)."""


def _rest_trial(base: str, name: str | None, seed: int, size: float = 3.0) -> dict:
    """One point-to-point record with rests (pose noise 1e-5 m and rad, white or AR(1) force
    noise of 0.2 N), the effect scaled to ``size`` times the noise."""
    from gsfric import models
    from gsfric.discovery import discover
    from gsfric.discovery.rest import poses_from_columns
    from gsfric.simulate.api import evaluate
    from gsfric.synth import effect_contributions, synthesize
    from gsfric.trajectory import Motion

    rng = np.random.default_rng(seed)
    platform = models.reference_platform(friction_model=base)
    motion = models.point_to_point(rng, 4000)
    sigma, phi = 0.2, (0.0, 0.95)[seed % 2]
    effects = {}
    if name is not None:
        params = dict(REST_EFFECTS[name])
        if name == "stroke_friction":
            params["reference"] = float(evaluate(platform, motion).D.min())
        c = effect_contributions(platform.with_effect(name, **params), motion, [name])[name]
        key = next(iter(REST_EFFECTS[name]))
        params[key] *= size * sigma / float(np.sqrt(np.mean(c ** 2)))
        effects[name] = params
    data = synthesize(platform, effects, motion=motion, noise=sigma, noise_correlation=phi,
                      pose_noise=1e-5, seed=seed)
    fr = data.frame
    rec = Motion.from_samples(fr.t.values, fr[["x", "y", "z"]].values,
                              quaternion=fr[["qw", "qx", "qy", "qz"]].values)
    result = discover(rec, fr[[f"F{i}" for i in range(1, 7)]].values, platform,
                      poses=poses_from_columns(fr), n_bootstrap=20, n_threads=1)
    return {"found": result.names, "verdict": result.verdict,
            "rms_ratio": result.rms_after / float(np.sqrt(np.mean(data.noise ** 2)))}


@pytest.mark.slow
@pytest.mark.parametrize("base", ["paper", "coupled"])
@pytest.mark.parametrize("name", list(REST_EFFECTS) + [None])
def test_rates_through_rests(base, name):
    """Point-to-point moves with rests, on both base friction models: each effect named alone
    at effect-to-noise 3 in >= 95% of 20 records and rms_after within 1.15 times the noise;
    without an effect nothing named."""
    trials = [_rest_trial(base, name, seed) for seed in range(200, 220)]
    _save(f"rests-{base}-{name}", trials)
    expected = [] if name is None else [name]
    assert np.mean([t["found"] == expected for t in trials]) >= RATE, trials
    assert np.mean([t["rms_ratio"] <= RMS_LIMIT for t in trials]) >= RATE, trials
