"""How strongly one iteration of the coupled friction solve contracts, and where the coupling is.

The fixed point of derive/coupled.py is ``s = G(s)`` on the 18 friction loads (per leg
``|R_E|``, ``|a_1 x R_C|``, ``|a_2 x R_C|``): from loads, the friction moments, the reactions
they cause (one back-substitution of the platform's 6x6 system), and the loads of those. This
script derives ``G`` alone (the coupled model with the loads of its first iterate as an input,
one plain iteration), takes its Jacobian ``J = dG/ds`` (CasADi), and at the fixed point of steps
of ``benchmarks.cases.states`` on the reference platform reports, per mu r:

* the spectral radius of J: the factor by which a plain iteration shrinks the error;
* that of ``(I - D)^-1 (J - D)``, ``D`` the 3x3 blocks of each leg's loads on its own: the
  factor left if every iteration solved each leg's own coupling exactly;
* the singular values of J at the last step.

    .venv/bin/python benchmarks/coupled_jacobian.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import sympy as sp  # noqa: E402

from benchmarks import cases as bench  # noqa: E402
from derive import build as dbuild  # noqa: E402
from derive import coupled as dcoupled  # noqa: E402
from derive import effects as fx  # noqa: E402
from derive import model as mdl  # noqa: E402
from gsfric import models  # noqa: E402
from gsfric._optional import optional  # noqa: E402
from gsfric.evaluation.evaluator import Evaluator  # noqa: E402

LEGS = 6
LOADS = 3


def loads_map():
    """CasADi function (x, P, Q, s) -> (G(s), dG/ds), s the 18 loads of the first iterate."""
    ca = optional("casadi")
    images = {}
    plain = dcoupled.solve

    def solve(ch, legs, A_qr, weight, friction, m, n_iter=dcoupled.N_ITERATIONS,
              accelerate=dcoupled.ACCELERATE):
        S = ch.input("s0", LEGS * LOADS, 1)

        class Given:
            moments = friction.moments
            weights = friction.weights

            @staticmethod
            def loads(leg, R_E, R_C, it):
                if it == 0:
                    return [S[LOADS * (leg.k - 1) + j] for j in range(LOADS)]
                images[leg.k] = friction.loads(leg, R_E, R_C, it)
                return images[leg.k]

        return plain(ch, legs, A_qr, weight, Given, m, 2, False)

    dcoupled.solve = solve
    try:
        model = mdl.build("kinematic", friction_model=1)
    finally:
        dcoupled.solve = plain
    x = ca.SX.sym("x", mdl.input_size(mdl.STATE))
    P = ca.SX.sym("P", mdl.input_size(mdl.PARAMETERS))
    Q = ca.SX.sym("Q", len(fx.parameter_names()))
    s = ca.SX.sym("s", LEGS * LOADS)
    env = {"effects": Q, "s0": s}
    dbuild._split(x, mdl.STATE, env)
    dbuild._split(P, mdl.PARAMETERS, env)
    image = sp.Matrix([v for k in range(1, LEGS + 1) for v in images[k]])
    G = model.chain.to_casadi(env, {"G": image})["G"]
    return ca.Function("G", [x, P, Q, s], [G, ca.jacobian(G, s)])


def main() -> None:
    G = loads_map()
    x = bench.states(200)
    reference = models.reference_platform("coupled")
    r = reference.friction.joint_radius
    for mu_r in (0.002, 0.006):
        ev = Evaluator(reference.with_friction(joint_coulomb=mu_r / r))
        plain, local = [], []
        for i in range(0, x.shape[0], 10):
            s = np.zeros(LEGS * LOADS)
            for _ in range(10):
                s = np.array(G(x[i], ev.P, ev.Q, s)[0]).ravel()
            J = np.array(G(x[i], ev.P, ev.Q, s)[1])
            D = np.zeros_like(J)
            for k in range(LEGS):
                b = slice(LOADS * k, LOADS * (k + 1))
                D[b, b] = J[b, b]
            plain.append(np.abs(np.linalg.eigvals(J)).max())
            local.append(np.abs(np.linalg.eigvals(
                np.linalg.solve(np.eye(len(s)) - D, J - D))).max())
        print(f"mu r = {mu_r:g} m, {len(plain)} steps: spectral radius of J median "
              f"{np.median(plain):.2e}, largest {max(plain):.2e}; with each leg's own block "
              f"solved: median {np.median(local):.2e}, largest {max(local):.2e}")
        sv = np.linalg.svd(J, compute_uv=False)
        print("  singular values of J (last step): " + " ".join(f"{v:.1e}" for v in sv))


if __name__ == "__main__":
    main()
