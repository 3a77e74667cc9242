"""The coupled friction model: joint friction that loads the mechanism, solved at every step.

In the paper's model friction is evaluated after the fact from the frictionless reactions and
fed back nowhere. In the coupled model the friction moments of the spherical joints (on the
platform, ``M_frE``; its reaction ``-M_frE`` on the leg) and of the universal joints (on the leg,
``M_frC``) enter the equilibrium of the legs (11)-(16) and of the platform (2)-(7):

    leg i, moments about C_i:   -D u x R_E + M_C n = K + M_frE - M_frC
    platform:                   sum R_E = F_req,   sum (E_i - p) x R_E + M_frE = M_req

As in the frictionless solve, each leg's moment balance gives the change of its torsion moment
and of the transverse part of R_E, and the 6x6 system ``A f = b`` in the axial forces keeps its
matrix: only the right-hand side changes. Friction depends on the reactions it changes
(``|R_E|``, ``|R_C|``), so the system is solved by fixed-point iteration, unrolled
``N_ITERATIONS`` times in the generated code:

    M_fr^(0) = G(R^(0))                            (R^(0): the frictionless reactions)
    f^(k)    = f^(0) + A^-1 db(x^(k)),  R^(k) = R(f^(k), x^(k)),     x^(1) = M_fr^(0)
    G^(k)    = friction(R^(k)),  r^(k) = G^(k) - x^(k)
    x^(k+1)  = G^(k) - theta^(k) (G^(k) - G^(k-1)),
    theta^(k) = <r^(k), r^(k) - r^(k-1)> / |r^(k) - r^(k-1)|^2,      k = 1 .. N_ITERATIONS - 1

each step re-using the QR factor of A (one back-substitution). The update is Anderson's
acceleration of depth 1 (a secant step on the friction moments of all legs at once, the residual
``r`` the change friction would make); it is left out (theta = 0, the plain step
``x^(k+1) = G^(k)``) at the first update, which has no previous residual, and at the last, so that
the reported moments are the friction of R^(N-1) and ``coupling_change`` measures a plain step.
The moments are affine in the joints' loads (``joint_friction_loads``: 3 per leg), so the
generated code carries the 18 loads as the iterate, with the inner product of the moments
written in the loads (``joint_friction_weights``): the same iterates, fewer operations.
The reported reactions are ``R^(N)``, in equilibrium with the reported friction moments
``x^(N)``; the output ``coupling_change`` is ``f^(N) - f^(N-1)``, the change the last plain step
made, which the runtime compares with a tolerance (``gsfric.evaluation.COUPLING_TOLERANCE``) to
flag steps where the iteration has not converged (mu r so large that friction locks the
mechanism). The plain map contracts with a factor proportional to ``mu r / D``; docs/explanation/friction.md
states the limits checked by the tests and what the acceleration gains.

The universal joint's friction is taken per bearing axis: the leg's angular velocity relative to
the base is ``omega_L = w_1 a_1 + w_2 a_2`` (a_1 base-fixed, a_2 leg-fixed, orthogonal), and each
bearing carries its own radial load ``|a_j x R_C|`` and turns with its own speed ``w_j``:

    M_frC = -sum_j (c_s w_j + mu r |a_j x R_C| sgn(w_j)) a_j

The spherical joint keeps the vector form (33).

The coupling weight ``w`` multiplies every friction moment in the right-hand sides: ``w = 1`` in
the coupled model, and in the paper model the effect ``joint_friction_coupling`` (``scale``) sets
it (0 by default: the paper's post-hoc evaluation, unchanged). In the paper model friction is
always evaluated from the frictionless reactions and the reported reactions stay frictionless;
the effect changes the actuator forces only (one solve with the post-hoc moments).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from . import legs as lg
from .friction import smooth_sign
from .vectors import cross, dot, norm

N_ITERATIONS = 6
"""Fixed-point iterations unrolled in the generated code (each: friction, one back-substitution)."""

ACCELERATE = True
"""Anderson steps (depth 1) between the plain iterations (``_anderson_step``)."""

ANDERSON_FLOOR = 1e-300
"""(N m)^2: added to the Anderson step's denominator, so that an unchanged residual gives 0."""


