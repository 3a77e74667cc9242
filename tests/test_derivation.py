"""The derivation: every Newton-Euler balance holds for the solved reactions.

The residuals are built from the derivation's own quantities (positions, accelerations,
inertias) but written here body by body, independently of how the solve eliminated unknowns:
the platform, the lower and the upper part of each leg, and each whole leg (the 42 equations of
(2)-(16) are the platform's 6 and the whole legs' 36).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from helpers import chain_values, perturbed_platform, random_states

from derive import kinematics as kin
from derive import legs as lg
from derive import model as mdl
from derive import platform as pf
from derive.vectors import cross
from gsfric import models
from gsfric.evaluation.paper_constants import paper_constants

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out


@pytest.fixture(scope="module")
def kinematic_model():
    return mdl.build("kinematic")


def _relative(residual: np.ndarray, scale: np.ndarray) -> float:
    return float(np.max(np.abs(residual)) / np.max(np.abs(scale)))


def balances(model) -> dict[str, sp.Matrix]:
    """Residual expressions of every body's Newton-Euler equations (zero at equilibrium)."""
    S = model.symbols
    g = S["g_vec"]
    legs = S["legs"]
    out = {}
    R_E = [L.R_E for L in legs]
    E = [L.E for L in legs]
    out["platform (2)-(7)"] = pf.platform_residual(R_E, E, S["p"], S["F_req"], S["M_req"])
    scale = {"platform (2)-(7)": sp.Matrix.vstack(S["F_req"], S["M_req"])}
    for L in legs:
        k = L.k
        u, C = L.u, L.C
        low, up = L.parts
        out[f"leg {k} (11)-(16)"] = lg.leg_residual(L.R_E, L.R_C, L.M_C, u, L.n, L.D, L.F_leg,
                                                    L.K)
        scale[f"leg {k} (11)-(16)"] = sp.Matrix.vstack(L.R_E, L.D * L.R_E)
        axial = L.F0 * u
        # upper part: -R_E at E, R_3 + axial and M_3 from the lower part at P3, gravity
        f_up = -L.R_E + L.R_3 + axial + up.weight_mass * g - up.mass * up.acceleration
        J_up = up.inertia.in_base()
        m_up = (cross(L.E - L.P3, -L.R_E) + L.M_3
                + cross(up.centre - L.P3, up.weight_mass * g - up.mass * up.acceleration)
                - J_up * up.alpha - cross(up.omega, J_up * up.omega))
        out[f"upper part {k} (28)-(32)"] = sp.Matrix.vstack(f_up, m_up)
        scale[f"upper part {k} (28)-(32)"] = sp.Matrix.vstack(L.R_E, L.D * L.R_E)
        # lower part: R_C and M_C n at C, -(R_3 + axial) and -M_3 at P3, gravity
        f_low = L.R_C - L.R_3 - axial + low.weight_mass * g - low.mass * low.acceleration
        J_low = low.inertia.in_base()
        m_low = (L.M_C * L.n + cross(L.P3 - C, -L.R_3 - axial) - L.M_3
                 + cross(low.centre - C, low.weight_mass * g - low.mass * low.acceleration)
                 - J_low * low.alpha - cross(low.omega, J_low * low.omega))
        out[f"lower part {k}"] = sp.Matrix.vstack(f_low, m_low)
        scale[f"lower part {k}"] = sp.Matrix.vstack(L.R_C, L.D * L.R_C)
    return out, scale


@pytest.mark.parametrize("legs_model", ["rigid", "paper"])
def test_every_newton_euler_balance_holds_at_random_states(kinematic_model, rng, legs_model):
    platform = perturbed_platform(rng, legs_model)
    x = random_states(rng, 25)
    res, scale = balances(kinematic_model)
    values = chain_values(platform, x)
    r = kinematic_model.chain.evaluate(values, res)
    s = kinematic_model.chain.evaluate(values, scale)
    assert len(r) == 1 + 3 * 6
    for name in r:
        assert _relative(r[name], s[name]) < 1e-9, name


def test_paper_mode_balances_hold_with_the_paper_constants(rng):
    model = mdl.build("paper")
    platform = models.paper_platform()
    x = random_states(rng, 10)
    res, scale = balances(model)
    values = chain_values(platform, x, K=paper_constants())
    r = model.chain.evaluate(values, res)
    s = model.chain.evaluate(values, scale)
    for name in r:
        assert _relative(r[name], s[name]) < 1e-9, name


def test_symmetric_static_pose_gives_equal_axial_forces_carrying_the_weight(kinematic_model):
    platform = models.reference_platform().with_legs(lower_mass=0.0, upper_mass=0.0,
                                                     lower_inertia=np.zeros((3, 3)),
                                                     upper_inertia=np.zeros((3, 3)))
    x = np.zeros((1, 24))
    x[0, 2] = models.HOME_HEIGHT
    x[0, 3:12] = np.eye(3).ravel()
    out = kinematic_model.chain.evaluate(chain_values(platform, x), {
        "F0": kinematic_model.outputs["F0"], "u": kinematic_model.outputs["u"]})
    F = out["F0"][0]
    u = out["u"][0].reshape(6, 3)
    weight = (platform.platform.mass + platform.platform.payload_mass) * platform.gravity
    assert np.ptp(F) < 1e-9 * abs(F[0])
    assert np.sum(F * u[:, 2]) == pytest.approx(weight, rel=1e-12)


