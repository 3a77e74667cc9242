"""Discovery on rig-like logs from a generator of its own, read through the command line.

Independent of benchmarks/discovery_rates.py (docs/explanation/discovery.md, "Rates on logs of a second
generator"). Every case draws:

* a platform: base radius 0.35-0.8 m, platform radius 0.45-0.8 of it, joint pairs 10-40 deg
  apart, home height 1.0-1.6 base radii, platform 5-40 kg with 0-15 kg of payload, legs 0.3-2
  times the reference leg's masses, friction coefficients 0.5-2 (prismatic viscous 0.5-5)
  times the reference's;
* a motion family (cycled): ``triangle`` (smoothed triangle waves: constant speed, sharp
  reversals), ``creep`` (0.02-0.08 Hz sines: leg speeds of a few mm/s), ``p2p_long`` and
  ``p2p_short`` (minimum-jerk moves with 1.5-4 s or 0.05-0.3 s rests), ``multisine`` (four
  tones of 0.1-4 Hz per axis, amplitudes falling as 1/f), ``chirp`` (logarithmic sweep
  0.05 -> 2-4 Hz, amplitude falling with the frequency);
* a force noise (cycled): ``pink`` (1/f), ``band`` (white filtered to a 2-20 Hz wide band),
  ``ar2`` (a resonance of 2-30 Hz, pole radius 0.9-0.98), ``outliers`` (white plus spikes of
  8-15 sigma on 0.5 % of the samples); sigma 0.1-0.5 N;
* a sampling rate of 500-2000 Hz (6-12 s, at most 10,000 samples), half the cases with time
  stamps jittered by up to +-10 % of the step, pose noise 0, 3e-6, 1e-5 or 3e-5 (m and rad);
* the log as a controller writes it: time in ms or an integer microsecond counter, positions
  in mm (4 decimals), roll/pitch/yaw in degrees (6 decimals), forces in N or kN, a status
  column, its own column names; read by ``gsfric discover --column-map FMT.toml --platform
  MODEL.toml`` (in-process, the command's own code path).

Cases: nulls, each catalog single at effect-to-noise 3 and 10 (``leg_weight`` left out: the
platforms carry their legs' weight), and out-of-catalog effects at effect-to-noise 5:
``hysteresis`` (Dahl friction on each leg: the force builds up over 2-5 mm of travel after a
reversal), ``friction_drift`` (a Coulomb friction growing from 0.2 to 1.8 times its mean over
the record, a warming seal), ``pose_scale`` (the log's x and y read (1 + e) times the true
ones). Effect-to-noise is the RMS of the effect's force over sigma.

One line per case with --verbose; then the table of rates by case, by motion family, by
noise, and the list of failures.

    python benchmarks/discovery_fresh.py --model paper --per-cell 2 --seed 0 --verbose
    python benchmarks/discovery_fresh.py --model coupled --per-cell 2 --seed 0 --verbose
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
import warnings
from collections import defaultdict

import numpy as np
import pandas as pd
from scipy.signal import butter, lfilter, sosfilt
from scipy.spatial.transform import Rotation

from gsfric import models
from gsfric.discovery import CANDIDATE_NAMES
from gsfric.simulate.api import evaluate
from gsfric.platform.description import Body, Friction, Geometry, Legs, Platform
from gsfric.synth import read_forces
from gsfric.trajectory import Motion

FAMILIES = ("triangle", "creep", "p2p_long", "p2p_short", "multisine", "chirp")
NOISES = ("pink", "band", "ar2", "outliers")
POSE_NOISES = (0.0, 3e-6, 1e-5, 3e-5)
OUTSIDE = ("hysteresis", "friction_drift", "pose_scale")
COUPLED_PART = ("joint_friction_coupling", "bushing_friction")


# ---------------------------------------------------------------- platforms


def _pairs(radius, centre_deg, half_deg):
    a = np.radians([centre_deg + 120 * k + s * half_deg for k in range(3) for s in (-1, 1)])
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.zeros(6)])


def random_platform(rng, friction_model):
    """A plausible hexapod other than the reference one, and its home height (m)."""
    rb = rng.uniform(0.35, 0.8)
    rp = rb * rng.uniform(0.45, 0.8)
    base = _pairs(rb, 0.0, rng.uniform(5, 20))
    top = np.roll(_pairs(rp, 60.0, rng.uniform(5, 20)), 1, axis=0)
    home = rb * rng.uniform(1.0, 1.6)
    mass = rng.uniform(5, 40)
    inertia = np.diag(mass * rp ** 2 * rng.uniform(0.25, 0.6, 3))
    payload = rng.uniform(0, 15)
    ref = models.REFERENCE_LEG
    k = rng.uniform(0.3, 2.0)
    legs = Legs(model="rigid", weight=True,
                lower_mass=k * ref["lower_mass"], lower_com=home * rng.uniform(0.2, 0.35),
                lower_inertia=np.diag(k * np.array(ref["lower_inertia"])),
                upper_mass=k * ref["upper_mass"], upper_com=home * rng.uniform(0.2, 0.35),
                upper_inertia=np.diag(k * np.array(ref["upper_inertia"])))
    f = rng.uniform(0.5, 2.0, 4)
    friction = Friction(model=friction_model, joint_viscous=0.02 * f[0], joint_coulomb=0.04 * f[1],
                        joint_radius=0.05 * f[2], prismatic_viscous=0.02 * rng.uniform(0.5, 5),
                        prismatic_coulomb=0.1 * f[3],
                        bushing_offset=home * rng.uniform(0.25, 0.4),
                        bushing_spacing=rng.uniform(0.06, 0.15),
                        prismatic_seal=rng.uniform(0.5, 4.0) if friction_model == "coupled"
                        else 0.0)
    platform = Platform(gravity=9.81, geometry=Geometry(base_joints=base, platform_joints=top),
                        platform=Body(mass=mass, inertia=inertia, payload_mass=payload,
                                      payload_inertia=np.diag([0.02, 0.02, 0.03]) * payload),
                        legs=legs, friction=friction, effects={})
    return platform, home, rb


# ---------------------------------------------------------------- motions
# shapes u(t) of about unit amplitude per axis (N, 6), analytic in t (jittered stamps allowed)


def _triangle(rng, t):
    f = rng.uniform(0.15, 0.6, 6)
    ph = rng.uniform(0, 2 * np.pi, 6)
    # arcsin of a slightly shrunk sine: a triangle wave with corners rounded over ~2 % of a period
    return 2 / np.pi * np.arcsin(0.995 * np.sin(2 * np.pi * f * t[:, None] + ph))


def _creep(rng, t):
    f = rng.uniform(0.02, 0.08, 6)
    return np.sin(2 * np.pi * f * t[:, None] + rng.uniform(0, 2 * np.pi, 6))


def _min_jerk(rng, t, move, rest):
    out = np.zeros((len(t), 6))
    now, here = t[0], np.zeros(6)
    while now <= t[-1]:
        now += rng.uniform(*rest)                      # at rest at ``here`` until ``now``
        out[t >= now] = here
        there, length = rng.uniform(-1, 1, 6), rng.uniform(*move)
        sel = (t >= now) & (t < now + length)
        s = (t[sel] - now) / length
        w = 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5
        out[sel] = here + w[:, None] * (there - here)
        out[t >= now + length] = there
        now, here = now + length, there
    return out


def _p2p_long(rng, t):
    return _min_jerk(rng, t, (0.4, 1.0), (1.5, 4.0))


def _p2p_short(rng, t):
    return _min_jerk(rng, t, (0.3, 0.8), (0.05, 0.3))


def _multisine(rng, t):
    f = rng.uniform(0.1, 4.0, (4, 6))
    a = 1.0 / (1.0 + f)
    u = sum(a[k] * np.sin(2 * np.pi * f[k] * t[:, None] + rng.uniform(0, 2 * np.pi, 6))
            for k in range(4))
    return u / a.sum(axis=0)


def _chirp(rng, t):
    f0, f1 = 0.05, rng.uniform(2.0, 4.0, 6)
    T = t[-1] - t[0] + 1e-9
    k = np.log(f1 / f0) / T
    phase = 2 * np.pi * f0 * (np.exp(k * (t[:, None] - t[0])) - 1) / k
    freq = f0 * np.exp(k * (t[:, None] - t[0]))
    return np.sin(phase + rng.uniform(0, 2 * np.pi, 6)) / (1.0 + freq)


SHAPES = {"triangle": _triangle, "creep": _creep, "p2p_long": _p2p_long,
          "p2p_short": _p2p_short, "multisine": _multisine, "chirp": _chirp}


def poses(shape, home, rb):
    """Positions (N, 3), m, and roll/pitch/yaw (N, 3), rad, of a shape about the home pose."""
    amp = np.array([0.06 * rb, 0.06 * rb, 0.04 * rb, 0.05, 0.05, 0.07])
    p = shape * amp
    return p[:, :3] + [0.0, 0.0, home], p[:, 3:]


def motion_of(t, position, rpy):
    q = Rotation.from_euler("xyz", rpy).as_quat()[:, [3, 0, 1, 2]]
    return Motion.from_samples(t, position, quaternion=q)


# ---------------------------------------------------------------- noises


def force_noise(rng, kind, n, rate, sigma):
    """Noise (N, 6) of standard deviation ``sigma`` (outliers: of its Gaussian part)."""
    w = rng.standard_normal((n + 2000, 6))
    if kind == "pink":
        spec = np.fft.rfft(w, axis=0)
        f = np.fft.rfftfreq(len(w), 1 / rate)
        spec[1:] /= np.sqrt(f[1:, None])
        spec[0] = 0.0
        e = np.fft.irfft(spec, len(w), axis=0)
    elif kind == "band":
        lo = rng.uniform(2.0, 20.0)
        hi = min(lo * rng.uniform(3.0, 10.0), 0.4 * rate)
        e = sosfilt(butter(4, [lo, hi], btype="band", fs=rate, output="sos"), w, axis=0)
    elif kind == "ar2":
        r, f0 = rng.uniform(0.9, 0.98), rng.uniform(2.0, 30.0)
        e = lfilter([1.0], [1.0, -2 * r * np.cos(2 * np.pi * f0 / rate), r * r], w, axis=0)
    else:
        e = w.copy()
    e = e[2000:]
    e = sigma * e / e.std(axis=0)
    if kind == "outliers":
        hit = rng.random(e.shape) < 0.005
        e[hit] += sigma * rng.uniform(8, 15, hit.sum()) * rng.choice([-1, 1], hit.sum())
    return e


# ---------------------------------------------------------------- effects


def _unit_params(rng, name, platform, D):
    """Parameters of ``name`` of arbitrary size, and the keys that scale it."""
    if name == "stribeck":
        return {"static": 1.0, "velocity": rng.uniform(0.005, 0.03)}, ["static"]
    if name == "seal_friction":
        return {"force": 1.0}, ["force"]
    if name == "quadratic_drag":
        return {"coefficient": 10.0}, ["coefficient"]
    if name == "stroke_friction":
        return {"slope": 10.0, "reference": float(D.mean())}, ["slope"]
    if name == "payload_offset":
        v = rng.normal(size=3)
        return dict(zip("xyz", 0.01 * v / np.linalg.norm(v))), list("xyz")
    if name == "sensor_bias":
        return {f"b{i}": float(v) for i, v in enumerate(rng.normal(size=6), 1)}, \
            [f"b{i}" for i in range(1, 7)]
    if name == "force_scale":
        return {f"g{i}": float(v) for i, v in enumerate(rng.normal(0, 0.01, 6), 1)}, \
            [f"g{i}" for i in range(1, 7)]
    if name == "time_offset":
        return {"delay": 0.005}, ["delay"]
    if name == "joint_friction_coupling":
        return {"scale": 0.5}, ["scale"]
    if name == "bushing_friction":
        return {"coefficient": 0.05, "spacing": platform.friction.bushing_spacing}, \
            ["coefficient"]
    raise ValueError(name)


def catalog_forces(rng, name, platform, motion, target):
    """The load cells' readings (N, 6) with ``name`` hidden at an effect RMS of ``target`` N,
    the true platform, and the effect's RMS reached."""
    base = read_forces(platform, motion)
    params, keys = _unit_params(rng, name, platform, evaluate(platform, motion).D)
    for _ in range(3):     # the effects are close to linear in their scaled parameters
        true = platform.with_effect(name, **params)
        F = read_forces(true, motion)
        size = float(np.sqrt(np.mean((F - base) ** 2)))
        k = target / max(size, 1e-12)
        if abs(k - 1) < 0.02:
            break
        for p in keys:
            params[p] *= k
    return F, true, size


