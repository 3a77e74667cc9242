"""Self-checks of the Pinocchio reference engine (no gsfric needed)."""

import numpy as np
import pytest

pytest.importorskip("pinocchio")

try:
    from tests.engines import pinocchio_hexapod as ph
except ImportError:
    from engines import pinocchio_hexapod as ph

SEEDS = range(8)
H = 1e-3


def vee(S):
    return np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]]) / 2.0


def d1(f, t, h=H):
    return (f(t - 2 * h) - 8 * f(t - h) + 8 * f(t + h) - f(t + 2 * h)) / (12 * h)


def d2(f, t, h=H):
    return (-f(t - 2 * h) + 16 * f(t - h) - 30 * f(t) + 16 * f(t + h) - f(t + 2 * h)) / (
        12 * h * h
    )


class SmoothMotion:
    """Platform motion with analytic derivatives: sinusoidal translation, two-axis rotation."""

    def __init__(self, rng):
        self.p0 = np.array([0.0, 0.0, 0.6]) + rng.uniform(-0.03, 0.03, 3)
        self.A = rng.uniform(0.01, 0.05, 3)
        self.w = rng.uniform(1.0, 4.0, 3)
        self.phi = rng.uniform(0.0, 2 * np.pi, 3)
        self.k1 = ph._unit(rng.normal(size=3))
        self.k2 = ph._unit(rng.normal(size=3))
        self.b = rng.uniform(0.05, 0.15, 2)
        self.wr = rng.uniform(1.0, 4.0, 2)
        self.c = rng.uniform(0.0, 2 * np.pi, 2)
        self.R0 = ph.rotation_about(ph._unit(rng.normal(size=3)), rng.uniform(-0.1, 0.1))

    def __call__(self, t):
        arg = self.w * t + self.phi
        th = self.b * np.sin(self.wr * t + self.c)
        dth = self.b * self.wr * np.cos(self.wr * t + self.c)
        ddth = -self.b * self.wr**2 * np.sin(self.wr * t + self.c)
        R1 = ph.rotation_about(self.k1, th[0])
        R2 = ph.rotation_about(self.k2, th[1])
        k2w = R1 @ self.k2
        return {
            "position": self.p0 + self.A * np.sin(arg),
            "rotation": R1 @ R2 @ self.R0,
            "velocity": self.A * self.w * np.cos(arg),
            "omega": dth[0] * self.k1 + dth[1] * k2w,
            "acceleration": -self.A * self.w**2 * np.sin(arg),
            "alpha": ddth[0] * self.k1 + ddth[1] * k2w + dth[0] * dth[1] * np.cross(self.k1, k2w),
        }


def test_smooth_motion_derivatives():
    motion = SmoothMotion(np.random.default_rng(0))
    t = 0.37
    s = motion(t)
    np.testing.assert_allclose(d1(lambda x: motion(x)["position"], t), s["velocity"], atol=1e-9)
    np.testing.assert_allclose(d2(lambda x: motion(x)["position"], t), s["acceleration"], atol=1e-7)
    omega = lambda x: vee(d1(lambda y: motion(y)["rotation"], x) @ motion(x)["rotation"].T)
    np.testing.assert_allclose(omega(t), s["omega"], atol=1e-9)
    np.testing.assert_allclose(d1(omega, t), s["alpha"], atol=1e-7)


def test_static_symmetric_massless_legs():
    geom = ph.symmetric_geometry(leg_mass=False)
    r = ph.inverse_dynamics(geom, ph.home_state())
    weight = geom["platform_mass"] * geom["gravity"]
    F = r["F"]
    assert np.all(F > 0)
    np.testing.assert_allclose(F, F[0], rtol=1e-10)
    np.testing.assert_allclose(r["R_E"].sum(axis=0), [0.0, 0.0, weight], atol=1e-10 * weight)
    np.testing.assert_allclose(r["R_E"][:, 2].sum(), weight, rtol=1e-10)
    np.testing.assert_allclose(r["R_E"], F[:, None] * r["u"], atol=1e-10 * weight)
    np.testing.assert_allclose(r["R_C"], r["R_E"], atol=1e-10 * weight)
    np.testing.assert_allclose(r["M_C"], 0.0, atol=1e-10 * weight)