def joint_friction_terms(let, w_rel, w_C, a1, a2, c_s, mu, r, eps, m) -> dict:
    """The parts of the joints' friction moments that do not depend on the reactions.

    Friction is linear in the loads once the speeds are known: with ``sgn`` the regularised
    sign of friction.py (``smooth_sign``),

    * spherical joint (33): ``M_frE = -c_s w - |R_E| g_E``, ``g_E = mu r sgn(w)``;
    * universal joint, vector form (34): ``-c_s omega_L - |R_C| g_C``, ``g_C = mu r sgn(omega_L)``;
    * universal joint per bearing axis: ``-sum_j (c_s w_j + |a_j x R_C| h_j) a_j`` with
      ``w_j = omega_L . a_j`` and ``h_j = mu r sgn(w_j)``; since omega_L = w_1 a_1 + w_2 a_2,
      its viscous part is the vector form's ``-c_s omega_L``.

    They are defined once per leg, so that each fixed-point iteration only evaluates the loads.
    ``m`` weighs the per-axis form against the vector form (1 coupled model, 0 paper).
    """
    t = dict(vE=let("fr_vE", -c_s * w_rel, r"v_{frE}"),
             gE=let("fr_gE", mu * r * smooth_sign(w_rel, eps), r"g_{frE}"),
             vC=let("fr_vC", -c_s * w_C, r"v_{frC}"), m=m, axes=())
    if m != 1:
        t["gC"] = let("fr_gC", (1 - m) * mu * r * smooth_sign(w_C, eps), r"g_{frC}")
    if m != 0:
        t["axes"] = tuple((a, let(f"fr_h{j}", m * mu * r * smooth_sign(dot(w_C, a), eps),
                                  rf"h_{{fr{j}}}"))
                          for j, a in ((1, a1), (2, a2)))
    return t


def joint_friction_loads(t, R_E, R_C) -> list:
    """The loads the joints' friction moments are affine in, from ``joint_friction_terms``
    and the reactions R_E, R_C (N): ``|R_E|``, then ``|R_C|`` (vector form, when ``t`` has
    ``gC``), then ``|a_j x R_C|`` for each bearing axis (per-axis form); N each."""
    loads = [norm(R_E)]
    if "gC" in t:
        loads.append(norm(R_C))
    loads += [norm(cross(a, R_C)) for a, _ in t["axes"]]
    return loads


def joint_friction_from_loads(t, loads):
    """(M_frE on the platform, M_frC on the leg), base frame, N m, from ``joint_friction_terms``
    and the loads of ``joint_friction_loads`` (in its order)."""
    MfrE = t["vE"] - loads[0] * t["gE"]
    MfrC = t["vC"]
    k = 1
    if "gC" in t:
        MfrC = MfrC - loads[1] * t["gC"]
        k = 2
    for (a, h), load in zip(t["axes"], loads[k:]):
        MfrC = MfrC - load * h * a
    return MfrE, MfrC


def joint_friction_weights(t) -> list:
    """Per load of ``joint_friction_loads``, the squared norm of the moment it multiplies,
    (N m / N)^2: ``|g_E|^2``, ``|g_C|^2``, ``h_j^2`` (the axes a_j are orthogonal unit vectors).

    With them, the squared norm of a change of the friction moments is the weighted sum of the
    squared changes of the loads (exact when the vector form and the per-axis form are not both
    weighted, i.e. for the friction models 0 and 1)."""
    w = [dot(t["gE"], t["gE"])]
    if "gC" in t:
        w.append(dot(t["gC"], t["gC"]))
    w += [h * h for _, h in t["axes"]]
    return w


def joint_friction_moments(t, R_E, R_C):
    """(M_frE on the platform, M_frC on the leg), base frame, N m, from ``joint_friction_terms``
    and the reactions R_E, R_C (N)."""
    return joint_friction_from_loads(t, joint_friction_loads(t, R_E, R_C))


def coupling_weight(P, Q, mode):
    """The weight of the joint friction moments in the equilibrium.

    Kinematic mode: ``m + (1 - m) s`` with ``m = friction_model`` (1 coupled, 0 paper) and ``s``
    the effect ``joint_friction_coupling.scale``; paper mode (the paper's RESULTS set-up): ``s``.
    """
    s = Q["joint_friction_coupling.scale"]
    if mode == "paper":
        return s
    m = P["friction_model"]
    return m + (1 - m) * s


