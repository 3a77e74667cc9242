"""The errata of the paper (docs/reference/errata.md): each printed form against the derived one.

Every equation of derive/printed.py and derive/printed_legs.py is evaluated at states of seeded
random motions, with the reactions and body accelerations of the derivation (the chain of
derive/model.py, evaluated through CasADi), converted to the paper's reading (derive/printed.py,
"Reading"). For an equation with errata E, E', ...:

* with every correction (``fix=EQUATION_ERRATA[eq]``) the equation holds: relative residual
  below ``HOLDS`` at every state;
* with every correction but one erratum's, it fails: relative residual above ``FAILS`` at
  most states (the median over the states; a term may vanish at a particular state). So each
  erratum alone breaks equilibrium, and the list of an equation's errata is complete.

The relative residual of an equation is ``|sum of terms| / sum of |terms|``; of a group (legs,
components), the largest of its members'. Notation errata are tested by the fact they document,
table errata on the CSVs of the paper's tables (``PAPER``).
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest
import sympy as sp
from helpers import PAPER_MISPRINTS

from derive import effects as fx
from derive import kinematics as kin
from derive import model as dm
from derive import printed as pr
from derive import printed_legs as pl
from gsfric import models
from gsfric.evaluation.evaluator import state_array
from gsfric.evaluation.paper_constants import PAPER_LEG_ACCELERATION
from gsfric.evaluation.parameters import parameter_values
from gsfric.paper import tables as paper
from gsfric.trajectory import Motion

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

PAPER = Path(__file__).resolve().parents[2] / "shared" / "paper"
DOC = Path(__file__).resolve().parents[1] / "docs" / "reference" / "errata.md"
HOLDS = 1e-9
FAILS = 1e-3
SEED = 20261122
STATES = 8

PLATE_INERTIA = np.diag([0.2, 0.5, 0.7])
"""A flat rectangular platform of 10 kg, about 0.8 m by 0.5 m, kg m^2: I_zz = I_xx + I_yy."""
TILT = np.array([0.15, 0.26, 0.0])
"""A constant tilt of the platform (rotation vector, rad, 0.3 rad about a horizontal axis), for
states away from the level pose."""
AXES_TILT = 0.4
"""Rotation of the universal joints' first axes out of the base plane (about C_i's radius), rad."""
RIGID_CENTRES = dict(lower_com=0.1, upper_com=0.4)
"""Rigid leg parts with centres 0.1 m from C_i and 0.4 m from E_i."""
ROD_INERTIA = np.diag([0.035, 0.035, 0.0005])
"""A slender leg part in its body frame (z along the leg), kg m^2."""


# ----------------------------------------------------------------------------- the chain


@functools.lru_cache(maxsize=None)
def _compiled():
    """The kinematic mode's chain as a CasADi function of its inputs, returning named quantities."""
    m = dm.build("kinematic")
    S = m.symbols
    out = {"p": S["p"], "T": S["T"], "r_M": S["r_M"], "a_M": S["a_M"],
           "J_P": S["J_M"] + S["J_L"], "alpha_P": S["alpha_platform"],
           "omega_P": S["omega_inertial"]}
    for L in S["legs"]:
        lower, upper = L.parts
        quantities = dict(
            E=L.E, C=L.C, D=L.D, u=L.u, n=L.n, R_E=L.R_E, R_C=L.R_C, M_C=L.M_C, R_3=L.R_3,
            M_3=L.M_3, F0=L.F0, P3=L.P3,
            m2=upper.mass, mg2=upper.weight_mass, a2=upper.acceleration, c2=upper.centre,
            J2=upper.inertia.in_base(),
            m4=lower.mass, mg4=lower.weight_mass, a4=lower.acceleration, c4=lower.centre,
            J4=lower.inertia.in_base(),
            alpha_L=upper.alpha, omega_in=upper.omega, omega_L=L.omega_leg,
            omega_rel=L.omega_rel, D_dot=L.D_dot, R_3_leg=L.R_3_leg, MfrE=L.MfrE,
            MfrC=L.MfrC)
        for name, value in quantities.items():
            out[f"{name}{L.k}"] = value if isinstance(value, sp.MatrixBase) \
                else sp.Matrix([value])
    inputs = {n: ca.SX.sym(n.replace(".", "_"), len(mat)) for n, mat in m.chain.inputs.items()}
    exprs = m.chain.to_casadi(inputs, out)
    names = list(out)
    f = ca.Function("errata", [inputs[n] for n in m.chain.inputs],
                    [exprs[n] for n in names])
    return f, list(m.chain.inputs), names, {n: out[n].shape for n in names}