def test_zero_friction_coefficients_give_zero_friction(rng):
    import gsfric

    platform = perturbed_platform(rng).with_friction(
        joint_viscous=0.0, joint_coulomb=0.0, prismatic_viscous=0.0, prismatic_coulomb=0.0)
    motion = models.random_motion(rng, np.linspace(0, 3, 50))
    r = gsfric.evaluate(platform, motion)
    for name in ("MfrE", "MfrC", "Ffr", "MfrE_s", "MfrC_s", "Ffr_s"):
        assert np.all(getattr(r, name) == 0.0), name
    np.testing.assert_array_equal(r.F, r.F0)
    moving = models.reference_platform()
    r2 = gsfric.evaluate(moving, motion)
    assert np.all(r2.MfrE_s < 0) and np.all(r2.Ffr_s <= 0)


def test_rotation_is_the_papers_b_matrix_and_orthonormal():
    a, b, c = sp.symbols("alpha beta gamma", real=True)
    T = kin.rotation_zxz(a, b, c)
    assert sp.simplify(T - kin.paper_b_entries(a, b, c)) == sp.zeros(3, 3)
    assert sp.simplify(T.T * T) == sp.eye(3)
    assert sp.simplify(T.det()) == 1


def test_leg_angular_velocity_has_no_component_along_the_torsion_direction(kinematic_model, rng):
    platform = perturbed_platform(rng)
    x = random_states(rng, 20)
    legs = kinematic_model.symbols["legs"]
    dots = {f"leg{L.k}": sp.Matrix([(L.omega_leg.T * L.n)[0, 0]]) for L in legs}
    out = kinematic_model.chain.evaluate(chain_values(platform, x), dots)
    for name, v in out.items():
        assert np.max(np.abs(v)) < 1e-12, name


def test_leg_angular_velocity_and_acceleration_match_finite_differences(kinematic_model, rng):
    """omega_L turns u at the rate u', and alpha_L is omega_L's time derivative."""
    platform = perturbed_platform(rng)
    h = 1e-5
    t0 = np.sort(rng.uniform(0.5, 4.0, 6))
    motion = models.random_motion(np.random.default_rng(7), np.concatenate([t0 - h, t0, t0 + h]))
    from gsfric.evaluation.evaluator import state_array

    legs = kinematic_model.symbols["legs"]
    outputs = {}
    for L in legs:
        outputs[f"u{L.k}"] = L.u
        outputs[f"w{L.k}"] = L.omega_leg
        outputs[f"al{L.k}"] = L.alpha_leg
    out = kinematic_model.chain.evaluate(chain_values(platform, state_array(motion)), outputs)
    n = t0.size
    for L in legs:
        k = L.k
        u, w, al = out[f"u{k}"], out[f"w{k}"], out[f"al{k}"]
        du = (u[2 * n:] - u[:n]) / (2 * h)
        dw = (w[2 * n:] - w[:n]) / (2 * h)
        np.testing.assert_allclose(np.cross(w[n:2 * n], u[n:2 * n]), du, atol=1e-8)
        np.testing.assert_allclose(al[n:2 * n], dw, atol=1e-6 * max(1.0, np.abs(al).max()))


def test_staleness_hash_covers_exactly_the_modules_that_generate_code(tmp_path):
    """derive/sources.py hashes the modules derive.build imports, and nothing else."""
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    from derive import sources

    root = Path(sources.__file__).resolve().parent
    code = ("import sys, derive.build; print(' '.join(sorted(m.split('.', 1)[1] + '.py' "
            "for m in sys.modules if m.startswith('derive.'))))")
    imported = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              check=True, cwd=root.parent).stdout.split()
    assert sorted(imported) == sorted(sources.GENERATING)
    copy = tmp_path / "derive"
    shutil.copytree(root, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert sources.source_hash(copy) != sources.source_hash(root)   # the runtime's printer
    for name in sources.RUNTIME_GENERATING:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(root.parent / name, tmp_path / name)
    assert sources.source_hash(copy) == sources.source_hash(root)
    (copy / "printed.py").write_text((copy / "printed.py").read_text() + "\n# edited\n")
    assert sources.source_hash(copy) == sources.source_hash(root)
    (copy / "legs.py").write_text((copy / "legs.py").read_text() + "\n# edited\n")
    assert sources.source_hash(copy) != sources.source_hash(root)
    (copy / "legs.py").write_text((root / "legs.py").read_text())
    printer = tmp_path / sources.RUNTIME_GENERATING[0]
    printer.write_text(printer.read_text() + "\n# edited\n")
    assert sources.source_hash(copy) != sources.source_hash(root)
