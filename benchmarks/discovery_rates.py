"""Rates of the discovery workflow on generated rig data (docs/explanation/discovery.md).

Its own generator: three motion families (sines, chirps, point-to-point minimum-jerk moves
with rests), two platforms (the reference platform, and one with a 1.5x payload and 2x
prismatic viscous friction), white and AR(1) force noise (phi up to 0.95), pose noise, effects
at effect-to-noise 2-10, null cases, pairs and out-of-catalog cases (a delay when
time_offset is left out of the candidates; a load cell with a quadratic characteristic).
Rig faults outside the catalog (``FAULTS``: interference lines at mains and other
frequencies, a dead band or hysteresis in one or several load cells, cross-talk between
channels, a slow drift of the zero) at effect-to-noise 2-5, on moves with rests and on
continuous motion, under white, AR(1) and pink force noise (``NOISES``).
Prints the table of rates and, for the cases named correctly, the largest rms_after over the
true noise and over the residual of the true model on the recorded motion (the best any model
can do when the motion is differentiated from noisy poses), the misses that the result itself
reports as ambiguous (the hidden effect listed as indistinguishable from what was fitted), and
the out-of-catalog cases confidently misnamed (a catalog name with the verdict "explained");
then the goal table of the honest verdict (``goals``).

    python benchmarks/discovery_rates.py                 # the full table (long)
    python benchmarks/discovery_rates.py --per-cell 2 --samples 3000   # a quick look
    python benchmarks/discovery_rates.py --kinds fault null --per-cell 1   # the faults
"""

from __future__ import annotations

import argparse
import time
from collections import defaultdict
from dataclasses import dataclass

import numpy as np

from gsfric import models
from gsfric.discovery import CANDIDATE_NAMES, discover
from gsfric.discovery.rest import poses_from_columns
from gsfric.models import reference_platform
from gsfric.signal.rotations import quaternion_from_rotation, rotation_from_euler
from gsfric.synth import synthesize
from gsfric.trajectory import Motion

RATE = 200.0
AMPLITUDE = np.array([0.03, 0.03, 0.02, 0.05, 0.05, 0.05])


def _motion(pose: np.ndarray, t: np.ndarray) -> Motion:
    position = pose[:, :3] + [0.0, 0.0, 0.95]
    rotation = rotation_from_euler(pose[:, 3], pose[:, 4] + 0.2, pose[:, 5])
    return Motion.from_samples(t, position, quaternion=quaternion_from_rotation(rotation))


def sines(rng, n):
    t = np.arange(n) / RATE
    f = rng.uniform(0.2, 1.2, 6)
    ph = rng.uniform(0, 2 * np.pi, 6)
    return _motion(AMPLITUDE * np.sin(2 * np.pi * f * t[:, None] + ph), t)


def chirps(rng, n):
    t = np.arange(n) / RATE
    f0, f1 = rng.uniform(0.05, 0.2, 6), rng.uniform(1.0, 2.0, 6)
    phase = 2 * np.pi * (f0 * t[:, None] + (f1 - f0) * t[:, None] ** 2 / (2 * t[-1]))
    return _motion(AMPLITUDE * np.sin(phase + rng.uniform(0, 2 * np.pi, 6)), t)


def point_to_point(rng, n):
    return models.point_to_point(rng, n, RATE, AMPLITUDE, height=0.95)


FAMILIES = {"sines": sines, "chirps": chirps, "rests": point_to_point}


# -- force noise and rig faults outside the catalog --------------------------------------------


def force_noise(kind: str, rng, n: int, sigma: float, phi: float = 0.9) -> np.ndarray:
    """Force noise (n, 6) of standard deviation sigma: ``white``, ``ar`` (AR(1) of
    coefficient phi) or ``pink`` (1/f power from 1/n of the rate up)."""
    w = rng.normal(size=(n, 6))
    if kind == "ar":
        x = np.empty_like(w)
        x[0] = w[0]
        for k in range(1, n):
            x[k] = phi * x[k - 1] + np.sqrt(1 - phi ** 2) * w[k]
    elif kind == "pink":
        f = np.fft.rfftfreq(n)
        f[0] = f[1]
        x = np.fft.irfft(np.fft.rfft(w, axis=0) / np.sqrt(f)[:, None], n, axis=0)
    else:
        x = w
    return sigma * x / x.std(axis=0)


def _play(F: np.ndarray, width: np.ndarray) -> np.ndarray:
    out, y = np.empty_like(F), F[0].copy()
    for k in range(len(F)):
        y = np.clip(y, F[k] - width, F[k] + width)
        out[k] = y
    return out