def leg_speed_and_travel(platform, motion):
    ev = evaluate(platform, motion)
    return ev.D, np.gradient(ev.D, motion.t, axis=0)


def outside_forces(rng, kind, platform, motion, target, t):
    """Readings (N, 6) with the out-of-catalog force ``kind`` (``hysteresis``,
    ``friction_drift``) of RMS ``target`` N, and that RMS (``pose_scale`` is made by
    ``pose_scale_factor``)."""
    base = read_forces(platform, motion)
    D, v = leg_speed_and_travel(platform, motion)
    if kind == "hysteresis":
        x0 = rng.uniform(0.002, 0.005)
        dx = np.diff(D, axis=0)
        z = np.zeros_like(D)
        for k in range(1, len(D)):
            s = np.sign(dx[k - 1])
            z[k] = s + (z[k - 1] - s) * np.exp(-np.abs(dx[k - 1]) / x0)
        shape = z
    else:   # friction_drift
        T = t[-1] - t[0]
        shape = np.tanh(v / 0.002) * (0.2 + 1.6 * (t - t[0])[:, None] / T)
    c = shape * target / float(np.sqrt(np.mean(shape ** 2)))
    return base + c, target


def pose_scale_factor(platform, motion, position, rpy, t, target):
    """The scale e of x, y giving a model-force change of RMS ``target`` N (bisection)."""
    F0 = read_forces(platform, motion)

    def size(e):
        m = motion_of(t, position * [1 + e, 1 + e, 1], rpy)
        return float(np.sqrt(np.mean((read_forces(platform, m) - F0) ** 2)))

    lo, hi = 0.0, 0.3
    if size(hi) < target:
        return hi, size(hi)
    for _ in range(14):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if size(mid) < target else (lo, mid)
    return hi, size(hi)