def _parameters(platform) -> dict:
    """The chain's parameter blocks for ``platform``, effects at their defaults."""
    return dict(parameter_values(platform),
                effects=[p.default for e in fx.generated() for p in e.parameters])


def _evaluate(platform, motion) -> dict:
    """Every named quantity at every step, each with the step as its last axis."""
    f, inputs, names, shapes = _compiled()
    x = state_array(motion)
    n = x.shape[0]
    values = _parameters(platform)
    per_step = set()
    offset = 0
    for name, shape, *_ in dm.STATE:
        size = int(np.prod(shape))
        values[name] = x[:, offset:offset + size].T
        per_step.add(name)
        offset += size
    args = [values[name] if name in per_step else np.ravel(values[name])[:, None]
            for name in inputs]
    res = f.map(n)(*args)
    out = {}
    for name, r in zip(names, res):
        a = np.array(r).reshape(shapes[name] + (n,))
        out[name] = a[0, 0] if shapes[name] == (1, 1) else (a[:, 0] if shapes[name][1] == 1
                                                             else a)
    return out


# ----------------------------------------------------------------------------- the states


def _lively_motion(rng: np.random.Generator, n: int = STATES):
    """A fast random 6-DoF motion about the home pose, sampled at n random times."""
    amplitude = rng.uniform(0.5, 1.0, 6) * np.array([0.03, 0.03, 0.03, 0.08, 0.08, 0.1])
    return models.sinusoidal(np.sort(rng.uniform(0.0, 3.0, n)), amplitude,
                             rng.uniform(1.0, 2.0, 6), rng.uniform(0.0, 2 * np.pi, 6))


def _tilted(motion, rotvec=TILT):
    """``motion`` with its orientation turned by a constant rotation (base frame) ``rotvec``."""
    from scipy.spatial.transform import Rotation

    R0 = Rotation.from_rotvec(rotvec).as_matrix()
    return Motion.from_arrays(t=motion.t, position=motion.position, rotation=R0 @ motion.rotation,
                              velocity=motion.velocity, omega=motion.omega @ R0.T,
                              acceleration=motion.acceleration, alpha=motion.alpha @ R0.T)


def _tilted_axes(platform, angle=AXES_TILT):
    """``platform`` with each universal joint's first axis turned about C_i's radius by angle."""
    from scipy.spatial.transform import Rotation

    g = platform.geometry
    radial = g.base_joints / np.linalg.norm(g.base_joints, axis=1)[:, None]
    axes = np.stack([Rotation.from_rotvec(angle * radial[i]).apply(np.array(g.universal_axes[i]))
                     for i in range(6)])
    return platform.with_geometry(universal_axes=axes)


def _quantities(platform, motion) -> SimpleNamespace:
    """The derived state in the paper's reading: reactions, inertial loads, weights, levers."""
    q = _evaluate(platform, motion)
    g = platform.gravity
    down = np.array([0.0, 0.0, -g])[:, None]
    legs = []
    for k in range(1, 7):
        def get(name):
            return q[f"{name}{k}"]
        J2, J4 = get("J2"), get("J4")
        alpha, omega_in = get("alpha_L"), get("omega_in")
        leg = SimpleNamespace(
            E=get("E"), C=get("C"), D=get("D"), u=get("u"), n=get("n"),
            R_E=get("R_E"), R_C=get("R_C"), R_3=get("R_3"), M_3=get("M_3"), F0=get("F0"),
            M_C=get("M_C"), D_dot=get("D_dot"), omega_L=get("omega_L"),
            omega_rel=get("omega_rel"), R_3_leg=get("R_3_leg"), MfrE=get("MfrE"),
            MfrC=get("MfrC"), a2=get("a2"), a4=get("a4"), J2=J2, J4=J4, alpha=alpha,
            omega_in=omega_in, m2=get("m2"), m4=get("m4"))
        leg.RE_o = -leg.R_E
        leg.RC_o = -leg.R_C
        leg.MC_o = -leg.M_C * leg.n
        leg.F2 = leg.m2 * leg.a2
        leg.F4 = leg.m4 * leg.a4
        leg.M2 = np.array(pr.inertial_moment(J2, alpha, omega_in))
        leg.M4 = np.array(pr.inertial_moment(J4, alpha, omega_in))
        leg.W2 = get("mg2") * down
        leg.W4 = get("mg4") * down
        leg.r2 = get("c2") - leg.C
        leg.r4 = get("c4") - leg.C
        leg.s2 = np.einsum("jn,jn->n", get("c2") - leg.E, -leg.u)
        leg.s3 = np.linalg.norm(get("P3") - leg.E, axis=0)
        legs.append(leg)
    for i, leg in enumerate(legs):
        leg.E_next = legs[(i + 1) % 6].E
    body = platform.platform
    m = body.mass + body.payload_mass
    return SimpleNamespace(
        platform=platform, legs=legs,
        E=np.stack([leg.E for leg in legs]), R_E=np.stack([leg.R_E for leg in legs]),
        p=q["p"], T=q["T"], o=q["p"] + q["r_M"], a=q["a_M"], J=q["J_P"], alpha=q["alpha_P"],
        omega=q["omega_P"], m=m, m_M=body.mass, m_E=body.payload_mass, W_T=m * g,
        I=np.diag(body.inertia + body.payload_inertia))