def fault(kind: str, F: np.ndarray, t: np.ndarray, rng, size: float, sigma: float
          ) -> np.ndarray:
    """A rig fault's error of the force readings (n, 6), N, of RMS ``size * sigma`` over the
    legs it is on, for the true forces F (n, 6) at times t (s)."""
    n = len(t)
    legs = rng.choice(6, size=int(rng.integers(1, 4)), replace=False)
    x = np.zeros_like(F)
    if kind in ("mains", "line"):
        f = 50.0 if kind == "mains" else float(rng.uniform(8.0, 0.4 / (t[1] - t[0])))
        phase = rng.uniform(0, 2 * np.pi)
        x[:, legs] = np.sin(2 * np.pi * f * t + phase)[:, None]
    elif kind == "dead_band":
        # the width grows until the error reaches its size
        width = np.full(6, size * sigma)
        x[:, legs] = (_play(F, width) - F)[:, legs]
    elif kind == "hysteresis":
        h = size * sigma
        z = np.zeros(6)
        dF = np.diff(F, axis=0, prepend=F[:1])
        for k in range(n):       # a Dahl-type reading: lags the force by up to h
            z = np.clip(z - dF[k] * (1 + np.sign(dF[k]) * z / h), -h, h)
            x[k, legs] = z[legs]
    elif kind == "coupling":
        source = [(i + 1 + int(rng.integers(0, 5))) % 6 for i in legs]
        for i, j in zip(legs, source):
            x[:, i] = F[:, j] - F[:, j].mean()
    elif kind == "drift":
        tau = (t - t[0]) / (t[-1] - t[0])
        x[:, legs] = (tau + 0.5 * tau ** 2)[:, None] * rng.choice([-1, 1], len(legs))
        x -= x.mean(axis=0)
    scale = np.sqrt(np.mean(x[:, legs] ** 2))
    return x * size * sigma / max(scale, 1e-300)


FAULTS = ("mains", "line", "dead_band", "hysteresis", "coupling", "drift")
NOISES = ("white", "ar", "pink")


MODEL = "paper"
"""The base friction model of both platforms (``--model``); never the library's default."""

COUPLED_ONLY = ("joint_friction_coupling", "bushing_friction")
"""Effects that are part of the coupled friction model itself (not candidates on it)."""


def platforms():
    ref = reference_platform(friction_model=MODEL)
    heavy = ref.with_body(payload_mass=1.5 * ref.platform.payload_mass).with_friction(
        prismatic_viscous=2 * ref.friction.prismatic_viscous)
    return {"reference": ref, "heavy": heavy}


UNIT = {  # parameters giving an effect of about unit size; scaled to the drawn size
    "stribeck": {"static": 1.0, "velocity": 0.01},
    "seal_friction": {"force": 1.0},
    "quadratic_drag": {"coefficient": 20.0},
    "stroke_friction": {"slope": 20.0},
    "payload_offset": {"x": 0.02, "y": -0.01, "z": 0.01},
    "sensor_bias": {f"b{i}": v for i, v in enumerate([1, -1, 0.5, -0.5, 1, -1], 1)},
    "joint_friction_coupling": {"scale": 1.0},
    "bushing_friction": {"coefficient": 0.1},
    "force_scale": {f"g{i}": v for i, v in enumerate([0.02, -0.02, 0.01, -0.01, 0.02, 0.0], 1)},
    "time_offset": {"delay": 0.01},
}
SCALED = {"stribeck": "static", "seal_friction": "force", "quadratic_drag": "coefficient",
          "stroke_friction": "slope", "joint_friction_coupling": "scale",
          "bushing_friction": "coefficient", "time_offset": "delay"}


def scaled(name, platform, motion, size, sigma):
    """Parameters of ``name`` giving an effect of RMS ``size * sigma``."""
    from gsfric.synth import effect_contributions

    params = dict(UNIT[name])
    if name == "stroke_friction":
        from gsfric.simulate.api import evaluate

        params["reference"] = float(evaluate(platform, motion).D.min())
    c = effect_contributions(platform.with_effect(name, **params), motion, [name])[name]
    k = size * sigma / max(float(np.sqrt(np.mean(c ** 2))), 1e-12)
    keys = [SCALED[name]] if name in SCALED else [p for p in params if p != "reference"]
    for p in keys:
        params[p] *= k
    return params


