"""The whole model: collects the equation groups into one chain per evaluation mode.

Two modes share every equation and differ only in where the bodies' accelerations come from:

* ``"kinematic"``: from the platform's motion (position, orientation, velocities, accelerations),
  through kinematics.py: every body's acceleration, the legs' angular velocities and
  accelerations, gyroscopic terms.
* ``"paper"``: the paper's RESULTS set-up, a substitution into the same equations: the platform's
  and payload's centre-of-mass acceleration and angular acceleration are given constants, every
  leg part has the same given constant accelerations, the gyroscopic terms are zero (the paper
  writes I alpha only), and the joints' relative angular speeds in (33)-(34) have the given
  magnitude (their directions still come from the motion).

Inputs (each a named block; the generated functions take them concatenated, see ``LAYOUT``):
state ``x`` (24 per step), parameters ``P`` (platform description), effect parameters ``Q``
(effects.CATALOG), and in paper mode the constants ``K``.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from . import bushing as bu
from . import coupled as cp
from . import effects as fx
from . import friction as fr
from . import kinematics as kin
from . import leg_frames as lf
from . import legs as lg
from . import platform as pf
from . import prismatic as pr
from .chain import Chain
from .vectors import cross, dot, norm

N_LEGS = 6

# (block, shape, unit, description); the order is the order in the flat input vector.
STATE = (
    ("position", (3,), "m", "platform frame origin, base frame"),
    ("rotation", (3, 3), "1", "platform -> base rotation T, row-major"),
    ("velocity", (3,), "m/s", "velocity of the platform frame origin"),
    ("omega", (3,), "rad/s", "platform angular velocity, base frame"),
    ("acceleration", (3,), "m/s^2", "acceleration of the platform frame origin"),
    ("alpha", (3,), "rad/s^2", "platform angular acceleration, base frame"),
)
PARAMETERS = (
    ("gravity", (), "m/s^2", "gravitational acceleration, along -z of the base frame"),
    ("base_joints", (6, 3), "m", "universal joints C_i, base frame"),
    ("platform_joints", (6, 3), "m", "spherical joints E_i, platform frame"),
    ("universal_axes", (6, 3), "1", "unit first axes a1 of the universal joints, base frame"),
    ("platform_mass", (), "kg", "moving platform"),
    ("platform_inertia", (3, 3), "kg m^2", "about its centre of mass, platform frame"),
    ("platform_com", (3,), "m", "platform frame"),
    ("payload_mass", (), "kg", "payload"),
    ("payload_inertia", (3, 3), "kg m^2", "about its centre of mass, platform frame"),
    ("payload_com", (3,), "m", "platform frame"),
    ("lower_mass", (), "kg", "lower leg part (zone 4)"),
    ("lower_com", (), "m", "fixed part of the distance of its centre from C_i"),
    ("lower_frac", (), "1", "part of that distance proportional to the leg length"),
    ("lower_inertia", (3, 3), "kg m^2", "about its centre, leg body frame"),
    ("upper_mass", (), "kg", "upper leg part (zone 2)"),
    ("upper_com", (), "m", "fixed part of the distance of its centre from E_i"),
    ("upper_frac", (), "1", "part of that distance proportional to the leg length"),
    ("upper_inertia", (3, 3), "kg m^2", "about its centre, leg body frame"),
    ("leg_weight", (), "1", "1: gravity acts on the leg parts; 0: it does not"),
    ("prismatic_point", (), "1", "position of the prismatic joint point, fraction of D from C_i"),
    ("joint_viscous", (), "N m s/rad", "c_s, spherical and universal joints"),
    ("joint_coulomb", (), "1", "mu, spherical and universal joints"),
    ("joint_radius", (), "m", "r, spherical and universal joints"),
    ("prismatic_viscous", (), "N s/m", "viscous coefficient, prismatic joints"),
    ("prismatic_coulomb", (), "1", "Coulomb coefficient, prismatic joints"),
    ("joint_eps", (), "rad/s", "regularisation speed of the joints' sign function"),
    ("prismatic_eps", (), "m/s", "regularisation speed of the prismatic sign function"),
    ("friction_model", (), "1", "1: coupled model (friction loads the mechanism, bushings, "
     "per-axis universal joints); 0: the paper's post-hoc (33)-(35)"),
    ("bushing_offset", (), "m", "distance from C_i of the first bushing (coupled model)"),
    ("bushing_spacing", (), "m", "distance b between the two bushings (coupled model)"),
    ("prismatic_seal", (), "N", "Coulomb force of the prismatic joints' seals"),
)
PAPER_CONSTANTS = (
    ("platform_acc", (3,), "m/s^2", "platform and payload acceleration"),
    ("platform_alpha", (3,), "rad/s^2", "platform angular acceleration"),
    ("leg_acc", (3,), "m/s^2", "acceleration of every leg part"),
    ("leg_alpha", (3,), "rad/s^2", "angular acceleration of every leg part"),
    ("joint_speed", (), "rad/s", "relative angular speed in every spherical and universal joint"),
)

# (name, shape per step, unit, description)
OUTPUTS = (
    ("F", (6,), "N", "actuator forces with friction and effects, + pushes the platform away"),
    ("F0", (6,), "N", "actuator forces of frictionless joints"),
    ("R_E", (6, 3), "N", "force of leg i on the platform at E_i, base frame"),
    ("R_C", (6, 3), "N", "force of the base on leg i at C_i, base frame"),
    ("M_C", (6,), "N m", "universal joint constraint moment on leg i along n_i"),
    ("R_3", (6, 3), "N", "prismatic joint transverse force on the upper part, base frame"),
    ("M_3", (6, 3), "N m", "prismatic joint moment on the upper part, about P_3, base frame"),
    ("MfrE", (6, 3), "N m", "spherical joint friction moment on the platform"),
    ("MfrC", (6, 3), "N m", "universal joint friction moment on the leg"),
    ("Ffr", (6,), "N", "prismatic friction force on the upper part along u (with effects)"),
    ("MfrE_s", (6,), "N m", "paper's signed scalar of (33), negative = opposing"),
    ("MfrC_s", (6,), "N m", "paper's signed scalar of (34)"),
    ("Ffr_s", (6,), "N", "paper's signed scalar of (35)"),
    ("D", (6,), "m", "leg lengths"),
    ("D_dot", (6,), "m/s", "leg length rates (sliding speeds)"),
    ("u", (6, 3), "1", "unit leg directions C_i -> E_i"),
    ("omega_leg", (6, 3), "rad/s", "leg angular velocities (relative velocity in C_i)"),
    ("omega_rel", (6, 3), "rad/s", "platform angular velocity relative to leg i (in E_i)"),
    ("s2", (6,), "1", "1 - (u.a1)^2: zero where the universal joint's moment is undefined"),
    ("R_3_leg", (6, 3), "N", "R_3 in the paper's leg frame (18)-(27)"),
    ("M_3_leg", (6, 3), "N m", "M_3 in the paper's leg frame (18)-(27)"),
    ("coupling_change", (6,), "N", "change of the axial forces over the coupled solve's last "
     "iteration"),
    ("F_joint", (6,), "N", "part of F from the joint friction moments carried by the actuators"),
    ("Ffr_viscous", (6,), "N", "viscous part of Ffr"),
    ("Ffr_coulomb", (6,), "N", "Coulomb part of Ffr from |R_3|, (35) (paper model)"),
    ("Ffr_bushing", (6,), "N", "Coulomb part of Ffr from the bushing forces (coupled model)"),
    ("Ffr_seal", (6,), "N", "seal part of Ffr"),
    ("Ffr_effects", (6,), "N", "part of Ffr from the catalog's prismatic friction effects"),
    ("N_bushing", (6, 2), "N", "magnitudes of the two bushings' normal forces (first, second)"),
)


def _size(shape) -> int:
    n = 1
    for s in shape:
        n *= s
    return n


def _block(ch: Chain, name, shape, latex=None):
    if len(shape) == 0:
        return ch.input(name, 1, 1, latex)[0, 0]
    if len(shape) == 1:
        return ch.input(name, shape[0], 1, latex)
    return ch.input(name, shape[0], shape[1], latex)


def _row(M: sp.Matrix, i: int) -> sp.Matrix:
    return M[i, :].T


@dataclass
class Model:
    """A built chain with its named inputs and outputs (Matrices of chain symbols)."""

    mode: str
    chain: Chain
    inputs: dict[str, tuple]          # input vector name -> block specs
    outputs: dict[str, sp.Matrix]
    symbols: dict                     # named intermediate symbols, for tests and notebooks


def build(mode: str = "kinematic") -> Model:
    """Derive the model in ``mode`` ("kinematic" or "paper")."""
    if mode not in ("kinematic", "paper"):
        raise ValueError(f"unknown mode {mode!r}")
    ch = Chain()
    latex = {"position": "p", "rotation": "T", "velocity": "v", "omega": r"\omega",
             "acceleration": "a", "alpha": r"\alpha"}
    X = {n: _block(ch, n, s, latex.get(n)) for n, s, _, _ in STATE}
    plat_latex = {"gravity": "g", "base_joints": "C", "platform_joints": "e",
                  "universal_axes": "a_{1}", "platform_mass": "m_{M}", "payload_mass": "m_{L}",
                  "platform_inertia": "I_{M}", "payload_inertia": "I_{L}",
                  "platform_com": "c_{M}", "payload_com": "c_{L}",
                  "lower_mass": "m_{4}", "upper_mass": "m_{2}", "lower_com": "l_{4}",
                  "upper_com": "l_{2}", "lower_frac": "k_{4}", "upper_frac": "k_{2}",
                  "lower_inertia": "I_{4}", "upper_inertia": "I_{2}", "leg_weight": "w_{leg}",
                  "prismatic_point": "k_{3}", "joint_viscous": "c_{s}", "joint_coulomb": r"\mu",
                  "joint_radius": "r", "prismatic_viscous": "c_{p}",
                  "prismatic_coulomb": r"\mu_{p}", "joint_eps": r"\varepsilon_{\omega}",
                  "prismatic_eps": r"\varepsilon_{v}"}
    P = {n: _block(ch, n, s, plat_latex.get(n)) for n, s, _, _ in PARAMETERS}
    q_names = fx.parameter_names()
    Qm = ch.input("effects", len(q_names), 1, "Q")
    Q = {n: Qm[k] for k, n in enumerate(q_names)}
    inputs = {"x": STATE, "P": PARAMETERS,
              "Q": tuple((n, (), "", "") for n in q_names)}
    K = None
    if mode == "paper":
        klatex = {"platform_acc": "a^{*}", "platform_alpha": r"\alpha^{*}",
                  "leg_acc": "a^{*}_{leg}", "leg_alpha": r"\alpha^{*}_{leg}",
                  "joint_speed": r"\omega^{*}"}
        K = {n: _block(ch, n, s, klatex[n]) for n, s, _, _ in PAPER_CONSTANTS}
        inputs["K"] = PAPER_CONSTANTS

    g_vec = sp.Matrix([0, 0, -P["gravity"]])
    p, T = X["position"], X["rotation"]
    v, w, a, al = X["velocity"], X["omega"], X["acceleration"], X["alpha"]
    eq_kin = "kinematics"

    # ---- platform and payload: centres, accelerations, inertias (eq. 1 and Newton-Euler)
    offset = sp.Matrix([Q["payload_offset.x"], Q["payload_offset.y"], Q["payload_offset.z"]])
    r_M = ch.let("r_M", T * P["platform_com"], "r_{M}", "1")
    r_L = ch.let("r_L", T * (P["payload_com"] + offset), "r_{L}", "1")
    J_M = T * P["platform_inertia"] * T.T
    J_L = T * P["payload_inertia"] * T.T
    if mode == "kinematic":
        a_M = ch.let("a_M", kin.point_acceleration(a, al, w, r_M), "a_{M}", eq_kin)
        a_L = ch.let("a_L", kin.point_acceleration(a, al, w, r_L), "a_{L}", eq_kin)
        al_P, w_in = al, w
    else:
        a_M = a_L = K["platform_acc"]
        al_P, w_in = K["platform_alpha"], sp.zeros(3, 1)
    m_M, m_L = P["platform_mass"], P["payload_mass"]
    turn = ch.let("M_rot", pf.inertial_moment(T, P["platform_inertia"] + P["payload_inertia"],
                                              al_P, w_in), "M_{rot}", "2-7")
    F_Mr, M_Mr = pf.body_required_wrench(m_M, m_M, r_M, a_M, g_vec, turn)
    F_Lr, M_Lr = pf.body_required_wrench(m_L, m_L, r_L, a_L, g_vec, sp.zeros(3, 1))
    F_req = ch.let("F_req", F_Mr + F_Lr, "F_{req}", "2-7")
    M_req = ch.let("M_req", M_Mr + M_Lr, "M_{req}", "2-7")

    # ---- legs: kinematics (1), (8)-(10) and the required loads (11)-(17)
    legs = []
    for i in range(N_LEGS):
        k = i + 1
        C, e, a1 = _row(P["base_joints"], i), _row(P["platform_joints"], i), \
            _row(P["universal_axes"], i)
        r_E = ch.let(f"r_E{k}", T * e, f"r_{{E{k}}}", "1")
        E = ch.let(f"E{k}", p + r_E, f"E_{{{k}}}", "1")
        D = ch.let(f"D{k}", norm(E - C), f"D_{{{k}}}", "8-10")
        u = ch.let(f"u{k}", (E - C) / D, f"u_{{{k}}}", "8-10")
        vE = ch.let(f"vE{k}", kin.point_velocity(v, w, r_E), f"v_{{E{k}}}", eq_kin)
        D_dot = ch.let(f"D_dot{k}", dot(u, vE), rf"\dot{{D}}_{{{k}}}", eq_kin)
        u_dot = ch.let(f"u_dot{k}", (vE - D_dot * u) / D, rf"\dot{{u}}_{{{k}}}", eq_kin)
        c, s2, a2, n = kin.universal_joint_axes(u, a1)
        c = ch.let(f"c{k}", c, f"c_{{{k}}}", eq_kin)
        s2 = ch.let(f"s2_{k}", 1 - c**2, f"s^{{2}}_{{{k}}}", eq_kin)
        a2 = ch.let(f"a2_{k}", cross(a1, u) / sp.sqrt(s2), f"a_{{2,{k}}}", eq_kin)
        n = ch.let(f"n{k}", (u - c * a1) / sp.sqrt(s2), f"n_{{{k}}}", eq_kin)
        q = ch.let(f"q{k}", dot(cross(u, u_dot), a1), f"q_{{{k}}}", eq_kin)
        lam = ch.let(f"lam{k}", c * q / s2, rf"\lambda_{{{k}}}", eq_kin)
        w_L = ch.let(f"omega_L{k}", cross(u, u_dot) + lam * u, rf"\omega_{{L{k}}}", eq_kin)
        B = sp.Matrix.hstack(a2, cross(u, a2), u)
        s4 = P["lower_com"] + P["lower_frac"] * D
        s2E = P["upper_com"] + P["upper_frac"] * D
        c4 = C + s4 * u
        c2 = E - s2E * u
        if mode == "kinematic":
            aE = ch.let(f"aE{k}", kin.point_acceleration(a, al, w, r_E), f"a_{{E{k}}}", eq_kin)
            D_ddot = ch.let(f"D_ddot{k}", dot(u_dot, vE) + dot(u, aE), rf"\ddot{{D}}_{{{k}}}",
                            eq_kin)
            u_ddot = ch.let(f"u_ddot{k}", (aE - D_ddot * u - 2 * D_dot * u_dot) / D,
                            rf"\ddot{{u}}_{{{k}}}", eq_kin)
            al_L = ch.let(f"alpha_L{k}", kin.leg_angular_acceleration(
                u, u_dot, u_ddot, a1, c, s2, lam, q), rf"\alpha_{{L{k}}}", eq_kin)
            a4 = ch.let(f"a4_{k}", kin.point_on_leg_acceleration(
                s4, P["lower_frac"] * D_dot, P["lower_frac"] * D_ddot, u, u_dot, u_ddot),
                f"a_{{4,{k}}}", eq_kin)
            a2c = ch.let(f"a2c_{k}", aE - kin.point_on_leg_acceleration(
                s2E, P["upper_frac"] * D_dot, P["upper_frac"] * D_ddot, u, u_dot, u_ddot),
                f"a_{{c2,{k}}}", eq_kin)
            w_Lin = w_L
        else:
            a4 = a2c = K["leg_acc"]
            al_L, w_Lin = K["leg_alpha"], sp.zeros(3, 1)
        mg4 = P["leg_weight"] * P["lower_mass"] + Q["leg_weight.lower_mass"]
        mg2 = P["leg_weight"] * P["upper_mass"] + Q["leg_weight.upper_mass"]
        turn4 = ch.let(f"M_rot4_{k}", pf.inertial_moment(B, P["lower_inertia"], al_L, w_Lin),
                       f"M_{{rot4,{k}}}", "17")
        turn2 = ch.let(f"M_rot2_{k}", pf.inertial_moment(B, P["upper_inertia"], al_L, w_Lin),
                       f"M_{{rot2,{k}}}", "17")
        # J: the parts' inertias in base axes, for reading and for the tests (not computed)
        parts = [dict(m=P["lower_mass"], m_weight=mg4, J=B * P["lower_inertia"] * B.T, c=c4,
                      a_c=a4, alpha=al_L, omega=w_Lin, moment=turn4),
                 dict(m=P["upper_mass"], m_weight=mg2, J=B * P["upper_inertia"] * B.T, c=c2,
                      a_c=a2c, alpha=al_L, omega=w_Lin, moment=turn2)]
        F_leg_e, K_leg_e = lg.leg_required(parts, C, g_vec)
        F_leg = ch.let(f"F_leg{k}", F_leg_e, f"F_{{leg,{k}}}", "11-17")
        K_leg = ch.let(f"K{k}", K_leg_e, f"K_{{{k}}}", "11-17")
        M_C = ch.let(f"M_C{k}", lg.torsion_moment(K_leg, u, n), f"M_{{C{k}}}", "11-17")
        t_E = ch.let(f"t_E{k}", lg.transverse_end_force(K_leg, M_C, u, n, D),
                     rf"R_{{E{k}}}^{{\perp}}", "11-17")
        legs.append(dict(k=k, C=C, e=e, a1=a1, a2=a2, E=E, D=D, u=u, n=n, D_dot=D_dot, w_L=w_L,
                         w_Lin=w_Lin, al_L=al_L, s2=s2, turn2=turn2, c2=c2, a2c=a2c, mg2=mg2,
                         F_leg=F_leg, K=K_leg, M_C=M_C, t_E=t_E, parts=parts))

    # ---- the 6x6 system in the axial forces, from (2)-(7)
    A = sp.zeros(6, 6)
    rhs_F, rhs_M = sp.Matrix(F_req), sp.Matrix(M_req)
    for i, L in enumerate(legs):
        A[:3, i] = L["u"]
        A[3:, i] = cross(L["E"] - p, L["u"])
        rhs_F -= L["t_E"]
        rhs_M -= cross(L["E"] - p, L["t_E"])
    A_qr = ch.factor("A", A, "A", "2-7")
    f = ch.solve("f", A_qr, sp.Matrix.vstack(rhs_F, rhs_M), "f", "2-7")

    P3 = P["prismatic_point"]
    for i, L in enumerate(legs):
        k = L["k"]
        L["R_E"] = ch.let(f"R_E{k}", f[i] * L["u"] + L["t_E"], f"R_{{E{k}}}", "11-17")
        L["R_C"] = ch.let(f"R_C{k}", L["R_E"] + L["F_leg"], f"R_{{C{k}}}", "11-17")
        L["P3"] = L["C"] + P3 * L["D"] * L["u"]
        F_ax, R_3, M_3 = pr.upper_part_loads(L["R_E"], L["u"], L["E"], L["P3"],
                                             P["upper_mass"], L["mg2"], L["a2c"], L["c2"],
                                             L["turn2"], g_vec)
        L["F0"] = ch.let(f"F0_{k}", F_ax, f"F_{{0,{k}}}", "28-32")
        L["R_3"] = ch.let(f"R_3{k}", R_3, f"R_{{3,{k}}}", "28-32")
        L["M_3"] = ch.let(f"M_3{k}", M_3, f"M_{{3,{k}}}", "28-32")

    # ---- friction (33)-(35); in the coupled model it loads the mechanism (derive/coupled.py)
    m_model = P["friction_model"] if mode == "kinematic" else sp.S.Zero
    for L in legs:
        k = L["k"]
        w_rel = ch.let(f"omega_rel{k}", w - L["w_L"], rf"\omega_{{1{k}}}", "33-35")
        w_C = L["w_L"]
        if mode == "paper":
            w_rel = ch.let(f"omega_rel_paper{k}", _with_magnitude(w_rel, K["joint_speed"],
                                                                  L["u"]),
                           rf"\omega^{{*}}_{{1{k}}}", "33-35")
            w_C = ch.let(f"omega_C_paper{k}", _with_magnitude(w_C, K["joint_speed"], L["u"]),
                         rf"\omega^{{*}}_{{0{k}}}", "33-35")
        L["w_rel"], L["w_C"] = w_rel, w_C
    weight = cp.coupling_weight(P, Q, mode)

    def moments(L, R_E, R_C, it):
        return _joint_friction(ch, f"{L['k']}_{it}", P, m_model, R_E, R_C, L["w_rel"],
                               L["w_C"], L["a1"], L["a2"])

    change = cp.solve(ch, legs, A_qr, p, weight, moments, m_model)
    for i, L in enumerate(legs):
        k = L["k"]
        dR = L["dR_E"]
        L["R_3"] = ch.let(f"R_3c{k}", L["R_3"] + dR - dot(L["u"], dR) * L["u"],
                          f"R_{{3,{k}}}^{{fr}}", "coupled")
        L["M_3"] = ch.let(f"M_3c{k}", L["M_3"] + cross(L["E"] - L["P3"], dR)
                          + m_model * L["MfrE"], f"M_{{3,{k}}}^{{fr}}", "coupled")
        E_next = legs[(i + 1) % N_LEGS]["E"]
        Lf = lf.leg_frame(L["E"], L["C"], E_next)
        L["R_3_leg"] = lf.to_leg_frame(Lf, L["R_3"])
        L["M_3_leg"] = lf.to_leg_frame(Lf, L["M_3"])
        L["MfrE_s"] = fr.joint_friction_scalar(L["w_rel"], L["R_E_fr"], P["joint_viscous"],
                                               P["joint_coulomb"], P["joint_radius"],
                                               P["joint_eps"])
        L["MfrC_s"] = fr.joint_friction_scalar(L["w_C"], L["R_C_fr"], P["joint_viscous"],
                                               P["joint_coulomb"], P["joint_radius"],
                                               P["joint_eps"])
        L.update(_prismatic_friction(ch, k, P, Q, m_model, L["R_3"], L["M_3"], L["D_dot"],
                                     L["D"], L["u"]))
    df = sp.Matrix([L["dF"] for L in legs])

    bias = [Q[f"sensor_bias.b{k}"] for k in range(1, 7)]
    out = {name: [] for name, *_ in OUTPUTS}
    for i, L in enumerate(legs):
        F = ch.let(f"F{L['k']}", L["F0"] + df[i] - L["Ffr"] + bias[i], f"F_{{{L['k']}}}",
                   "28-32")
        vals = dict(F=[F], F0=[L["F0"]], R_E=list(L["R_E"]), R_C=list(L["R_C"]),
                    M_C=[L["M_C"]], R_3=list(L["R_3"]), M_3=list(L["M_3"]),
                    MfrE=list(L["MfrE"]), MfrC=list(L["MfrC"]), Ffr=[L["Ffr"]],
                    MfrE_s=[L["MfrE_s"]], MfrC_s=[L["MfrC_s"]], Ffr_s=[L["Ffr_s"]],
                    D=[L["D"]], D_dot=[L["D_dot"]], u=list(L["u"]), omega_leg=list(L["w_L"]),
                    omega_rel=list(L["w_rel"]), s2=[L["s2"]], R_3_leg=list(L["R_3_leg"]),
                    M_3_leg=list(L["M_3_leg"]), coupling_change=[change[i]], F_joint=[df[i]],
                    Ffr_viscous=[L["Ffr_viscous"]], Ffr_coulomb=[L["Ffr_coulomb"]],
                    Ffr_bushing=[L["Ffr_bushing"]], Ffr_seal=[L["Ffr_seal"]],
                    Ffr_effects=[L["Ffr_effects"]], N_bushing=list(L["N_bushing"]))
        for name, vlist in vals.items():
            out[name].extend(vlist)
    outputs = {name: sp.Matrix(v) for name, v in out.items()}
    symbols = dict(legs=legs, f=f, df=df, A=A, F_req=F_req, M_req=M_req, p=p, T=T, X=X, P=P,
                   Q=Q, K=K, g_vec=g_vec, r_M=r_M, r_L=r_L, a_M=a_M, a_L=a_L, J_M=J_M, J_L=J_L,
                   alpha_platform=al_P, omega_inertial=w_in)
    return Model(mode, ch, inputs, outputs, symbols)


FRICTION_INPUTS = (
    ("R_E", (6, 3), "N", "force of leg i on the platform at E_i"),
    ("R_C", (6, 3), "N", "force of the base on leg i at C_i"),
    ("R_3", (6, 3), "N", "prismatic joint transverse force"),
    ("M_3", (6, 3), "N m", "prismatic joint moment"),
    ("omega_rel", (6, 3), "rad/s", "relative angular velocity in the spherical joints"),
    ("omega_leg", (6, 3), "rad/s", "relative angular velocity in the universal joints"),
    ("D_dot", (6,), "m/s", "sliding speeds"),
    ("D", (6,), "m", "leg lengths"),
    ("u", (6, 3), "1", "unit leg directions"),
)


def _joint_friction(ch, tag, P, m, R_E, R_C, w_rel, w_C, a1, a2):
    """Friction moments (M_frE on the platform, M_frC on the leg) of one leg, (33)-(34).

    ``m``: the friction model's weight (1: universal joint per bearing axis, coupled.py;
    0: the paper's vector form (34)); the spherical joint keeps the vector form (33).
    """
    c_s, mu, r, eps = P["joint_viscous"], P["joint_coulomb"], P["joint_radius"], P["joint_eps"]
    MfrE = ch.let(f"MfrE{tag}", fr.joint_friction_moment(w_rel, R_E, c_s, mu, r, eps),
                  f"M_{{frE{tag}}}", "33-35")
    vector = fr.joint_friction_moment(w_C, R_C, c_s, mu, r, eps)
    if m == 0:
        MfrC = vector
    else:
        MfrC = m * cp.universal_joint_friction(w_C, R_C, a1, a2, c_s, mu, r, eps) \
            + (1 - m) * vector
    return MfrE, ch.let(f"MfrC{tag}", MfrC, f"M_{{frC{tag}}}", "33-35")


def _prismatic_friction(ch, k, P, Q, m, R_3, M_3, v, D, u) -> dict:
    """Prismatic friction of leg k in its parts: (35) with |R_3| (weight 1 - m) or the
    bushings (weight m, bushing.py), viscous, seals and the catalog's effects."""
    eps_v, c, mu = P["prismatic_eps"], P["prismatic_viscous"], P["prismatic_coulomb"]
    out = {}
    sgn_v = ch.let(f"sgn_v{k}", fr.smooth_sign(v, eps_v), rf"\sigma_{{{k}}}", "33-35")
    s_a = P["bushing_offset"] - P["prismatic_point"] * D
    N_a, N_b = bu.bushing_forces(R_3, M_3, u, s_a, P["bushing_spacing"])
    N_a = ch.let(f"N_a{k}", N_a, f"N_{{a,{k}}}", "bushing")
    N_b = ch.let(f"N_b{k}", N_b, f"N_{{b,{k}}}", "bushing")
    out["N_bushing"] = [norm(N_a), norm(N_b)]
    viscous, bushing, seal = bu.bushing_friction_parts(v, N_a, N_b, c, mu, P["prismatic_seal"],
                                                       eps_v)
    out["Ffr_viscous"] = viscous
    out["Ffr_bushing"] = m * bushing
    out["Ffr_seal"] = seal
    out["Ffr_coulomb"] = -(1 - m) * mu * norm(R_3) * sgn_v
    out["Ffr_effects"] = fx.prismatic_effects_force(Q, v, sgn_v, D, u, M_3)
    out["Ffr_s"] = fr.prismatic_friction_scalar(v, R_3, c, mu, eps_v)
    out["Ffr"] = ch.let(f"Ffr{k}", viscous + out["Ffr_coulomb"] + out["Ffr_bushing"] + seal
                        + out["Ffr_effects"], f"F_{{fr,{k}}}", "33-35")
    return out