@functools.lru_cache(maxsize=None)
def world(name: str) -> SimpleNamespace:
    """The states the tests share, by name.

    ``rigid``: the reference platform with rigid leg parts centred as ``RIGID_CENTRES``, a
    lively motion. ``paper_legs``: the paper's leg model (zone centres at 0.25 D and 0.75 D),
    same kind of motion. ``anisotropic``: the paper's legs with a flat platform
    (``PLATE_INERTIA``) and slender leg parts (``ROD_INERTIA``), the platform tilted by ``TILT``.
    ``weightless``: the paper's legs without their weight. ``tilted_axes``: the paper's legs with
    the universal joints' first axes out of the base plane (``AXES_TILT``), so that the legs spin
    and the joints carry torsion.
    ``paper_setup``: the paper's 40-step motion (constant accelerations from rest) with the
    paper's legs without weight, as its equations (11)-(16) have them.
    """
    rng = np.random.default_rng(SEED + sum(map(ord, name)))
    paper_legs = models.paper_platform()
    if name == "rigid":
        return _quantities(models.reference_platform("paper").with_legs(**RIGID_CENTRES),
                           _lively_motion(rng))
    if name == "paper_legs":
        return _quantities(paper_legs, _lively_motion(rng))
    if name == "anisotropic":
        platform = paper_legs.with_body(inertia=PLATE_INERTIA).with_legs(
            lower_inertia=ROD_INERTIA, upper_inertia=ROD_INERTIA)
        return _quantities(platform, _tilted(_lively_motion(rng)))
    if name == "tilted_axes":
        return _quantities(_tilted_axes(paper_legs), _lively_motion(rng))
    if name == "weightless":
        return _quantities(paper_legs.with_legs(weight=False), _lively_motion(rng))
    if name == "paper_setup":
        return _quantities(paper_legs.with_legs(weight=False), models.paper_motion())
    raise KeyError(name)


# ----------------------------------------------------------------------------- residuals


def relative(groups) -> np.ndarray:
    """Per state: the largest ``|residual| / magnitude`` of a list of term dicts."""
    ratios = [np.abs(pr.residual(t)) / pr.magnitude(t) for t in groups]
    return np.max(np.broadcast_arrays(*ratios), axis=0)


def platform_moments(w, eq: str, fix=()) -> list[dict]:
    """(5), (6) or (7) with the derived reactions in the reading (``R^O_E = -R_E``)."""
    f = {"5": pr.eq5_terms, "6": pr.eq6_terms, "7": pr.eq7_terms}[eq]
    return [f(-w.R_E, w.E, w.W_T, w.o, w.I, w.alpha, fix, m=w.m, a=w.a, J=w.J, omega=w.omega)]


def leg_forces(w, fix=()) -> list[dict]:
    """(11)-(13) for every leg."""
    out = []
    for leg in w.legs:
        out += pl.eq11_13_terms(leg.RC_o, leg.RE_o, leg.F2, leg.F4, fix, W2=leg.W2, W4=leg.W4)
    return out