def test_static_symmetric_heavy_legs():
    geom = ph.symmetric_geometry()
    r = ph.inverse_dynamics(geom, ph.home_state())
    g = geom["gravity"]
    weight = geom["platform_mass"] * g
    total = weight + 6 * (geom["lower_mass"] + geom["upper_mass"]) * g
    np.testing.assert_allclose(r["F"], r["F"][0], rtol=1e-10)
    np.testing.assert_allclose(r["M_C"], r["M_C"][0], atol=1e-10 * weight)
    np.testing.assert_allclose(r["R_E"].sum(axis=0), [0.0, 0.0, weight], atol=1e-10 * weight)
    np.testing.assert_allclose(r["R_C"].sum(axis=0), [0.0, 0.0, total], atol=1e-10 * total)


@pytest.mark.parametrize("seed", SEEDS)
def test_platform_newton_euler(seed):
    rng = np.random.default_rng(seed)
    geom = ph.random_geometry(rng)
    state = ph.random_state(rng)
    r = ph.inverse_dynamics(geom, state)

    R, w, al = state["rotation"], state["omega"], state["alpha"]
    m = geom["platform_mass"]
    c = R @ geom["platform_com"]
    a_com = state["acceleration"] + np.cross(al, c) + np.cross(w, np.cross(w, c))
    g_vec = np.array([0.0, 0.0, -geom["gravity"]])
    I_w = R @ geom["platform_inertia"] @ R.T
    scale = m * geom["gravity"]

    force = r["R_E"].sum(axis=0) + m * g_vec
    np.testing.assert_allclose(force, m * a_com, atol=1e-10 * scale)

    com = state["position"] + c
    moment = np.cross(r["E"] - com, r["R_E"]).sum(axis=0)
    np.testing.assert_allclose(moment, I_w @ al + np.cross(w, I_w @ w), atol=1e-10 * scale)


@pytest.mark.parametrize("seed", SEEDS)
def test_massless_legs_are_two_force_members(seed):
    rng = np.random.default_rng(seed)
    geom = ph.symmetric_geometry(leg_mass=False)
    r = ph.inverse_dynamics(geom, ph.random_state(rng))
    scale = geom["platform_mass"] * geom["gravity"]
    np.testing.assert_allclose(r["R_E"], r["F"][:, None] * r["u"], atol=1e-10 * scale)
    np.testing.assert_allclose(r["R_C"], r["R_E"], atol=1e-10 * scale)
    np.testing.assert_allclose(r["M_C"], 0.0, atol=1e-10 * scale)


@pytest.mark.parametrize("seed", SEEDS)
def test_residuals(seed):
    rng = np.random.default_rng(seed)
    geom = ph.random_geometry(rng)
    r = ph.inverse_dynamics(geom, ph.random_state(rng))
    scale = geom["platform_mass"] * geom["gravity"]
    assert r["closure_position"] < 1e-14
    assert r["closure_velocity"] < 1e-12
    assert r["closure_acceleration"] < 1e-11
    assert r["solve_residual"] < 1e-10 * scale
    assert r["moment_offaxis"] < 1e-10 * scale