# ---------------------------------------------------------------- logs


def write_log(path, style, t, position, rpy, forces):
    """A controller's log: its own names and units; returns the column-map TOML text."""
    if style == 0:
        names = {"t": "Time [ms]", "x": "PosX [mm]", "y": "PosY [mm]", "z": "PosZ [mm]",
                 "roll": "Roll [deg]", "pitch": "Pitch [deg]", "yaw": "Yaw [deg]",
                 **{f"F{i}": f"Load{i} [kN]" for i in range(1, 7)}}
        units = {"t": "ms", "F": "kN"}
        tcol = np.round(1e3 * t, 6)
    else:
        names = {"t": "counter_us", "x": "plat.x", "y": "plat.y", "z": "plat.z",
                 "roll": "plat.rx", "pitch": "plat.ry", "yaw": "plat.rz",
                 **{f"F{i}": f"act{i}.force" for i in range(1, 7)}}
        units = {"t": "us", "F": "N"}
        tcol = (np.round(1e6 * t).astype(np.int64) + 1_000_000)
    fscale = 1e-3 if units["F"] == "kN" else 1.0
    cols = {names["t"]: tcol}
    for k, a in enumerate("xyz"):
        cols[names[a]] = np.round(1e3 * position[:, k], 4)
    for k, a in enumerate(("roll", "pitch", "yaw")):
        cols[names[a]] = np.round(np.degrees(rpy[:, k]), 6)
    for i in range(6):
        cols[names[f"F{i + 1}"]] = forces[:, i] * fscale
    cols["status"] = np.full(len(t), 7)
    pd.DataFrame(cols).to_csv(path, index=False)
    lines = ['angles = "xyz"', "[columns]"]
    lines += [f'{k} = "{v}"' for k, v in names.items()]
    lines += ["[units]", f't = "{units["t"]}"'] + [f'{a} = "mm"' for a in "xyz"]
    lines += [f'{a} = "deg"' for a in ("roll", "pitch", "yaw")]
    lines += [f'F{i} = "{units["F"]}"' for i in range(1, 7)]
    return "\n".join(lines) + "\n"