def one_case(kind, names, family, platform_name, phi, size, seed, samples):
    """One record and its discovery; ``phi``: the AR(1) coefficient of the force noise, or
    one of ``NOISES``; ``names``: the hidden catalog effects, or the fault of a ``fault``
    case."""
    rng = np.random.default_rng(seed)
    platform = platforms()[platform_name]
    motion = FAMILIES[family](rng, samples)
    sigma = 0.2
    effects = {n: scaled(n, platform, motion, size, sigma) for n in names
               if kind != "fault"}
    data = synthesize(platform, effects, motion=motion, noise=0.0, pose_noise=1e-5, seed=seed)
    noise = (force_noise(phi, rng, samples, sigma) if isinstance(phi, str)
             else force_noise("ar" if phi else "white", rng, samples, sigma, phi))
    fr = data.frame
    rec = Motion.from_samples(fr.t.values, fr[["x", "y", "z"]].values,
                              quaternion=fr[["qw", "qx", "qy", "qz"]].values)
    forces = fr[[f"F{i}" for i in range(1, 7)]].values + noise
    if kind == "fault":
        forces = forces + fault(names[0], data.forces, fr.t.values, rng, size, sigma)
    candidates = CANDIDATE_NAMES
    if kind == "delay_outside":
        candidates = tuple(c for c in CANDIDATE_NAMES if c != "time_offset")
    if kind == "nonlinear_sensor":
        forces = forces + size * sigma * (data.forces * np.abs(data.forces)) / np.sqrt(
            np.mean(data.forces ** 4))
    r = discover(rec, forces, platform, poses=poses_from_columns(fr), n_bootstrap=20,
                 n_threads=1, candidates=candidates)
    true_noise = float(np.sqrt(np.mean(noise ** 2)))
    # the true model on the recorded (noisy, differentiated) motion, over the same pairs: no
    # model can do better than this, whatever the workflow
    from gsfric.synth import read_forces

    true = data.platform if kind not in ("nonlinear_sensor",) else platform
    F_true = read_forces(true, rec)[r.used]
    if kind in ("nonlinear_sensor", "fault"):
        F_true = F_true + (forces - noise - fr[[f"F{i}" for i in range(1, 7)]].values)[r.used]
    e = (forces[r.used] - F_true)[r.sliding]
    true_rms = float(np.sqrt(np.mean(e ** 2)))
    return r, true_noise, true_rms