def leg_moments(w, eq: str, fix=(), inertia=None) -> list[dict]:
    """(14), (15) or (16) for every leg; ``inertia(leg) -> (M2, M4)`` replaces the derived ones."""
    index = {"14": 0, "15": 1, "16": 2}[eq]
    fixes = [(), (), ()]
    fixes[index] = fix
    out = []
    for leg in w.legs:
        M2, M4 = (leg.M2, leg.M4) if inertia is None else inertia(leg)
        terms = pl.eq14_16_terms(leg.RE_o, leg.E, leg.C, leg.D, leg.F2, leg.F4, M2, M4,
                                 leg.MC_o, *fixes, W2=leg.W2, W4=leg.W4, r2=leg.r2, r4=leg.r4)
        out.append(terms[index])
    return out


def upper_parts(w, fix=(), transform=("E22",), which=slice(None), inertial=None) -> list[dict]:
    """(28)-(32) for every leg, its vectors taken to the leg frame by ``eq25_27(fix=transform)``.

    ``inertial(leg) -> vector`` replaces zone 2's inertial force in (30)-(31) (``which``
    selects equations).
    """
    out = []
    for leg in w.legs:
        U = pl.leg_frame(leg.E, leg.C, leg.E_next, ("E21",))

        def to_leg(v):
            return np.array(pl.eq25_27(v, U, transform))

        R3 = to_leg(-(leg.R_3 + leg.F0 * leg.u))
        F2 = to_leg(leg.F2 if inertial is None else inertial(leg))
        terms = pl.eq28_32_terms(R3, to_leg(leg.RE_o), F2, to_leg(leg.M2), to_leg(-leg.M_3),
                                 leg.D, fix, W2=to_leg(leg.W2), s2=leg.s2, s3=leg.s3)
        out += terms[which]
    return out


def assert_holds(groups, what: str) -> None:
    r = relative(groups)
    assert r.max() < HOLDS, f"{what}: relative residual {r.max():.2e} (should hold)"


def assert_fails(groups, what: str) -> None:
    r = relative(groups)
    assert np.median(r) > FAILS, f"{what}: relative residual {np.median(r):.2e} at half the " \
        "states (should fail)"


def assert_isolates(build, eq: str, eid: str) -> None:
    """``build(fix)``: with every correction of ``eq`` it holds, without ``eid``'s it fails."""
    every = pr.EQUATION_ERRATA[eq]
    assert eid in every
    assert_holds(build(every), f"({eq}) with every correction")
    assert_fails(build(tuple(e for e in every if e != eid)), f"({eq}) without {eid}")


# ----------------------------------------------------------------------------- (1)


def test_E01_rotation_labels():
    alpha, beta, gamma = sp.symbols("alpha beta gamma", real=True)
    b = pr.eq1_printed_b(alpha, beta, gamma)
    T = kin.rotation_zxz(alpha, beta, gamma)
    assert sp.simplify(b - T) == sp.zeros(3, 3)
    m = pr.eq1_printed_matrices(alpha, beta, gamma)
    values = {alpha: 0.4, beta: 0.7, gamma: -1.1}
    as_labelled = m["Rz(gamma)"] * m["Ry(beta)"] * m["Rx(alpha)"]
    gap = np.abs(np.array((as_labelled - b).subs(values).evalf(), dtype=float)).max()
    assert gap > 0.1
    ey, ex = sp.Matrix([0, 1, 0]), sp.Matrix([1, 0, 0])
    assert m["Ry(beta)"] * ey == ey
    assert sp.simplify(kin.rotation_zxz(0, beta, 0) * ex - ex) == sp.zeros(3, 1)


def test_E02_eq1_translation():
    w = world("rigid")
    for i, leg in enumerate(w.legs):
        e = w.platform.geometry.platform_joints[i]
        printed = np.array(pr.eq1_point(w.T, e))
        derived = np.array(pr.eq1_point(w.T, e, ("E02",), p=w.p))
        np.testing.assert_allclose(derived, leg.E, atol=1e-12)
        assert np.linalg.norm(printed - leg.E, axis=0).min() > 0.5


# ----------------------------------------------------------------------------- (2)-(7)