def run_cli(directory, log, fmt, platform):
    """``gsfric discover`` on the log, in-process; the summary.json it wrote."""
    from gsfric.cli import main

    out = os.path.join(directory, "out")
    args = ["discover", "--measured", log, "--column-map", fmt, "--platform", platform,
            "--out", out, "--quiet"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            main.main(args, prog_name="gsfric")
        except SystemExit as exit_:
            if exit_.code:
                raise
    with open(os.path.join(out, "summary.json")) as fh:
        return json.load(fh)


def true_model_rms(log, fmt, true_platform, platform, extra=None):
    """RMS (N) of what the true model leaves on the log: the true platform (the hidden effect
    in it) evaluated on the motion as ``gsfric discover`` reads and differentiates it from the
    log, against the logged forces, over the (sample, leg) pairs the workflow uses (the
    sliding pairs of the used samples). No model can do better than this on the log, whatever
    the workflow; what it leaves beyond the force noise is the motion estimate's error.
    ``extra`` (N, 6): an out-of-catalog force added to the true model's (None: none)."""
    from gsfric import io as gio
    from gsfric.discovery.residuals import Problem
    from gsfric.discovery.rest import poses_from_columns
    from gsfric.discovery.settings import Settings

    log_format = gio.LogFormat.from_options(fmt, None, None, None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        motion, forces, _, columns = gio._read_measured(log, None, gio.DEFAULT_POLYORDER,
                                                        log_format)
    problem = Problem(motion, forces, platform, Settings(n_threads=1),
                      poses=poses_from_columns(columns))
    F_true = read_forces(true_platform, motion)
    if extra is not None:
        F_true = F_true + extra
    e = (forces - F_true)[problem.used][problem.sliding]
    return float(np.sqrt(np.mean(e ** 2)))


# ---------------------------------------------------------------- cases


def one_case(case, model, keep=None, noises=NOISES):
    kind, name, size, c, seed = case
    rng = np.random.default_rng(seed)
    platform, home, rb = random_platform(rng, model)
    family, noise_kind = FAMILIES[c % len(FAMILIES)], noises[(c // 2) % len(noises)]
    rate = float(rng.choice([500.0, 1000.0, 2000.0]) * rng.uniform(0.9, 1.1))
    n = int(min(rng.uniform(6, 12) * rate, 10_000))
    t = np.arange(n) / rate
    jitter = bool(c % 2)
    if jitter:
        t = t + rng.uniform(-0.1, 0.1, n) / rate
    position, rpy = poses(SHAPES[family](rng, t), home, rb)
    motion = motion_of(t, position, rpy)
    sigma = rng.uniform(0.1, 0.5)
    pose_noise = POSE_NOISES[(c // 3) % len(POSE_NOISES)]
    scale = 1.0
    true_platform, F_true_extra = platform, None
    if kind == "null":
        F, reached = read_forces(platform, motion), 0.0
    elif kind == "single":
        F, true_platform, reached = catalog_forces(rng, name, platform, motion, size * sigma)
    elif name == "pose_scale":
        F = read_forces(platform, motion)
        e, reached = pose_scale_factor(platform, motion, position, rpy, t, size * sigma)
        scale = 1.0 + e
    else:
        F, reached = outside_forces(rng, name, platform, motion, size * sigma, t)
        # the added force as drawn (a function of the true motion and time)
        F_true_extra = F - read_forces(platform, motion)
    e = force_noise(rng, noise_kind, n, rate, sigma)
    rec_pos = position * [scale, scale, 1.0] + rng.normal(0, pose_noise, position.shape)
    rec_rpy = rpy + rng.normal(0, pose_noise, rpy.shape)
    with tempfile.TemporaryDirectory() as d:
        if keep:
            d = os.path.join(keep, f"case{c}")
            os.makedirs(d, exist_ok=True)
        log, fmt, plat = (os.path.join(d, f) for f in ("log.csv", "fmt.toml", "model.toml"))
        with open(fmt, "w") as fh:
            fh.write(write_log(log, (c // 4) % 2, t, rec_pos, rec_rpy, F + e))
        platform.to_toml(plat)
        s = run_cli(d, log, fmt, plat)
        true_rms = true_model_rms(log, fmt, true_platform, platform, F_true_extra)
    names = [x["name"] for x in s["effects"]]
    true_noise = float(np.sqrt(np.mean(e ** 2)))
    info = dict(kind=kind, name=name or "-", size=size, family=family, noise=noise_kind,
                rate=rate, n=n, jitter=jitter, pose_noise=pose_noise, sigma=sigma,
                reached=reached / sigma, seed=seed, names=names, verdict=s["verdict"],
                rms_ratio=s["rms_after"] / true_noise, true_ratio=true_rms / true_noise,
                ambiguous=[a["effects"] for a in s["ambiguous"]],
                looks_like=(s.get("unexplained") or {}).get("looks_like", ""),
                notes=s.get("notes", []))
    if kind == "null":
        info["ok"] = not names and s["verdict"] == "no_discrepancy"
        info["named"] = bool(names)
    elif kind == "single":
        info["ok"] = name in names
        info["named"] = name in names
    else:
        info["ok"] = s["verdict"] == "unexplained_discrepancy"
        info["named"] = bool(names)
    info["confident_misname"] = (s["verdict"] == "explained" and bool(names)
                                 and (kind != "single" or name not in names))
    return info


def cases(per_cell, seed, model):
    rng = np.random.default_rng(seed)
    out, c = [], 0

    def add(kind, name, size):
        nonlocal c
        out.append((kind, name, size, c, int(rng.integers(2 ** 31))))
        c += 1

    for _ in range(5 * per_cell):
        add("null", None, 0.0)
    for name in CANDIDATE_NAMES:
        if name == "leg_weight" or (model == "coupled" and name in COUPLED_PART):
            continue
        for size in (3.0, 10.0):
            for _ in range(per_cell):
                add("single", name, size)
    for name in OUTSIDE:
        for _ in range(2 * per_cell):
            add("outside", name, 5.0)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", choices=("paper", "coupled"), default="paper",
                    help="friction model of the drawn platforms")
    ap.add_argument("--per-cell", type=int, default=2,
                    help="cases per effect and size (nulls: 5x, out-of-catalog: 2x)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the drawn cases")
    ap.add_argument("--only", nargs="+", default=None,
                    help="only cases of these effects ('null' for the nulls)")
    ap.add_argument("--cases", nargs="+", type=int, default=None,
                    help="only these case numbers (as printed by --verbose)")
    ap.add_argument("--noises", nargs="+", choices=NOISES, default=NOISES,
                    help="the force noises to cycle through (default: all)")
    ap.add_argument("--verbose", action="store_true", help="one line per case")
    ap.add_argument("--keep", default=None, metavar="DIR",
                    help="keep each case's log, column map, platform and discover output in "
                         "DIR/caseN")
    a = ap.parse_args()
    todo = cases(a.per_cell, a.seed, a.model)
    if a.only:
        todo = [x for x in todo if (x[1] or "null") in a.only]
    if a.cases:
        todo = [x for x in todo if x[3] in a.cases]
    start = time.time()
    results = []
    for case in todo:
        r = one_case(case, a.model, a.keep, tuple(a.noises))
        results.append(r)
        if a.verbose:
            print(f"#{case[3]:<3d} {r['kind']:7s} {r['name']:24s} {r['size']:<4g} "
                  f"{r['family']:9s} {r['noise']:8s} {r['rate']:6.0f}Hz "
                  f"{'jit' if r['jitter'] else '   '} pose={r['pose_noise']:<6g} "
                  f"-> {'OK  ' if r['ok'] else 'FAIL'} {','.join(r['names']) or '-':32s} "
                  f"{r['verdict']:24s} rms/noise={r['rms_ratio']:.3f} "
                  f"true/noise={r['true_ratio']:.3f}"
                  f" {r['looks_like'][:60] if r['kind'] != 'single' else ''}", flush=True)
    print(f"{len(results)} cases, base model {a.model}, seed {a.seed}, "
          f"{time.time() - start:.0f} s")
    groups = defaultdict(list)
    for r in results:
        label = ("null: nothing named, no_discrepancy" if r["kind"] == "null" else
                 f"{r['name']} @ {r['size']:g}: named" if r["kind"] == "single" else
                 f"{r['name']}: unexplained_discrepancy")
        groups[("case", label)].append(r)
        groups[("family", r["family"])].append(r)
        groups[("noise", r["noise"])].append(r)
    print(f"{'':7s} {'':42s} {'rate':>6s} {'n':>3s} {'max rms_after/noise':>20s} "
          f"{'confident misnames':>18s}")
    for (what, label), rs in sorted(groups.items()):
        ok = sum(r["ok"] for r in rs)
        named = [r["rms_ratio"] for r in rs if r["kind"] == "single" and r["ok"]]
        worst = f"{max(named):.3f}" if named else "-"
        print(f"{what:7s} {label:42s} {ok / len(rs):6.0%} {len(rs):3d} {worst:>20s} "
              f"{sum(r['confident_misname'] for r in rs):18d}")
    fails = [r for r in results if not r["ok"]]
    print(f"failures: {len(fails)}")
    for r in fails:
        print(f"  {r['kind']} {r['name']} @ {r['size']:g} {r['family']} {r['noise']} "
              f"seed={r['seed']}: named {r['names'] or '-'}, {r['verdict']}, ambiguous "
              f"{r['ambiguous'] or '-'}; {r['looks_like']}")


if __name__ == "__main__":
    main()