def cases(per_cell, sizes):
    seed = 0
    out = []
    fam, plats = list(FAMILIES), ["reference", "heavy"]
    for k in range(max(50, per_cell * 6)):
        out.append(("null", [], fam[k % 3], plats[k % 2], NOISES[(k // 3) % 3], 0.0, seed))
        seed += 1
    for name in FAULTS:
        for j in range(per_cell):
            out.append(("fault", [name], ("rests", "sines", "chirps")[j % 3], plats[j % 2],
                        NOISES[(j + FAULTS.index(name)) % 3], (2.0, 5.0, 3.0)[j % 3], seed))
            seed += 1
    c = 0     # one counter over every single case: families, platforms and noises all cycle
    for name in CANDIDATE_NAMES:
        if name == "leg_weight" or (MODEL == "coupled" and name in COUPLED_ONLY):
            continue
        for size in sizes:
            for _ in range(per_cell):
                out.append(("single", [name], fam[c % 3], plats[(c // 3) % 2],
                            (0.0, 0.95)[(c // 6) % 2], size, seed))
                seed += 1
                c += 1
    pairs = [("seal_friction", "bushing_friction"), ("stribeck", "payload_offset"),
             ("seal_friction", "force_scale"), ("quadratic_drag", "sensor_bias")]
    if MODEL == "coupled":
        pairs[0] = ("seal_friction", "stroke_friction")
    for a, b in pairs:
        for j in range(per_cell):
            out.append(("pair", [a, b], fam[j % 3], plats[j % 2], (0.0, 0.9)[j % 2], 5.0,
                        seed))
            seed += 1
    for kind, names in (("delay_outside", ["time_offset"]), ("nonlinear_sensor", [])):
        for j in range(per_cell):
            out.append((kind, names, fam[j % 3], plats[j % 2], (0.0, 0.9)[j % 2], 5.0, seed))
            seed += 1
    return out


def ambiguities(r) -> list[tuple[str, ...]]:
    """The explanations a result reports as indistinguishable on its data: a named effect and
    the candidates it cannot be told from, a refitted parameter and the candidates that could
    replace its change."""
    out = [tuple([rnd.winner] + list(rnd.indistinguishable)) for rnd in r.rounds
           if rnd.winner and rnd.indistinguishable]
    for name, entry in r.refit.parameters.items():
        for alt in entry.alternatives or []:
            out.append((f"refit:{name}", alt))
    return out


def memory(n):
    """Peak traced memory (NumPy arrays included) and time of one discover on n samples."""
    import tracemalloc

    data = synthesize(reference_platform(friction_model=MODEL),
                      effects=["stribeck:static=2,velocity=0.01"], samples=n, rate=RATE,
                      noise=0.1, pose_noise=1e-5, seed=1)
    fr = data.frame
    rec = Motion.from_samples(fr.t.values, fr[["x", "y", "z"]].values,
                              quaternion=fr[["qw", "qx", "qy", "qz"]].values)
    forces, poses, model = fr[[f"F{i}" for i in range(1, 7)]].values, poses_from_columns(fr), \
        data.model
    del data, fr
    tracemalloc.start()
    start = time.time()
    r = discover(rec, forces, model, poses=poses, n_threads=1)
    seconds = time.time() - start
    peak = tracemalloc.get_traced_memory()[1]
    print(f"{n} samples: discover {seconds:.1f} s (with tracemalloc), traced peak "
          f"{peak / 2**20:.0f} MB = {peak / n:.0f} B/sample; named {r.names}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-cell", type=int, default=12, help="cases per effect and size")
    ap.add_argument("--samples", type=int, default=6000)
    ap.add_argument("--sizes", type=float, nargs="+", default=[2.0, 3.0, 10.0])
    ap.add_argument("--nulls", type=int, default=None, help="null cases (default >= 50)")
    ap.add_argument("--model", choices=("paper", "coupled"), default="paper",
                    help="friction model of the base platforms (default paper)")
    ap.add_argument("--kinds", nargs="+", default=None,
                    choices=("null", "single", "pair", "delay_outside", "nonlinear_sensor",
                             "fault"),
                    help="only these kinds of case")
    ap.add_argument("--families", nargs="+", default=None, choices=tuple(FAMILIES),
                    help="only cases of these motion families")
    ap.add_argument("--effects", nargs="+", default=None, choices=CANDIDATE_NAMES,
                    help="only single and pair cases with these effects")
    ap.add_argument("--seeds", nargs="+", type=int, default=None,
                    help="only the cases of these seeds (as printed by --verbose)")
    ap.add_argument("--verbose", action="store_true",
                    help="one line per case: names, verdict, rms_after over the noise")
    ap.add_argument("--memory", type=int, default=None, metavar="N",
                    help="only measure the traced memory peak and time of one discover on N "
                         "samples")
    a = ap.parse_args()
    global MODEL
    MODEL = a.model
    if a.memory:
        return memory(a.memory)
    todo = cases(a.per_cell, a.sizes)
    if a.nulls is not None:
        nulls = [c for c in todo if c[0] == "null"][:a.nulls]
        todo = nulls + [c for c in todo if c[0] != "null"]
    if a.kinds:
        todo = [c for c in todo if c[0] in a.kinds]
    if a.families:
        todo = [c for c in todo if c[2] in a.families]
    if a.effects:
        todo = [c for c in todo if c[0] not in ("single", "pair") or set(c[1]) & set(a.effects)]
    if a.seeds:
        todo = [c for c in todo if c[6] in a.seeds]
    rows = defaultdict(lambda: [0, 0, 0.0, 0.0, 0])
    start = time.time()
    confident = []     # out-of-catalog cases given a catalog name with the verdict "explained"
    records = []
    for kind, names, family, plat, phi, size, seed in todo:
        began = time.time()
        r, noise, true_rms = one_case(kind, names, family, plat, phi, size, seed, a.samples)
        records.append(Record(kind, names, size, r, noise, true_rms, time.time() - began))
        if kind == "null":
            key, ok = ("null: false discovery", family), bool(r.names)
        elif kind == "single":
            key, ok = (f"{names[0]} @ {size:g}", family), names[0] in r.names
        elif kind == "pair":
            key, ok = ("pair: both named", "+".join(names)), set(names) <= set(r.names)
        else:
            key, ok = (f"{kind}: unexplained", family), r.verdict == "unexplained_discrepancy"
        pairs = ambiguities(r)
        # a hidden effect not named but reported as indistinguishable from what was fitted
        # (a named effect or a refitted parameter of the model): missed, and said so
        missed_reported = kind in ("single", "pair") and not ok and any(
            n in p for p in pairs for n in names if n not in r.names)
        if a.verbose:
            print(f"{kind:17s} {'+'.join(names) or '-':40s} {family:7s} {plat:9s} noise={phi!s:5s} "
                  f"size={size:<4g} seed={seed:<4d} -> {ok!s:5s} {','.join(r.names) or '-':40s}"
                  f" {r.verdict:24s} {r.rms_after / noise:.3f} {true_rms / noise:.3f}"
                  f" ambiguous={';'.join('/'.join(p) for p in pairs) or '-'}", flush=True)
        rows[key][0] += int(ok)
        rows[key][1] += 1
        rows[key][4] += int(missed_reported)
        if (kind in ("delay_outside", "nonlinear_sensor", "fault") and r.names
                and r.verdict == "explained"):
            confident.append((kind, family, seed, r.names))
        if kind in ("single", "pair") and ok:
            rows[key][2] = max(rows[key][2], r.rms_after / noise)
            rows[key][3] = max(rows[key][3], r.rms_after / true_rms)
    print(f"{len(todo)} cases, {a.samples} samples each, base model {MODEL}, "
          f"{time.time() - start:.0f} s")
    print(f"{'case':40s} {'family':28s} {'rate':>7s} {'n':>4s} {'max rms_after/noise':>20s} "
          f"{'max rms_after/true model':>25s} {'missed, reported ambiguous':>27s}")
    for (name, family), (k, n, worst, worst_true, amb) in sorted(rows.items()):
        print(f"{name:40s} {family:28s} {k / n:7.0%} {n:4d} {worst:20.3f} {worst_true:25.3f}"
              f" {amb:27d}")
    print(f"out-of-catalog cases confidently misnamed (a catalog name, verdict explained): "
          f"{len(confident)} {confident}")
    goals(records)


@dataclass
class Record:
    """One case's outcome: its kind, hidden effects (or fault), size, result, true noise (N),
    true model's residual (N) and time of the discovery (s)."""

    kind: str
    names: list
    size: float
    result: object
    noise: float
    true_rms: float
    seconds: float


def _rate(hits: list[bool]) -> str:
    return f"{sum(hits)}/{len(hits)}" + (f" ({sum(hits) / len(hits):.0%})" if hits else "")


def goals(records: list[Record]) -> None:
    """The goal table of the honest verdict over the records."""
    outside = [x for x in records if x.kind in ("fault", "delay_outside", "nonlinear_sensor")]
    nulls = [x for x in records if x.kind == "null"]
    singles = [x for x in records if x.kind == "single"]
    pairs = [x for x in records if x.kind == "pair"]
    above = [x for x in records if x.result.verdict == "no_discrepancy"
             and x.result.noise.floor is not None
             and x.result.rms_after > 2 * np.hypot(x.noise, np.sqrt(np.mean(np.square(
                 x.result.noise.floor.pose))))]
    rows = [
        ("out-of-catalog reported unexplained_discrepancy",
         _rate([x.result.verdict == "unexplained_discrepancy" for x in outside]), ">= 9/10"),
        ("confidently misnamed (catalog name, explained, out of catalog)",
         str(sum(bool(x.result.names) and x.result.verdict == "explained" for x in outside)),
         "0"),
        ("nulls with anything named", _rate([bool(x.result.names) for x in nulls]), "0"),
        ("catalog singles named, effect-to-noise >= 3",
         _rate([x.names[0] in x.result.names for x in singles if x.size >= 3]), ">= 98 %"),
        ("catalog singles named, effect-to-noise = 2",
         _rate([x.names[0] in x.result.names for x in singles if x.size == 2]), ">= 95 %"),
        ("pairs named exactly",
         _rate([set(x.result.names) == set(x.names) for x in pairs]), ">= 90 %"),
        ("no_discrepancy, residual > 2x true floor (all with a stated reason)",
         f"{len(above)} ({sum(bool(x.result.verdict_reason) for x in above)} with a reason)",
         "0 without a reason"),
        ("time per discovery (mean, max), s",
         f"{np.mean([x.seconds for x in records]):.1f}, {max(x.seconds for x in records):.1f}"
         if records else "-", "<= 10 s at 6,000 samples"),
    ]
    print()
    print(f"{'measure':70s} {'measured':>22s} {'goal':>22s}")
    for name, value, goal in rows:
        print(f"{name:70s} {value:>22s} {goal:>22s}")
    for kind in FAULTS:
        hits = [x.result.verdict == "unexplained_discrepancy" for x in outside
                if x.kind == "fault" and x.names[0] == kind]
        if hits:
            print(f"  fault {kind:20s} unexplained {_rate(hits)}")


if __name__ == "__main__":
    main()