def test_E03_eq2_4_reading():
    w = world("rigid")
    readings = {(s_r, s_w): pr.eq2_4_terms(s_r * -w.R_E, s_w * w.W_T, w.m_M, w.m_E, w.a)
                for s_r in (1, -1) for s_w in (1, -1)}
    assert_holds(readings[(1, 1)], "(2)-(4), R^O on the leg, W_T > 0")
    for reading, terms in readings.items():
        if reading != (1, 1):
            assert_fails(terms, f"(2)-(4) under reading {reading}")


@pytest.mark.parametrize("eq", ["5", "6", "7"])
def test_eq5_7_as_printed_fail_under_every_reading(eq):
    w = world("anisotropic")
    for s_r in (1, -1):
        for s_w in (1, -1):
            f = {"5": pr.eq5_terms, "6": pr.eq6_terms, "7": pr.eq7_terms}[eq]
            terms = f(-s_r * w.R_E, w.E, s_w * w.W_T, w.o, w.I, w.alpha)
            assert_fails([terms], f"({eq}) as printed, reading {(s_r, s_w)}")


def test_E04_eq5_signs():
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), "5", fix), "5", "E04")


def test_E05_eq6_signs():
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), "6", fix), "6", "E05")


def test_E06_eq6_missing_RXE4():
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), "6", fix), "6", "E06")


def test_E07_eq6_weight_lever():
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), "6", fix), "6", "E07")


def test_E08_eq7_signs():
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), "7", fix), "7", "E08")


def test_E09_eq7_RXE6_for_RYE6():
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), "7", fix), "7", "E09")


def test_E10_eq7_missing_RYE4():
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), "7", fix), "7", "E10")


@pytest.mark.parametrize("eq", ["5", "6", "7"])
def test_E11_eq5_7_inertial_force_moment(eq):
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), eq, fix), eq, "E11")


@pytest.mark.parametrize("eq", ["5", "6", "7"])
def test_E12_eq5_7_inertial_moment(eq):
    assert_isolates(lambda fix: platform_moments(world("anisotropic"), eq, fix), eq, "E12")


# ----------------------------------------------------------------------------- (11)-(17)


def test_E13_leg_weights():
    w = world("paper_legs")
    assert_isolates(lambda fix: leg_forces(w, fix), "11-13", "E13")
    for eq in ("14", "15"):
        assert_isolates(lambda fix: leg_moments(w, eq, fix), eq, "E13")
    assert_isolates(lambda fix: upper_parts(w, fix, which=slice(0, 4)), "28-32", "E13")
    light = world("weightless")
    assert_holds(leg_forces(light), "(11)-(13) as printed, legs without weight")


def test_E14_eq14_15_operator():
    w = world("paper_legs")
    for eq in ("14", "15"):
        assert_isolates(lambda fix: leg_moments(w, eq, fix), eq, "E14")


def test_E15_eq15_signs():
    assert_isolates(lambda fix: leg_moments(world("paper_legs"), "15", fix), "15", "E15")


def test_E16_eq16_signs():
    assert_isolates(lambda fix: leg_moments(world("paper_legs"), "16", fix), "16", "E16")


def test_E17_eq16_missing_D():
    assert_isolates(lambda fix: leg_moments(world("paper_legs"), "16", fix), "16", "E17")


def test_E18_universal_joint_moment():
    w = world("tilted_axes")
    for eq in ("14", "15"):
        assert_isolates(lambda fix: leg_moments(w, eq, fix), eq, "E18")


def test_E19_zone_centres():
    rigid, paper = world("rigid"), world("paper_legs")
    for eq in ("14", "15", "16"):
        assert_isolates(lambda fix: leg_moments(rigid, eq, fix), eq, "E19")
        every_but = tuple(e for e in pr.EQUATION_ERRATA[eq] if e != "E19")
        assert_holds(leg_moments(paper, eq, every_but), f"({eq}), paper legs, printed levers")
    assert_isolates(lambda fix: upper_parts(rigid, fix, which=slice(2, 4)), "28-32", "E19")


def test_E20_eq17_inertial_moment():
    w = world("anisotropic")
    every = {eq: pr.EQUATION_ERRATA[eq] for eq in ("14", "15", "16")}

    def inertia(fix):
        def moments(leg):
            body = w.platform.legs
            out = []
            for m, a, J, I in ((leg.m2, leg.a2, leg.J2, np.diag(body.upper_inertia)),
                               (leg.m4, leg.a4, leg.J4, np.diag(body.lower_inertia))):
                _, M = pl.eq17(m, a, I, leg.alpha, fix, J=J, omega=leg.omega_in)
                out.append(np.array(M))
            return out
        return moments

    derived = [t for eq, fix in every.items() for t in leg_moments(w, eq, fix, inertia(("E20",)))]
    printed = [t for eq, fix in every.items() for t in leg_moments(w, eq, fix, inertia(()))]
    assert_holds(derived, "(14)-(16) with (17) corrected")
    assert_fails(printed, "(14)-(16) with (17) as printed")