@pytest.mark.parametrize("seed", SEEDS)
def test_leg_rates_keep_closure(seed):
    rng = np.random.default_rng(seed)
    geom = ph.random_geometry(rng)
    motion = SmoothMotion(rng)
    t = rng.uniform(0.0, 2.0)
    ref = motion(t)
    r = ph.inverse_dynamics(geom, ref)

    def q(x):
        return ph.leg_coordinates(geom, ref, motion(x))

    for k in (-2, -1, 1, 2):
        s = motion(t + k * H)
        assert ph.closure_gap(geom, ref, s, q(t + k * H)) < 1e-14
    np.testing.assert_allclose(q(t), 0.0, atol=1e-15)
    np.testing.assert_allclose(d1(q, t), r["v_legs"], atol=1e-9)
    np.testing.assert_allclose(d2(q, t), r["a_legs"], atol=1e-6)
    np.testing.assert_allclose(r["d_dot"], r["v_legs"][:, 2])


@pytest.mark.parametrize("seed", SEEDS)
def test_leg_newton_euler(seed):
    """R_C, M_C and the whole system's momentum balance from finite-difference leg kinematics."""
    rng = np.random.default_rng(seed)
    geom = ph.random_geometry(rng)
    motion = SmoothMotion(rng)
    t = rng.uniform(0.0, 2.0)
    state = motion(t)
    r = ph.inverse_dynamics(geom, state)
    a1 = geom["universal_axes"]
    g_vec = np.array([0.0, 0.0, -geom["gravity"]])
    ml, mu = geom["lower_mass"], geom["upper_mass"]
    scale = geom["platform_mass"] * geom["gravity"]

    def legs(x):
        return ph.leg_geometry(geom, motion(x))

    def x_lower(x):
        C, _, u, _ = legs(x)
        return C + geom["lower_com"] * u

    def x_upper(x):
        _, E, u, _ = legs(x)
        return E - geom["upper_com"] * u

    def frames(x):
        _, _, u, _ = legs(x)
        return np.array([ph.leg_frame(a1[i], u[i]) for i in range(6)])

    def omega(x):
        dR = d1(frames, x)
        Rl = frames(x)
        return np.array([vee(dR[i] @ Rl[i].T) for i in range(6)])

    a_l = d2(x_lower, t)
    a_u = d2(x_upper, t)
    w = omega(t)
    al = d1(omega, t)
    np.testing.assert_allclose(r["omega_leg"], w, atol=1e-9)
    np.testing.assert_allclose(r["alpha_leg"], al, atol=1e-6)

    C, E, _, _ = legs(t)
    Rl = frames(t)
    newton = r["R_C"] - r["R_E"] + (ml + mu) * g_vec
    np.testing.assert_allclose(newton, ml * a_l + mu * a_u, atol=1e-7 * scale)

    xl, xu = x_lower(t), x_upper(t)
    for i in range(6):
        Il = Rl[i] @ geom["lower_inertia"] @ Rl[i].T
        Iu = Rl[i] @ geom["upper_inertia"] @ Rl[i].T
        dH = (
            np.cross(xl[i] - C[i], ml * a_l[i])
            + np.cross(xu[i] - C[i], mu * a_u[i])
            + (Il + Iu) @ al[i]
            + np.cross(w[i], (Il + Iu) @ w[i])
        )
        applied = (
            np.cross(E[i] - C[i], -r["R_E"][i])
            + np.cross(xl[i] - C[i], ml * g_vec)
            + np.cross(xu[i] - C[i], mu * g_vec)
        )
        M = dH - applied
        np.testing.assert_allclose(r["M_C_vector"][i], M, atol=1e-7 * scale)
        np.testing.assert_allclose(r["M_C"][i], M @ r["n"][i], atol=1e-7 * scale)

    R, wp, alp = state["rotation"], state["omega"], state["alpha"]
    c = R @ geom["platform_com"]
    a_com = state["acceleration"] + np.cross(alp, c) + np.cross(wp, np.cross(wp, c))
    m_total = geom["platform_mass"] + 6 * (ml + mu)
    momentum_rate = geom["platform_mass"] * a_com + (ml * a_l + mu * a_u).sum(axis=0)
    np.testing.assert_allclose(
        r["R_C"].sum(axis=0) + m_total * g_vec, momentum_rate, atol=1e-7 * scale
    )