def build_friction() -> Model:
    """The friction map alone: reactions, joint speeds and coefficients -> friction.

    The friction of the platform's friction model (``friction_model``) evaluated from the given
    reactions, with nothing fed back.
    """
    ch = Chain()
    blocks = {n: _block(ch, n, s) for n, s, *_ in FRICTION_INPUTS}
    P = {n: _block(ch, n, s) for n, s, _, _ in PARAMETERS}
    q_names = fx.parameter_names()
    Qm = ch.input("effects", len(q_names), 1, "Q")
    Q = {n: Qm[j] for j, n in enumerate(q_names)}
    out = {n: [] for n in ("MfrE", "MfrC", "Ffr", "MfrE_s", "MfrC_s", "Ffr_s")}
    m = P["friction_model"]
    c_s, mu, r, eps = P["joint_viscous"], P["joint_coulomb"], P["joint_radius"], P["joint_eps"]
    for i in range(N_LEGS):
        k = i + 1
        row = {n: (_row(b, i) if b.shape[1] == 3 else b[i]) for n, b in blocks.items()}
        u = row["u"]
        a1 = _row(P["universal_axes"], i)
        a2 = cross(a1, u) / norm(cross(a1, u))
        res = {}
        res["MfrE"], res["MfrC"] = _joint_friction(ch, k, P, m, row["R_E"], row["R_C"],
                                                   row["omega_rel"], row["omega_leg"], a1, a2)
        res["MfrE_s"] = fr.joint_friction_scalar(row["omega_rel"], row["R_E"], c_s, mu, r, eps)
        res["MfrC_s"] = fr.joint_friction_scalar(row["omega_leg"], row["R_C"], c_s, mu, r, eps)
        res.update(_prismatic_friction(ch, k, P, Q, m, row["R_3"], row["M_3"], row["D_dot"],
                                       row["D"], u))
        for n in out:
            v = res[n]
            out[n].extend(list(v) if isinstance(v, sp.MatrixBase) else [v])
    inputs = {n: s for n, s, *_ in FRICTION_INPUTS}
    return Model("friction", ch, inputs, {n: sp.Matrix(v) for n, v in out.items()}, {})


def _with_magnitude(w, speed, fallback):
    """The vector ``speed * w / |w|``; ``speed * fallback`` where w is exactly zero."""
    n2 = dot(w, w)
    return sp.Matrix([sp.Piecewise((speed * w[j] / sp.sqrt(n2), n2 > 0),
                                   (speed * fallback[j], True)) for j in range(3)])


def input_size(specs) -> int:
    return sum(_size(s) for _, s, *_ in specs)