# ----------------------------------------------------------------------------- (18)-(32)


def test_E21_leg_frame_V():
    w = world("rigid")
    for leg in w.legs:
        derived = np.array(pl.leg_frame(leg.E, leg.C, leg.E_next, ("E21",)))
        printed = np.array(pl.leg_frame(leg.E, leg.C, leg.E_next))
        np.testing.assert_allclose(np.einsum("kjn,jn->kn", derived, leg.R_3), leg.R_3_leg,
                                   atol=1e-12)
        np.testing.assert_allclose(printed[:2], -derived[:2], atol=1e-12)
        np.testing.assert_allclose(printed[2], derived[2], atol=1e-12)
        handed = np.einsum("jn,jn->n", np.cross(derived[0], derived[1], axis=0), derived[2])
        np.testing.assert_allclose(handed, 1.0, atol=1e-12)


def test_E22_leg_components():
    w = world("rigid")
    every = pr.EQUATION_ERRATA["28-32"]
    assert_holds(upper_parts(w, every, ("E22",)), "(28)-(32), components R . U")
    assert_fails(upper_parts(w, every, (), slice(2, 5)), "(30)-(32), components as printed")
    assert_holds(upper_parts(w, every, (), slice(0, 2)), "(28)-(29), components as printed")
    for leg in w.legs:
        U = pl.leg_frame(leg.E, leg.C, leg.E_next, ("E21",))
        for transform, keeps in ((("E22",), True), ((), False)):
            size = np.linalg.norm(np.array(pl.eq25_27(leg.R_E, U, transform)), axis=0)
            kept = np.allclose(size, np.linalg.norm(leg.R_E, axis=0), rtol=1e-12)
            assert kept == keeps


def test_E23_eq30_31_inertial_force_label():
    w = world("paper_legs")
    every = pr.EQUATION_ERRATA["28-32"]
    assert_holds(upper_parts(w, every, which=slice(2, 4)), "(30)-(31) with F_2 for R_2")
    assert_fails(upper_parts(w, every, which=slice(2, 4), inertial=lambda leg: leg.RE_o),
                 "(30)-(31) with the reaction R_E for R_2")


def test_E24_axial_equation():
    w = world("paper_legs")
    every = pr.EQUATION_ERRATA["28-32"]
    printed_set = tuple(e for e in every if e != "E24")
    assert_holds(upper_parts(w, every, which=slice(5, 6)), "axial equation with F0")
    axial = np.median([np.abs(leg.F0) for leg in w.legs])
    transverse = np.median([np.linalg.norm(leg.R_3, axis=0) for leg in w.legs])
    assert axial > 10 * transverse
    shifted = SimpleNamespace(**vars(w))
    shifted.legs = [SimpleNamespace(**{**vars(leg), "F0": leg.F0 + 100.0}) for leg in w.legs]
    assert_holds(upper_parts(shifted, printed_set), "(28)-(32) with another axial force")
    assert_fails(upper_parts(shifted, every, which=slice(5, 6)),
                 "axial equation with another axial force")


# ----------------------------------------------------------------------------- (33)-(35)


def test_E25_sign_function():
    w = world("rigid")
    fr = w.platform.friction
    printed_power, derived_power = [], []
    for leg in w.legs:
        for omega, R, chain in ((leg.omega_rel, leg.R_E, leg.MfrE), (leg.omega_L, leg.R_C,
                                                                      leg.MfrC)):
            args = (fr.joint_viscous, omega, fr.joint_coulomb, fr.joint_radius, R)
            derived = np.array(pl.eq33_34(*args, ("E25",)))
            printed = np.array(pl.eq33_34(*args))
            np.testing.assert_allclose(derived, chain, rtol=1e-4, atol=1e-12)
            derived_power.append(np.einsum("jn,jn->n", derived, omega))
            printed_power.append(np.einsum("jn,jn->n", printed, omega))
    assert np.max(derived_power) < 0
    assert np.max(printed_power) > 0


