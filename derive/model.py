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
(the generated effects of effects.CATALOG), and in paper mode the constants ``K``.

``build`` reads as the physics runs: ``_platform`` (what platform and payload need), ``_leg``
for each leg (kinematics, the parts' needs, the reduction to one unknown), ``_solve`` (the 6x6
system in the axial forces), ``_reactions`` (every joint's reaction), ``_friction`` and
``_coupling`` (joint friction carried by the actuators: the coupled model's fixed point,
derive/coupled.py, and the prismatic friction of either model from the final reactions). Each calls the equation groups'
functions through a ``Chain.scope`` so that every named quantity is computed once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace

import sympy as sp

from . import bushing as bu
from . import conditioning
from . import coupled as cp
from . import effects as fx
from . import friction as fr
from . import kinematics as kin
from . import leg_frames as lf
from . import legs as lg
from . import platform as pf
from . import prismatic as pr
from .chain import Chain
from .mechanics import Body, Inertia, Wrench
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
    ("h", (), "1", "singularity measure of the force Jacobian, 0 = singular (conditioning.py)"),
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

# Outputs that the SIMD-over-steps functions compute only in a call that asks for one of them
# (derive/simd.py): copies of other outputs in another frame, and the parts of sums that are
# outputs themselves. The runtime computes them on first access (gsfric.evaluation.DETAILS).
ON_REQUEST = ("R_3_leg", "M_3_leg", "Ffr_viscous", "Ffr_coulomb", "Ffr_bushing", "Ffr_seal",
              "Ffr_effects", "N_bushing")


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


STATE_LATEX = {"position": "p", "rotation": "T", "velocity": "v", "omega": r"\omega",
               "acceleration": "a", "alpha": r"\alpha"}
PARAMETER_LATEX = {
    "gravity": "g", "base_joints": "C", "platform_joints": "e", "universal_axes": "a_{1}",
    "platform_mass": "m_{M}", "payload_mass": "m_{L}", "platform_inertia": "I_{M}",
    "payload_inertia": "I_{L}", "platform_com": "c_{M}", "payload_com": "c_{L}",
    "lower_mass": "m_{4}", "upper_mass": "m_{2}", "lower_com": "l_{4}", "upper_com": "l_{2}",
    "lower_frac": "k_{4}", "upper_frac": "k_{2}", "lower_inertia": "I_{4}",
    "upper_inertia": "I_{2}", "leg_weight": "w_{leg}", "prismatic_point": "k_{3}",
    "joint_viscous": "c_{s}", "joint_coulomb": r"\mu", "joint_radius": "r",
    "prismatic_viscous": "c_{p}", "prismatic_coulomb": r"\mu_{p}",
    "joint_eps": r"\varepsilon_{\omega}", "prismatic_eps": r"\varepsilon_{v}",
    "friction_model": "m_{fr}", "bushing_offset": "s_{a}", "bushing_spacing": "b",
    "prismatic_seal": "F_{seal}"}
CONSTANT_LATEX = {"platform_acc": "a^{*}", "platform_alpha": r"\alpha^{*}",
                  "leg_acc": "a^{*}_{leg}", "leg_alpha": r"\alpha^{*}_{leg}",
                  "joint_speed": r"\omega^{*}"}


@dataclass
class Inputs:
    """The chain's inputs by name: state X, parameters P, effect parameters Q, constants K."""

    mode: str
    X: dict
    P: dict
    Q: dict
    K: dict | None
    g_vec: sp.Matrix     # gravitational acceleration, base frame, (3, 1), m/s^2

    @property
    def kinematic(self) -> bool:
        return self.mode == "kinematic"


@dataclass
class PlatformPart:
    """Platform and payload: their bodies and the wrench about p they need, eqs. (2)-(7)."""

    p: sp.Matrix
    T: sp.Matrix
    platform: Body
    payload: Body
    alpha: sp.Matrix          # angular acceleration entering the rotation moment
    omega: sp.Matrix          # angular velocity entering it (zero in paper mode)
    required: Wrench          # F_req, M_req about p


@dataclass
class Leg:
    """Leg k's quantities, filled block by block (paper symbols: C, E, D, u, n, R_E ...)."""

    k: int
    C: sp.Matrix
    a1: sp.Matrix
    E: sp.Matrix
    r_E: sp.Matrix                 # E - p, base frame
    D: sp.Expr
    u: sp.Matrix
    joint: kin.UniversalJoint
    D_dot: sp.Expr
    omega_leg: sp.Matrix
    alpha_leg: sp.Matrix
    lower: Body
    upper: Body
    upper_need: Wrench             # the upper part's required wrench (about its centre)
    s_upper: sp.Expr               # distance of the upper part's centre from C
    F_leg: sp.Matrix
    K: sp.Matrix                   # base frame (computed in the leg's axes)
    M_C: sp.Expr
    t_E: sp.Matrix                 # R_E's part perpendicular to u
    out: dict = field(default_factory=dict)   # reactions and friction, by output name

    @property
    def n(self) -> sp.Matrix:
        return self.joint.n

    @property
    def parts(self) -> tuple[Body, Body]:
        return self.lower, self.upper

    def __getattr__(self, name):
        out = self.__dict__.get("out", {})
        if name in out:
            return out[name]
        raise AttributeError(name)


@dataclass
class Model:
    """A built chain with its named inputs and outputs (Matrices of chain symbols)."""

    mode: str
    chain: Chain
    inputs: dict[str, tuple]          # input vector name -> block specs
    outputs: dict[str, sp.Matrix]
    symbols: dict                     # named intermediate quantities, for tests and notebooks


def build(mode: str = "kinematic", friction_model: int | None = None,
          n_iter: int = cp.N_ITERATIONS) -> Model:
    """Derive the model in ``mode`` ("kinematic" or "paper").

    Parameters
    ----------
    mode : {"kinematic", "paper"}
        Where the bodies' accelerations come from (module docstring).
    friction_model : {None, 0, 1}
        None: the parameter ``friction_model`` of P chooses the model at every step; 0 or 1:
        the model fixed when deriving (the input is then unused), so that the paper's model
        (0) needs no fixed-point iterations.
    n_iter : int
        Iterations of the coupled solve (``coupled.N_ITERATIONS``; other counts for
        benchmarks/coupled_early_exit.py).

    Returns
    -------
    Model
        The chain, its inputs (``x``, ``P``, ``Q`` and in paper mode ``K``, laid out as
        ``STATE``, ``PARAMETERS``, the effect catalog and ``PAPER_CONSTANTS``) and the outputs of
        ``OUTPUTS`` (per step, legs in order, base frame, SI units).
    """
    if mode not in ("kinematic", "paper"):
        raise ValueError(f"unknown mode {mode!r}")
    ch = Chain()
    inp = _inputs(ch, mode)
    if friction_model is not None:
        inp.P["friction_model"] = sp.Integer(friction_model)
    platform = _platform(ch, inp)
    legs = [_leg(ch, inp, platform, i) for i in range(N_LEGS)]
    A, A_qr, f = _solve(ch, platform, legs)
    h = conditioning.singularity_measure(ch, A, A_qr, inp.P["platform_joints"])
    for i, leg in enumerate(legs):
        _reactions(ch, inp, leg, f[i], legs[(i + 1) % N_LEGS])
    for leg in legs:
        _friction(ch, inp, leg)
    df = _coupling(ch, inp, legs, A_qr, n_iter)
    for leg in legs:
        _actuator_force(ch, inp, leg, df[leg.k - 1])
    outputs = {name: sp.Matrix([v for leg in legs for v in _flat(leg.out[name])])
               for name, *_ in OUTPUTS if name != "h"}
    outputs["h"] = sp.Matrix([h])
    inputs = {"x": STATE, "P": PARAMETERS,
              "Q": tuple((n, (), "", "") for n in fx.parameter_names())}
    if mode == "paper":
        inputs["K"] = PAPER_CONSTANTS
    symbols = dict(legs=legs, f=f, df=df, A=A, F_req=platform.required.force,
                   M_req=platform.required.moment, p=platform.p, T=platform.T, X=inp.X,
                   P=inp.P, Q=inp.Q, K=inp.K, g_vec=inp.g_vec, platform=platform,
                   r_M=platform.platform.centre - platform.p,
                   r_L=platform.payload.centre - platform.p,
                   a_M=platform.platform.acceleration, a_L=platform.payload.acceleration,
                   J_M=platform.platform.inertia.in_base(),
                   J_L=platform.payload.inertia.in_base(),
                   alpha_platform=platform.alpha, omega_inertial=platform.omega)
    return Model(mode, ch, inputs, outputs, symbols)


def _flat(value) -> list:
    return list(value) if isinstance(value, sp.MatrixBase) else [value]


def _effects_input(ch: Chain) -> dict:
    """Declare the effect-parameter vector Q; its entries by flat name ``effect.parameter``."""
    names = fx.parameter_names()
    Qm = ch.input("effects", len(names), 1, "Q")
    return {n: Qm[j] for j, n in enumerate(names)}


def _inputs(ch: Chain, mode: str) -> Inputs:
    """Declare the input blocks, in the order of the flat input vectors."""
    X = {n: _block(ch, n, s, STATE_LATEX.get(n)) for n, s, _, _ in STATE}
    P = {n: _block(ch, n, s, PARAMETER_LATEX.get(n)) for n, s, _, _ in PARAMETERS}
    Q = _effects_input(ch)
    K = None
    if mode == "paper":
        K = {n: _block(ch, n, s, CONSTANT_LATEX[n]) for n, s, _, _ in PAPER_CONSTANTS}
    return Inputs(mode, X, P, Q, K, sp.Matrix([0, 0, -P["gravity"]]))


def _platform(ch: Chain, inp: Inputs) -> PlatformPart:
    """Platform and payload: centres (1), accelerations, the wrench they need (2)-(7)."""
    X, P, Q = inp.X, inp.P, inp.Q
    p, T = X["position"], X["rotation"]
    geometry, motion, need = ch.scope("1"), ch.scope("kinematics"), ch.scope("2-7")
    offset = sp.Matrix([Q["payload_offset.x"], Q["payload_offset.y"], Q["payload_offset.z"]])
    r_M = geometry("r_M", T * P["platform_com"], "r_{M}")
    r_L = geometry("r_L", T * (P["payload_com"] + offset), "r_{L}")
    if inp.kinematic:
        a, alpha, omega = X["acceleration"], X["alpha"], X["omega"]
        a_M = motion("a_M", kin.point_acceleration(a, alpha, omega, r_M), "a_{M}")
        a_L = motion("a_L", kin.point_acceleration(a, alpha, omega, r_L), "a_{L}")
    else:
        a_M = a_L = inp.K["platform_acc"]
        alpha, omega = inp.K["platform_alpha"], sp.zeros(3, 1)
    m_M, m_L = P["platform_mass"], P["payload_mass"]
    platform = Body(m_M, m_M, Inertia(P["platform_inertia"], T, p + r_M), a_M, alpha, omega)
    payload = Body(m_L, m_L, Inertia(P["payload_inertia"], T, p + r_L), a_L, alpha, omega)
    # One rotation moment for both: they turn together, in the same axes.
    both = Inertia(P["platform_inertia"] + P["payload_inertia"], T, p)
    turn = both.rotation_moment(alpha, omega, need, "M_rot", "M_{rot}")
    required = pf.required_wrench([(platform, turn), (payload, sp.zeros(3, 1))], p, inp.g_vec)
    required = Wrench(need("F_req", required.force, "F_{req}"),
                      need("M_req", required.moment, "M_{req}"), p)
    return PlatformPart(p, T, platform, payload, alpha, omega, required)


def _leg(ch: Chain, inp: Inputs, platform: PlatformPart, i: int) -> Leg:
    """Leg i: kinematics (1), (8)-(10), its parts' needs (11)-(17), R_E up to its axial part."""
    k = i + 1
    X, P, Q = inp.X, inp.P, inp.Q
    geometry, lengths = ch.scope("1", k), ch.scope("8-10", k)
    motion, need = ch.scope("kinematics", k), ch.scope("11-17", k)
    C, e, a1 = (_row(P[n], i) for n in ("base_joints", "platform_joints", "universal_axes"))
    E, r_E = kin.platform_point(platform.p, platform.T, e, geometry)
    D, u = kin.leg_length_and_direction(E, C, lengths)
    joint = kin.universal_joint_axes(u, a1, motion)
    v_E = motion("v_E", kin.point_velocity(X["velocity"], X["omega"], r_E), "v_{E}")
    D_dot, u_dot = kin.leg_rates(u, D, v_E, motion)
    spin = kin.leg_angular_velocity(u, u_dot, joint, motion)
    # the parts' centres, as distances from C along the leg
    k_low, k_up = P["lower_frac"], 1 - P["upper_frac"]
    s_low = P["lower_com"] + k_low * D
    s_up = k_up * D - P["upper_com"]
    if inp.kinematic:
        a_E = motion("a_E", kin.point_acceleration(X["acceleration"], X["alpha"], X["omega"],
                                                   r_E), "a_{E}")
        D_ddot, u_ddot = kin.leg_second_rates(u, u_dot, D, D_dot, v_E, a_E, motion)
        alpha_body, alpha_leg = kin.leg_angular_acceleration(u_dot, u_ddot, a1, joint, spin,
                                                             motion)
        a_low = motion("a_lower", kin.point_on_leg_acceleration(
            s_low, k_low * D_dot, k_low * D_ddot, u, u_dot, u_ddot), "a_{4}")
        a_up = motion("a_upper", kin.point_on_leg_acceleration(
            s_up, k_up * D_dot, k_up * D_ddot, u, u_dot, u_ddot), "a_{c2}")
        omega_in = spin.omega
        rates = (alpha_body, spin.omega_body)
    else:
        a_low = a_up = inp.K["leg_acc"]
        alpha_leg, omega_in = inp.K["leg_alpha"], sp.zeros(3, 1)
        rates = None
    weight = P["leg_weight"]
    lower = Body(P["lower_mass"], weight * P["lower_mass"] + Q["leg_weight.lower_mass"],
                 Inertia(P["lower_inertia"], joint.frame, C + s_low * u), a_low, alpha_leg,
                 omega_in)
    upper = Body(P["upper_mass"], weight * P["upper_mass"] + Q["leg_weight.upper_mass"],
                 Inertia(P["upper_inertia"], joint.frame, C + s_up * u), a_up, alpha_leg,
                 omega_in)
    rotation = ch.scope("17", k)
    if rates is None:
        rates = lower.inertia.body_rates(alpha_leg, omega_in, rotation, "leg_body")
    turn_low = rotation("M_rot4_leg", lower.inertia.rotation_moment_in_body(*rates),
                        "M^{leg}_{rot4}")
    turn_up = rotation("M_rot2_leg", upper.inertia.rotation_moment_in_body(*rates),
                       "M^{leg}_{rot2}")
    force_low = need("F_lower", lower.required_force(inp.g_vec), "F_{4}")
    force_up = need("F_upper", upper.required_force(inp.g_vec), "F_{2}")
    F_leg = need("F_leg", force_low + force_up, "F_{leg}")
    K_leg = need("K_leg", lg.leg_moment([s_low, s_up], [force_low, force_up],
                                        [turn_low, turn_up], joint), "K^{leg}")
    M_C = need("M_C", lg.torsion_moment(K_leg, joint), "M_{C}")
    t_E = need("t_E", lg.transverse_end_force(K_leg, M_C, joint, D), r"R_{E}^{\perp}")
    upper_need = Wrench(force_up, rotation("M_rot2", joint.frame * turn_up, "M_{rot2}"),
                        upper.centre)
    return Leg(k, C, a1, E, r_E, D, u, joint, D_dot, spin.omega, alpha_leg, lower, upper,
               upper_need, s_up, F_leg, joint.frame * K_leg, M_C, t_E)


def _on_platform(platform: PlatformPart, leg: Leg, force, moment=None) -> Wrench:
    """A wrench the leg puts on the platform at E (its point written p + r_E)."""
    return Wrench(force, moment if moment is not None else sp.zeros(3, 1),
                  platform.p + leg.r_E)


def _solve(ch: Chain, platform: PlatformPart, legs: list[Leg]):
    """Eqs. (2)-(7) as a 6x6 system in the axial forces f: ``A f = required - transverse``."""
    A = sp.zeros(6, 6)
    rest = platform.required
    for i, leg in enumerate(legs):
        A[:3, i] = leg.u
        A[3:, i] = cross(leg.r_E, leg.u)
        rest = rest - _on_platform(platform, leg, leg.t_E)
    A_qr = ch.factor("A", A, "A", "2-7")
    f = ch.solve("f", A_qr, sp.Matrix.vstack(rest.force, rest.moment), "f", "2-7")
    return A, A_qr, f


def _reactions(ch: Chain, inp: Inputs, leg: Leg, f_axial, next_leg: Leg) -> None:
    """R_E, R_C (11)-(17), the prismatic joint (28)-(32) and the leg frame (18)-(27)."""
    need, prismatic = ch.scope("11-17", leg.k), ch.scope("28-32", leg.k)
    R_E = need("R_E", f_axial * leg.u + leg.t_E, "R_{E}")
    R_C = need("R_C", R_E + leg.F_leg, "R_{C}")
    s_3 = inp.P["prismatic_point"] * leg.D
    P3 = leg.C + s_3 * leg.u
    F_ax, R_3, M_3 = pr.upper_part_loads(R_E, leg.upper_need.force, leg.upper_need.moment,
                                         leg.u, leg.D, leg.s_upper, s_3)
    frame = lf.leg_frame(leg.E, leg.C, next_leg.E)
    R_3 = prismatic("R_3", R_3, "R_{3}")
    M_3 = prismatic("M_3", M_3, "M_{3}")
    leg.out.update(R_E=R_E, R_C=R_C, P3=P3, M_C=leg.M_C, D=leg.D, D_dot=leg.D_dot, u=leg.u,
                   omega_leg=leg.omega_leg, s2=leg.joint.sin2,
                   F0=prismatic("F0", F_ax, "F_{0}"), R_3=R_3, M_3=M_3, frame=frame)


def _friction(ch: Chain, inp: Inputs, leg: Leg) -> None:
    """The joints' relative angular velocities that friction (33)-(34) opposes."""
    let = ch.scope("33-35", leg.k)
    omega_rel = let("omega_rel", inp.X["omega"] - leg.omega_leg, r"\omega_{1}")
    omega_C = leg.omega_leg
    if inp.mode == "paper":
        speed = inp.K["joint_speed"]
        omega_rel = let("omega_rel_paper", _with_magnitude(omega_rel, speed, leg.u),
                        r"\omega^{*}_{1}")
        omega_C = let("omega_C_paper", _with_magnitude(omega_C, speed, leg.u),
                      r"\omega^{*}_{0}")
    leg.out["omega_rel"], leg.out["omega_C"] = omega_rel, omega_C


def _coupling(ch: Chain, inp: Inputs, legs: list[Leg], A_qr, n_iter: int = cp.N_ITERATIONS):
    """Joint friction in the equilibrium (derive/coupled.py), then every leg's friction.

    Coupled model (kinematic mode, ``friction_model = 1``): the fixed point of the reactions
    and the friction they cause. Paper model (and paper mode): friction from the frictionless
    reactions; the effect joint_friction_coupling adds the joint moments' load to F. Then the
    prismatic friction from the final R_3, M_3 (the spherical joint's friction moment enters
    M_3 in the coupled model).
    """
    P, Q = inp.P, inp.Q
    m = P["friction_model"] if inp.kinematic else sp.S.Zero

    terms = [_joint_friction_terms(ch.scope("33-35", leg.k), P, m, leg.out["omega_rel"],
                                   leg.out["omega_C"], leg.a1, leg.joint.a2) for leg in legs]

    def loads(leg, R_E, R_C, it):
        let = ch.scope("33-35", leg.k)
        return [let(f"load{j}_{it}", v, f"s_{{fr{j}}}^{{({it})}}") for j, v in
                enumerate(cp.joint_friction_loads(terms[leg.k - 1], R_E, R_C))]

    def moments(leg, leg_loads, it):
        MfrE, MfrC = cp.joint_friction_from_loads(terms[leg.k - 1], leg_loads)
        let = ch.scope("33-35", leg.k)
        return (let(f"MfrE_{it}", MfrE, f"M_{{frE_{it}}}"),
                let(f"MfrC_{it}", MfrC, f"M_{{frC_{it}}}"))

    def weights(leg):
        let = ch.scope("33-35", leg.k)
        return [let(f"wload{j}", v, f"w_{{fr{j}}}") for j, v in
                enumerate(cp.joint_friction_weights(terms[leg.k - 1]))]

    friction = SimpleNamespace(loads=loads, moments=moments, weights=weights)
    df, change = cp.solve(ch, legs, A_qr, cp.coupling_weight(P, Q, inp.mode), friction, m,
                          n_iter)
    for i, leg in enumerate(legs):
        o, let = leg.out, ch.scope("coupled", leg.k)
        dR = o["dR_E"]
        o["R_3"] = let("R_3_fr", o["R_3"] + dR - dot(leg.u, dR) * leg.u, r"R^{fr}_{3}")
        o["M_3"] = let("M_3_fr", o["M_3"] + cross(leg.E - o["P3"], dR) + m * o["MfrE"],
                       r"M^{fr}_{3}")
        frame = o.pop("frame")
        o["R_3_leg"], o["M_3_leg"] = lf.to_leg_frame(frame, o["R_3"]), \
            lf.to_leg_frame(frame, o["M_3"])
        c_s, mu, r, eps = P["joint_viscous"], P["joint_coulomb"], P["joint_radius"], \
            P["joint_eps"]
        o["MfrE_s"] = fr.joint_friction_scalar(o["omega_rel"], o["R_E_fr"], c_s, mu, r, eps)
        o["MfrC_s"] = fr.joint_friction_scalar(o["omega_C"], o["R_C_fr"], c_s, mu, r, eps)
        o.update(_prismatic_friction(ch.scope("33-35", leg.k), P, Q, m, o["R_3"], o["M_3"],
                                     leg.D_dot, leg.D, leg.u))
        o["coupling_change"], o["F_joint"] = change[i], df[i]
    return df


def _actuator_force(ch: Chain, inp: Inputs, leg: Leg, df) -> None:
    """The actuator force: frictionless axial force, coupled joint friction, prismatic
    friction and the sensor's bias."""
    Q = inp.Q
    o = leg.out
    o["F"] = ch.scope("28-32", leg.k)(
        "F", o["F0"] + df - o["Ffr"]
        + Q[f"sensor_bias.b{leg.k}"], "F")


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


def _joint_friction_terms(let, P, m, w_rel, w_C, a1, a2) -> dict:
    """The reaction-free parts of one leg's joint friction (coupled.joint_friction_terms)."""
    return cp.joint_friction_terms(let, w_rel, w_C, a1, a2, P["joint_viscous"],
                                   P["joint_coulomb"], P["joint_radius"], P["joint_eps"], m)


def _joint_friction(let, tag, terms, R_E, R_C):
    """Friction moments (M_frE on the platform, M_frC on the leg) of one leg, (33)-(34).

    ``terms``: ``_joint_friction_terms`` (the model ``m``: 1 the universal joint per bearing
    axis, 0 the paper's vector form (34); the spherical joint keeps the vector form (33)).
    ``tag`` tells the fixed point's iterates apart.
    """
    MfrE, MfrC = cp.joint_friction_moments(terms, R_E, R_C)
    return let(f"MfrE{tag}", MfrE, f"M_{{frE{tag}}}"), let(f"MfrC{tag}", MfrC,
                                                           f"M_{{frC{tag}}}")


def _prismatic_friction(let, P, Q, m, R_3, M_3, v, D, u) -> dict:
    """Prismatic friction of one leg in its parts: (35) with |R_3| (weight 1 - m) or the two
    bushings (weight m, bushing.py), viscous, seal, and the catalog's effects."""
    eps_v, c_p, mu_p = P["prismatic_eps"], P["prismatic_viscous"], P["prismatic_coulomb"]
    sign_v = let("sgn_v", fr.smooth_sign(v, eps_v), r"\sigma")
    s_a = P["bushing_offset"] - P["prismatic_point"] * D
    N_a, N_b = bu.bushing_forces(R_3, M_3, u, s_a, P["bushing_spacing"])
    N_a, N_b = let("N_a", N_a, "N_{a}"), let("N_b", N_b, "N_{b}")
    viscous, bushing, seal = bu.bushing_friction_parts(v, N_a, N_b, c_p, mu_p,
                                                       P["prismatic_seal"], sign_v)
    out = dict(Ffr_viscous=viscous, Ffr_bushing=m * bushing, Ffr_seal=seal,
               Ffr_coulomb=(1 - m) * (fr.prismatic_friction(v, R_3, c_p, mu_p, sign_v)
                                      - viscous),
               Ffr_effects=fx.prismatic_effects_force(Q, v, sign_v, D, u, M_3),
               N_bushing=sp.Matrix([norm(N_a), norm(N_b)]),
               Ffr_s=fr.prismatic_friction_scalar(v, R_3, c_p, mu_p, eps_v))
    out["Ffr"] = let("Ffr", viscous + out["Ffr_coulomb"] + out["Ffr_bushing"] + seal
                     + out["Ffr_effects"], "F_{fr}")
    return out


def build_friction() -> Model:
    """The friction map alone: reactions, joint speeds and coefficients -> friction.

    The friction of the platform's friction model (``friction_model``) evaluated from the
    given reactions, with nothing fed back.

    Returns
    -------
    Model
        Inputs ``FRICTION_INPUTS`` (per step, legs in order), ``P`` and ``Q``; outputs
        MfrE, MfrC (6, 3) N m, Ffr (6,) N and the paper's scalars MfrE_s, MfrC_s, Ffr_s.
    """
    ch = Chain()
    blocks = {n: _block(ch, n, s) for n, s, *_ in FRICTION_INPUTS}
    P = {n: _block(ch, n, s) for n, s, _, _ in PARAMETERS}
    Q = _effects_input(ch)
    out = {n: [] for n in ("MfrE", "MfrC", "Ffr", "MfrE_s", "MfrC_s", "Ffr_s")}
    m = P["friction_model"]
    c_s, mu, r, eps = P["joint_viscous"], P["joint_coulomb"], P["joint_radius"], P["joint_eps"]
    for i in range(N_LEGS):
        row = {n: (_row(b, i) if b.shape[1] == 3 else b[i]) for n, b in blocks.items()}
        let = ch.scope("33-35", i + 1)
        u, a1 = row["u"], _row(P["universal_axes"], i)
        a2 = cross(a1, u) / norm(cross(a1, u))
        terms = _joint_friction_terms(let, P, m, row["omega_rel"], row["omega_leg"], a1, a2)
        res = dict(zip(("MfrE", "MfrC"), _joint_friction(let, "", terms, row["R_E"],
                                                         row["R_C"])))
        res["MfrE_s"] = fr.joint_friction_scalar(row["omega_rel"], row["R_E"], c_s, mu, r, eps)
        res["MfrC_s"] = fr.joint_friction_scalar(row["omega_leg"], row["R_C"], c_s, mu, r, eps)
        res.update(_prismatic_friction(let, P, Q, m, row["R_3"], row["M_3"], row["D_dot"],
                                       row["D"], u))
        for n in out:
            out[n].extend(_flat(res[n]))
    inputs = {n: s for n, s, *_ in FRICTION_INPUTS}
    return Model("friction", ch, inputs, {n: sp.Matrix(v) for n, v in out.items()}, {})


def _with_magnitude(w, speed, fallback):
    """The vector ``speed * w / |w|``; ``speed * fallback`` where w is exactly zero."""
    n2 = dot(w, w)
    return sp.Matrix([sp.Piecewise((speed * w[j] / sp.sqrt(n2), n2 > 0),
                                   (speed * fallback[j], True)) for j in range(3)])


def input_size(specs) -> int:
    """Length of the flat vector laid out by ``specs``.

    Parameters
    ----------
    specs : sequence of (name, shape, ...) tuples
        ``STATE``, ``PARAMETERS``, ``PAPER_CONSTANTS`` or ``FRICTION_INPUTS``.

    Returns
    -------
    int
    """
    return sum(_size(s) for _, s, *_ in specs)