def solve(ch, legs, A_qr, weight, friction, m, n_iter=N_ITERATIONS, accelerate=ACCELERATE):
    """Unrolled fixed point of the coupled equilibrium; updates every leg's outputs in place.

    The iterate is the vector of every leg's friction loads (``joint_friction_loads``: 3 per
    leg in the coupled model); the friction moments are affine in them
    (``joint_friction_from_loads``), so a plain step on the loads is the plain step on the
    moments, and the Anderson step on the loads, with the inner product weighted by
    ``joint_friction_weights``, is the Anderson step on the moments.

    Parameters
    ----------
    ch : Chain
    legs : list of model.Leg
        With the frictionless ``R_E``, ``R_C``, ``M_C`` in ``leg.out``.
    A_qr : Factor
        The QR factor of the platform's 6x6 system in the axial forces.
    weight : sympy expression
        Weight of the friction moments in the equilibrium (``coupling_weight``).
    friction : object
        ``friction.loads(leg, R_E, R_C, it)``: the leg's friction loads (list, N) from its
        reactions; ``friction.moments(leg, loads, it)``: its friction moments (M_frE, M_frC),
        (3, 1) each, N m, from the loads; ``friction.weights(leg)``: the loads' weights.
    m : sympy expression
        The friction model (1 coupled, 0 paper). Friction is evaluated from the reactions
        ``R^(0) + m (R^(k) - R^(0))`` and the reported reactions are the same: in the paper
        model everything stays the frictionless (post-hoc) value, and only the effect
        ``joint_friction_coupling`` (through ``weight``) adds the post-hoc moments' load to the
        axial forces, as one solve (every iterate is the same; with a symbolic ``m = 0`` one
        iteration is generated).
    n_iter : int
        Iterations (back-substitutions), ``N_ITERATIONS``.
    accelerate : bool
        Anderson steps (``_anderson_step``) on the updates 2 .. n_iter - 2 (``ACCELERATE``).

    Returns
    -------
    (df, change) : sympy.Matrix (6, 1) each, N
        The change of the axial forces by the joint friction, and its change over the last
        iteration (zero in the paper model, where every iterate is the same). Sets in
        ``leg.out``: ``R_E``, ``R_C``, ``M_C`` (coupled), ``MfrE``, ``MfrC`` (in equilibrium
        with them), ``R_E_fr``, ``R_C_fr`` (the reactions the moments were computed from) and
        ``dR_E`` (the change of R_E by friction).
    """
    if m == 0:
        n_iter = 1
    R0 = [(leg.out["R_E"], leg.out["R_C"], leg.out["M_C"]) for leg in legs]
    R_E = [r[0] for r in R0]
    R_C = [r[1] for r in R0]
    loads = _friction_loads(friction, legs, R_E, R_C, 0)
    mfr = _friction_moments(friction, legs, loads, 0)
    df_prev = sp.zeros(len(legs), 1)
    memory = _AndersonMemory()
    for it in range(1, n_iter + 1):
        df, dts, dMCs = _friction_solve(ch, legs, A_qr, weight, mfr, it)
        R_E_new, R_C_new = _reactions(legs, R0, df, dts, m)
        if it == n_iter:
            break
        R_E, R_C = R_E_new, R_C_new
        df_prev = df
        image = _friction_loads(friction, legs, R_E, R_C, it)
        loads = _next_loads(ch, it, legs, friction, image, loads, memory,
                            accelerate and it < n_iter - 1)
        mfr = _friction_moments(friction, legs, loads, it)
    _set_outputs(ch, legs, R0, (R_E, R_C), (R_E_new, R_C_new), mfr, (df, dts, dMCs), m)
    return df, m * (df - df_prev)


def _set_outputs(ch, legs, R0, R_fr, R_new, mfr, change, m) -> None:
    """Set every leg's coupled outputs in ``leg.out`` (see ``solve``).

    ``R_fr``: the reactions (R_E, R_C lists) the moments ``mfr`` were computed from; ``R_new``:
    those in equilibrium with them; ``change``: the last iteration's ``_friction_solve``.
    """
    df, dts, dMCs = change
    for i, leg in enumerate(legs):
        let = ch.scope("coupled", leg.k)
        o = leg.out
        o["R_E_fr"], o["R_C_fr"] = R_fr[0][i], R_fr[1][i]
        o["MfrE"], o["MfrC"] = mfr[i]
        o["dR_E"] = m * (df[i] * leg.u + dts[i])
        o["M_C"] = let("M_C_fr", R0[i][2] + m * dMCs[i], r"M^{fr}_{C}")
        o["R_E"] = let("R_E_fr", R_new[0][i], r"R^{fr}_{E}")
        o["R_C"] = let("R_C_fr", R_new[1][i], r"R^{fr}_{C}")


def _friction_loads(friction, legs, R_E, R_C, it) -> list:
    """Every leg's friction loads (``friction.loads``) from its reactions ``R_E[i]``, ``R_C[i]``."""
    return [friction.loads(leg, R_E[i], R_C[i], it) for i, leg in enumerate(legs)]


def _friction_moments(friction, legs, loads, it) -> list:
    """Every leg's friction moments (M_frE, M_frC) (``friction.moments``) from its loads."""
    return [friction.moments(leg, loads[i], it) for i, leg in enumerate(legs)]