def test_E26_relative_rotation_not_a_projection():
    w = world("rigid")
    across = []
    for leg in w.legs:
        w_rel = leg.omega_rel
        along = np.einsum("jn,jn->n", w_rel, leg.u)
        across.append(np.linalg.norm(w_rel - along * leg.u, axis=0)
                      / np.linalg.norm(w_rel, axis=0))
    assert np.max(across, axis=0).min() > 0.5


def test_E27_prismatic_viscous_units():
    from sympy.physics import units as u
    from sympy.physics.units.systems.si import SI, dimsys_SI

    def dimension(q):
        return dimsys_SI.get_dimensional_dependencies(u.Dimension(SI.get_dimensional_expr(q)))

    speed = u.meter / u.second
    force = dimension(u.newton)
    assert dimension(u.newton * u.meter * u.second / u.radian * speed) != force
    assert dimension(u.newton * u.second / u.meter * speed) == force


# ----------------------------------------------------------------------------- RESULTS


def test_E28_unit_matrix_inertia():
    rng = np.random.default_rng(SEED)
    T = models.sinusoidal(np.array([0.3]), rng.uniform(0.1, 0.5, 6)).rotation[0]
    omega, alpha = rng.normal(size=3), rng.normal(size=3)
    for I, exact in ((0.07 * np.eye(3), True), (PLATE_INERTIA, False)):
        J = T @ I @ T.T
        derived = np.array(pr.inertial_moment(J, alpha, omega))
        printed = np.diag(I) * alpha
        gap = np.abs(derived - printed).max() / np.abs(derived).max()
        assert (gap < 1e-12) == exact
    w = world("paper_legs")
    for eq in ("5", "6", "7"):
        every_but = tuple(e for e in pr.EQUATION_ERRATA[eq] if e != "E12")
        assert_holds(platform_moments(w, eq, every_but), f"({eq}) with I_X alpha_X, I = 0.07 1")


def test_E29_one_acceleration_for_every_zone():
    w = world("paper_legs")
    parts = np.stack([a for leg in w.legs for a in (leg.a2, leg.a4)])
    spread = np.linalg.norm(parts - parts.mean(axis=0), axis=1).max(axis=0)
    assert (spread / np.linalg.norm(parts, axis=1).mean(axis=0)).min() > 0.1


# ----------------------------------------------------------------------------- tables and text


def _paper_text() -> str:
    files = sorted(PAPER.glob("000_*.txt")) if PAPER.is_dir() else []
    if not files:
        pytest.skip(f"the paper's text is not in {PAPER}")
    return files[0].read_text()


def _table_path(number: int) -> Path:
    files = sorted(PAPER.glob(f"table{number}_*.csv")) if PAPER.is_dir() else []
    if not files:
        pytest.skip(f"the paper's Table {number} is not in {PAPER}")
    return files[0]


def _caption(text: str, number: int) -> str:
    """The text from Table ``number``'s caption on."""
    match = re.search(rf"Table \({number}\) Friction", text)
    assert match, f"no caption of Table ({number})"
    return text[match.start():]


def _printed_header(text: str, number: int) -> list[str]:
    line = next(li for li in _caption(text, number).splitlines() if li.startswith("POS"))
    return line.split()[1:]


def test_E30_table1_header():
    text = _paper_text()
    title = _caption(text, 1).splitlines()[0]
    assert "moving platform" in title
    header1, header2 = _printed_header(text, 1), _printed_header(text, 2)
    assert all(h.startswith("MfrC") for h in header1)
    assert "MfrC.3" in header1 and "MfrC.3" in header2
    csv_header = pr.read_table(_table_path(1))[0][1:]
    assert csv_header == [f"MfrE{i}" for i in range(1, 7)]


def test_E31_universal_joints_called_spherical():
    text = " ".join(_paper_text().split())
    for phrase in ("Reaction forces and moments for the spherical joints connected the links "
                   "with the base",
                   "between the spherical joint connected with the fixed and the prismatic",
                   "the spherical joints (Ci)"):
        assert phrase in text
    w = world("rigid")
    for leg in w.legs:
        spin_about_n = np.abs(np.einsum("jn,jn->n", leg.omega_L, leg.n))
        assert spin_about_n.max() < 1e-12 * np.linalg.norm(leg.omega_L, axis=0).max()
        assert np.linalg.norm(leg.omega_L, axis=0).min() > 1e-3


