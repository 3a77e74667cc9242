"""What stopping the coupled friction solve early, per step, would gain: a feasibility measure.

The coupled actuator map solves its fixed point in ``N_ITERATIONS`` unrolled iterations
(derive/coupled.py). An early exit would run a short solve of k iterations, accept a step when
that solve's own last change is below an acceptance tolerance ``tol_a (1 N + |F0|)``, and run
the full solve only for the others. With SIMD over steps (8 lanes on AVX-512) a group of 8
steps needs the full solve as soon as one of its steps does.

For the reference platform on the benchmark's states (``benchmarks.cases.states``: a smooth random
motion at 1 kHz) and, with ``--random``, on the random platforms of
``benchmarks/coupled_convergence.py``, at each mu r, this script derives the coupled actuator
map with k = 1 .. N_ITERATIONS iterations (CasADi, no C compiler needed) and reports, for each k
and ``tol_a``:

* the share of steps the short solve accepts and of 8-step groups that need the full solve;
* the largest difference between an accepted step's F and the full solve's, relative to
  ``1 N + |F0|``;
* the CasADi instructions per step an early exit would cost: ``I_k + g I_N`` (the short solve,
  then the whole full solve again for a group that needs it, ``g`` the share of such groups),
  against ``I_N``, and the lower bound ``I_k + g (I_N - I_k)`` of a full solve that continued
  the short one.

    .venv/bin/python benchmarks/coupled_early_exit.py
    .venv/bin/python benchmarks/coupled_early_exit.py --mu-r 0.002 0.006 --steps 20000 --random
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from helpers_validation import random_platform  # noqa: E402

from benchmarks import cases as bench  # noqa: E402
from derive import build as dbuild  # noqa: E402
from derive import coupled as dcoupled  # noqa: E402
from derive import effects as fx  # noqa: E402
from derive import model as mdl  # noqa: E402
from gsfric import models  # noqa: E402
from gsfric._optional import optional  # noqa: E402
from gsfric.evaluation.evaluator import Evaluator, state_array  # noqa: E402

TOLERANCES = (1e-8, 1e-9, 1e-10, 1e-11)
LANES = 8


def short_solves(n_max: int) -> dict:
    """k -> CasADi function (x, P, Q) -> (F, F0, coupling_change) of the coupled model with k
    iterations (``model.build(..., n_iter=k)``)."""
    ca = optional("casadi")
    x = ca.SX.sym("x", mdl.input_size(mdl.STATE))
    P = ca.SX.sym("P", mdl.input_size(mdl.PARAMETERS))
    Q = ca.SX.sym("Q", len(fx.parameter_names()))
    out = {}
    for k in range(1, n_max + 1):
        model = mdl.build("kinematic", friction_model=1, n_iter=k)
        env = {}
        dbuild._split(x, mdl.STATE, env)
        dbuild._split(P, mdl.PARAMETERS, env)
        env["effects"] = Q
        o = model.chain.to_casadi(env, {n: model.outputs[n]
                                        for n in ("F", "F0", "coupling_change")})
        out[k] = ca.Function(f"coupled_{k}", [x, P, Q],
                             [o["F"], o["F0"], o["coupling_change"]])
    return out


def evaluate(functions: dict, platform, x: np.ndarray) -> dict:
    """k -> (F, F0, coupling_change), each (N, 6) N."""
    ev = Evaluator(platform)
    res = {}
    for k, f in functions.items():
        vals = f.map(x.shape[0], "serial")(x.T, ev.P, ev.Q)
        res[k] = tuple(np.array(v).T for v in vals)
    return res


def report(name: str, res: dict, functions: dict) -> None:
    n_full = max(res)
    F_full, F0, cc_full = res[n_full]
    scale = 1.0 + np.abs(F0)
    steps = F0.shape[0]
    groups = steps // LANES
    i_full = functions[n_full].n_instructions()
    print(f"{name}: {steps} steps; full solve ({n_full} iterations, {i_full} instructions): "
          f"largest |change| / (1 + |F0|) {np.max(np.abs(cc_full) / scale):.1e}")
    print("  k  instr  tol_a   steps accepted  groups to rerun  max |F - F_full| rel  "
          "instr rerun  (continued)  relative to full")
    for k in range(1, n_full):
        F, _, cc = res[k]
        rel = np.max(np.abs(cc) / scale, axis=1)
        i_k = functions[k].n_instructions()
        for tol in TOLERANCES:
            ok = rel <= tol
            rerun = ~ok[:groups * LANES].reshape(groups, LANES).all(axis=1)
            g = rerun.mean()
            err = np.max(np.abs(F - F_full)[ok] / scale[ok]) if ok.any() else float("nan")
            cost = i_k + g * i_full
            cont = i_k + g * (i_full - i_k)
            print(f"  {k}  {i_k:5d}  {tol:.0e}  {ok.mean():14.1%}  {g:15.1%}  {err:20.1e}  "
                  f"{cost:11.0f}  {cont:11.0f}  {cost / i_full:16.2f}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mu-r", type=float, nargs="+", default=[0.002, 0.006], help="m")
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--random", action="store_true",
                        help="also 11 random platforms on 60-step random motions")
    args = parser.parse_args(argv)
    functions = short_solves(dcoupled.N_ITERATIONS)
    x = bench.states(args.steps)
    reference = models.reference_platform("coupled")
    r = reference.friction.joint_radius
    print(f"reference platform: mu r = {reference.friction.joint_coulomb * r:g} m")
    for mu_r in args.mu_r:
        platform = reference.with_friction(joint_coulomb=mu_r / r)
        report(f"reference platform, mu r = {mu_r:g}, bench.states", evaluate(
            functions, platform, x), functions)
        if args.random:
            parts = []
            for seed in range(1, 12):
                rng = np.random.default_rng(seed)
                p = random_platform(rng).with_friction(model="coupled", joint_radius=0.05,
                                                       joint_coulomb=mu_r / 0.05)
                motion = models.random_motion(np.random.default_rng(1000 + seed),
                                              np.linspace(0.0, 3.0, 64))
                parts.append(evaluate(functions, p, state_array(motion)))
            merged = {k: tuple(np.concatenate([p[k][j] for p in parts]) for j in range(3))
                      for k in functions}
            report(f"11 random platforms, mu r = {mu_r:g}, 64-step random motions", merged,
                   functions)


if __name__ == "__main__":
    main()