def _friction_solve(ch, legs, A_qr, weight, mfr, it):
    """Iteration ``it``'s change of the axial forces by the friction moments ``mfr``.

    Each leg's moment balance gives the change of its torsion moment and of the transverse part
    of R_E; the platform's balance, with the QR factor ``A_qr``, the change of the axial forces.

    Returns
    -------
    (df, dts, dMCs)
        ``df`` sympy.Matrix (6, 1), N; per leg the transverse change of R_E (3, 1), N, and the
        change of the torsion moment M_C, N m.
    """
    rhs_F, rhs_M = sp.zeros(3, 1), sp.zeros(3, 1)
    dts, dMCs = [], []
    for leg, (ME, MC) in zip(legs, mfr):
        let = ch.scope("coupled", leg.k)
        dK = let(f"dK_leg{it}", leg.joint.frame.T * (weight * (ME - MC)),
                 rf"\Delta K^{{({it})}}_{{leg}}")
        dM_C = let(f"dM_C{it}", lg.torsion_moment(dK, leg.joint),
                   rf"\Delta M^{{({it})}}_{{C}}")
        dt = let(f"dt_E{it}", lg.transverse_end_force(dK, dM_C, leg.joint, leg.D),
                 rf"\Delta R^{{({it})}}_{{E\perp}}")
        rhs_F -= dt
        rhs_M -= cross(leg.r_E, dt) + weight * ME
        dts.append(dt)
        dMCs.append(dM_C)
    df = ch.solve(f"df_it{it}_", A_qr, sp.Matrix.vstack(rhs_F, rhs_M),
                  rf"\Delta f^{{({it})}}", "coupled")
    return df, dts, dMCs


def _reactions(legs, R0, df, dts, m) -> tuple[list, list]:
    """The legs' reactions R_E, R_C: the frictionless ``R0`` plus ``m`` times friction's change."""
    R_E_new, R_C_new = [], []
    for i, leg in enumerate(legs):
        dR = m * (df[i] * leg.u + dts[i])
        R_E_new.append(R0[i][0] + dR)
        R_C_new.append(R0[i][1] + dR)
    return R_E_new, R_C_new


@dataclass
class _AndersonMemory:
    """The previous update of the fixed point, for the Anderson step.

    Attributes
    ----------
    images : list or None
        The loads ``G`` of the previous update's reactions (a list per leg); None before it.
    residuals : list or None
        Their residuals ``G - x`` (a list per leg); None before the first update.
    weights : list or None
        The loads' weights in the inner product (``friction.weights``), once a step needs them.
    """

    images: list | None = None
    residuals: list | None = None
    weights: list | None = None


def _next_loads(ch, it, legs, friction, image, loads, memory, accelerate) -> list:
    """The loads of the next iteration: ``image`` (the plain step) or the Anderson step.

    ``loads`` are the loads the iteration was solved with, ``image`` those of its reactions;
    ``accelerate`` allows the Anderson step, taken when ``memory`` holds a previous update.
    Updates ``memory`` to this update.
    """
    residual = [[G - x for G, x in zip(Gs, xs)] for Gs, xs in zip(image, loads)]
    if accelerate and memory.residuals is not None:
        if memory.weights is None:
            memory.weights = [friction.weights(leg) for leg in legs]
        loads = _anderson_step(ch, it, image, residual, memory.images, memory.residuals,
                               memory.weights)
    else:
        loads = image
    memory.images, memory.residuals = image, residual
    return loads


def _anderson_step(ch, it, image, residual, images, residuals, weights):
    """One Anderson step of depth 1 on the friction loads (a list per leg).

    With ``x`` the loads an iteration was solved with, ``G(x)`` the loads of its reactions
    and ``r = G(x) - x``, the next loads are ``G_k - theta (G_k - G_(k-1))`` with
    ``theta = <r_k, r_k - r_(k-1)> / |r_k - r_(k-1)|^2`` (the secant step that cancels the
    residual along its last change; 0 when the residual did not change), the inner product
    weighted by ``weights`` (``joint_friction_weights``: that of the friction moments).
    """
    num = den = sp.S.Zero
    for rs, ps, ws in zip(residual, residuals, weights):
        for r, p, w in zip(rs, ps, ws):
            d = r - p
            wd = w * d
            num += wd * r
            den += wd * d
    theta = ch.scope("coupled")(f"theta{it}", num / (den + ANDERSON_FLOOR),
                                rf"\theta^{{({it})}}")
    return [[G - theta * (G - P) for G, P in zip(Gs, Ps)] for Gs, Ps in zip(image, images)]