def test_E32_table_misprints():
    """The runtime's detector (the only one) finds exactly the cells of E32 in the printed
    tables."""
    found = {(m.table, m.pos, m.column, m.printed, tuple(sorted(m.kinds)))
             for number in (1, 2, 3) for m in paper.find_misprints(number)}
    assert found == PAPER_MISPRINTS


def test_E33_tables_1_2_disagree():
    """By (11)-(13), R^O_Ci = R^O_Ei - F_2i - F_4i, so | |R_Ci| - |R_Ei| | <= |F_2i + F_4i|, and
    with one joint speed for both joints (33)-(34) differ by at most mu r |F_2i + F_4i|."""
    t1, t2 = (pr.read_table(_table_path(n))[1] for n in (1, 2))
    m1 = np.abs(np.array([[float(c) for c in row[1:]] for row in t1]))
    m2 = np.abs(np.array([[float(c) for c in row[1:]] for row in t2]))
    fr, mass = models.reference_platform().friction, 0.5
    a = np.array(PAPER_LEG_ACCELERATION)
    F2, _ = pl.eq17(mass, a, np.zeros(3), np.zeros(3))
    F4, _ = pl.eq17(mass, a, np.zeros(3), np.zeros(3))
    R_E = np.random.default_rng(SEED).normal(0.0, 30.0, (3, 1000))
    R_C = -np.array([pr.residual(t) for t in pl.eq11_13_terms(np.zeros(3), R_E, F2, F4)])
    gap = np.linalg.norm(np.add(F2, F4))
    assert np.abs(np.linalg.norm(R_C, axis=0) - np.linalg.norm(R_E, axis=0)).max() <= gap
    rounding = 2 * 0.0005
    bound = fr.joint_coulomb * fr.joint_radius * gap + rounding
    assert bound < 0.0012
    assert (np.abs(m1 - m2) > bound).sum() == 218
    weight_bound = fr.joint_coulomb * fr.joint_radius * (gap + 2 * mass * 9.81) + rounding
    assert (np.abs(m1 - m2) > weight_bound).sum() == 57


def test_E34_table3_size():
    """For the paper's motion and legs the derived prismatic friction is below 0.01 N; Table 3's
    values imply, by (35) with any sliding speed up to 1 m/s, transverse forces of about 10 N and
    more. The printed (25)-(27), applied to the spherical joints' forces, give friction forces of
    Table 3's size."""
    w = world("paper_setup")
    fr = w.platform.friction
    path = _table_path(3)
    header, rows = pr.read_table(path)
    table = np.abs(np.array([[float(c) for c in row[1:]] for row in rows]))
    lost = [(m.pos - 1, header.index(m.column) - 1) for m in paper.find_misprints(3)
            if "small" in m.kinds]
    sound = np.ones(table.shape, bool)
    sound[tuple(np.array(lost).T)] = False
    ours = np.stack([np.abs(pl.eq35(fr.prismatic_viscous, leg.D_dot, fr.prismatic_coulomb,
                                    leg.R_3)) for leg in w.legs])
    assert ours.max() < 0.01
    implied = (table[sound] - fr.prismatic_viscous * 1.0) / fr.prismatic_coulomb
    assert implied.min() > 9.5
    with_printed = []
    for leg in w.legs:
        U = pl.leg_frame(leg.E, leg.C, leg.E_next, ("E21",))
        comp = np.array(pl.eq25_27(leg.RE_o, U))
        with_printed.append(fr.prismatic_coulomb * np.hypot(comp[0], comp[1]))
    ratio = np.median(with_printed) / np.median(table[sound])
    assert 1 / 3 < ratio < 3


# ----------------------------------------------------------------------------- the record


def test_every_erratum_has_a_test_and_a_row():
    names = [n for n in globals() if n.startswith("test_E")]
    doc = DOC.read_text() if DOC.exists() else ""
    for e in pr.ERRATA:
        assert any(n.startswith(f"test_{e.id}_") for n in names), e.id
        assert re.search(rf"\b{e.id}\b", doc), f"{e.id} is not in docs/reference/errata.md"
    listed = set(re.findall(r"\bE\d\d\b", doc))
    assert listed == {e.id for e in pr.ERRATA}
