"""The coupled friction model: bushings, per-axis universal joints, the fixed-point solve.

* closed form: the bushings of a leg under a transverse load are a beam on two supports;
* the coupled solve converges within ``coupled.N_ITERATIONS`` iterations for joint friction
  ``mu r`` up to ``MU_R_CONVERGED`` on random platforms (hypothesis), and flags the steps beyond
  (``mu r = MU_R_LOCKING``);
* its result is a fixed point: the friction recomputed from the reported reactions by the
  independent friction map is the friction the reactions were solved with;
* the paper model is untouched by it: the paper's post-hoc friction, frictionless reactions;
* a platform file without ``[friction] model`` keeps the paper's meaning.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from helpers_validation import random_platform
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gsfric
from derive import bushing, coupled, prismatic
from gsfric import models
from gsfric.commands.platform import platform_template
from gsfric.compiled import native
from gsfric.errors import InputError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import COUPLING_TOLERANCE, FLAG_COUPLING
from gsfric.evaluation.parameters import effect_vector, parameter_vector

MU_R_CONVERGED = 0.006
"""m: joint friction mu r up to which the fixed point converges to COUPLING_TOLERANCE (with its
Anderson steps; the plain iteration of as many steps reaches only about 0.004)."""
MU_R_LOCKING = 0.05
"""m: joint friction mu r at which the fixed point does not converge on the reference motion."""


def _motion(seed: int, n: int = 60):
    return models.random_motion(np.random.default_rng(seed), np.linspace(0.0, 3.0, n))


def test_bushings_are_a_beam_on_two_supports():
    """A weightless rod at rest, a transverse load P at its end E (distance D from C), bushings
    at s_a and s_b = s_a + b: N_b = -P (D - s_a) / b, N_a = P (D - s_b) / b (on the rod)."""
    u = sp.Matrix([0, 0, 1])
    D, s_a, b, k3 = 0.8, 0.25, 0.1, 0.5
    load = sp.Matrix([3.0, -2.0, 0])          # external transverse load on the rod at E, N
    R_E = -load                               # the leg's force on the platform
    _, R_3, M_3 = prismatic.upper_part_loads(R_E, sp.zeros(3, 1), sp.zeros(3, 1), u, D,
                                             D - 0.2, k3 * D)
    N_a, N_b = bushing.bushing_forces(R_3, M_3, u, s_a - k3 * D, b)
    expected_b = -load * (D - s_a) / b
    expected_a = load * (D - (s_a + b)) / b
    assert float((N_b - expected_b).norm()) < 1e-12
    assert float((N_a - expected_a).norm()) < 1e-12
    # the rod's equilibrium: the bushings balance the load and its moment about C
    assert float((N_a + N_b + load).norm()) < 1e-12
    moment = s_a * u.cross(N_a) + (s_a + b) * u.cross(N_b) + D * u.cross(load)
    assert float(moment.norm()) < 1e-12


def test_bushing_friction_is_coulomb_on_both_bushings_plus_seal_and_viscous():
    N_a, N_b = sp.Matrix([3.0, 4.0, 0]), sp.Matrix([0, 0.6, 0.8])
    parts = bushing.bushing_friction_parts(0.2, N_a, N_b, 5.0, 0.1, 2.0, 1.0)
    assert [float(p) for p in parts] == pytest.approx([-1.0, -0.1 * (5.0 + 1.0), -2.0])
    parts = bushing.bushing_friction_parts(-0.2, N_a, N_b, 5.0, 0.1, 2.0, -1.0)
    assert [float(p) for p in parts] == pytest.approx([1.0, 0.1 * 6.0, 2.0])


def _coupled(platform, mu_r):
    return platform.with_friction(model="coupled", joint_radius=0.05,
                                  joint_coulomb=mu_r / 0.05)


def _friction_map(platform, result):
    """The friction of the reported reactions, from the separate friction map."""
    f = native.get("friction")
    ins = [result.R_E, result.R_C, result.R_3, result.M_3, result.omega_rel,
           result.omega_leg, result.D_dot, result.D, result.u]
    n = len(result)
    ins = [np.ascontiguousarray(a.reshape(n, -1)) for a in ins]
    return f(ins + [parameter_vector(platform), effect_vector(platform)])


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), mu_r=st.floats(0.0, MU_R_CONVERGED))
def test_fixed_point_converges_on_random_platforms(seed, mu_r):
    platform = _coupled(random_platform(np.random.default_rng(seed)), mu_r)
    result = gsfric.evaluate(platform, _motion(seed), strict=False)
    assert not np.any(result.flag & FLAG_COUPLING)
    limit = COUPLING_TOLERANCE * (1.0 + np.abs(result.F0))
    assert np.all(np.abs(result.coupling_change) <= limit)
    # a fixed point: friction from the reported reactions is the friction they carry
    again = _friction_map(platform, result)
    scale = 1.0 + np.abs(result.F0).max()
    for name in ("MfrE", "MfrC"):
        moment = again[name].reshape(result.arrays[name].shape)
        # moments change with the reactions by mu r per newton: the iteration's last step
        assert np.max(np.abs(moment - result.arrays[name])) <= 10 * COUPLING_TOLERANCE * scale
    assert np.allclose(again["Ffr"], result.Ffr, rtol=0, atol=1e-5 * scale)


def test_locking_friction_is_flagged():
    platform = _coupled(models.reference_platform("coupled"), MU_R_LOCKING)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = gsfric.evaluate(platform, _motion(3))
    assert np.any(result.flag & FLAG_COUPLING)
    converged = gsfric.evaluate(_coupled(models.reference_platform("coupled"), 0.002), _motion(3))
    assert not np.any(converged.flag & FLAG_COUPLING)


def test_coupled_friction_reaches_the_actuators():
    """The reference platform on a smooth motion: joint friction changes F by newtons, not by
    the 0.01 N of the post-hoc model, and the prismatic friction is bushing + seal + viscous."""
    motion = models.sinusoidal(np.linspace(0.0, 10.0, 501))
    coupled_ = gsfric.evaluate(models.reference_platform("coupled"), motion)
    paper = gsfric.evaluate(models.reference_platform("paper"), motion)
    assert np.abs(coupled_.F_joint).max() > 0.5
    assert np.all(paper.F_joint == 0.0)
    assert np.allclose(coupled_.Ffr, coupled_.Ffr_viscous + coupled_.Ffr_bushing
                       + coupled_.Ffr_seal + coupled_.Ffr_effects, atol=1e-12)
    assert np.all(coupled_.Ffr_coulomb == 0.0)
    assert np.allclose(paper.Ffr, paper.Ffr_viscous + paper.Ffr_coulomb + paper.Ffr_seal
                       + paper.Ffr_effects, atol=1e-12)
    # the seal alone: 2 N against the motion, so |Ffr| > 2 N - viscous wherever the leg moves
    moving = np.abs(coupled_.D_dot) > 1e-2
    assert np.all(np.abs(coupled_.Ffr_seal[moving]) > 1.99)
    assert np.allclose(coupled_.F, coupled_.F0 + coupled_.F_joint - coupled_.Ffr, atol=1e-9)


def test_paper_model_is_the_post_hoc_evaluation():
    """Paper model: reactions frictionless, friction from them, F = F0 - Ffr (no effects)."""
    platform = models.reference_platform("paper")
    result = gsfric.evaluate(platform, _motion(5))
    frictionless = gsfric.evaluate(platform.with_friction(joint_coulomb=0.0, joint_viscous=0.0,
                                                          prismatic_coulomb=0.0,
                                                          prismatic_viscous=0.0,
                                                          prismatic_seal=0.0), _motion(5))
    for name in ("R_E", "R_C", "M_C", "R_3", "M_3", "F0"):
        assert np.array_equal(result.arrays[name], frictionless.arrays[name]), name
    assert np.allclose(result.F, result.F0 - result.Ffr, rtol=0, atol=1e-12)
    again = _friction_map(platform, result)
    assert np.allclose(again["MfrC"].reshape(-1, 6, 3), result.MfrC, rtol=0, atol=1e-13)


def test_universal_joint_friction_acts_per_bearing_axis():
    """Coupled model: M_frC lies along a_1 and a_2, each component opposing its own axis speed;
    the paper's vector form is antiparallel to omega_L instead."""
    platform = models.reference_platform("coupled").with_friction(joint_viscous=0.0)
    result = gsfric.evaluate(platform, _motion(7))
    a1 = platform.geometry.universal_axes[None]
    u = result.u
    a2 = np.cross(a1, u)
    a2 /= np.linalg.norm(a2, axis=2, keepdims=True)
    n = np.cross(a2, a1)
    M, w = result.MfrC, result.omega_leg
    assert np.max(np.abs(np.einsum("nki,nki->nk", M, n))) < 1e-12
    for a in (a1, a2):
        Ma = np.einsum("nki,nki->nk", M, np.broadcast_to(a, M.shape))
        wa = np.einsum("nki,nki->nk", w, np.broadcast_to(a, M.shape))
        fast = np.abs(wa) > 1e-2
        assert np.all(Ma[fast] * wa[fast] < 0)
        load = np.linalg.norm(np.cross(np.broadcast_to(a, M.shape), result.R_C), axis=2)
        expected = platform.friction.joint_coulomb * platform.friction.joint_radius * load
        assert np.allclose(np.abs(Ma[fast]), expected[fast], rtol=1e-3)


def test_platform_file_without_friction_model_keeps_the_paper_meaning(tmp_path):
    platform = models.reference_platform("coupled")
    path = tmp_path / "p.toml"
    platform.to_toml(path)
    text = path.read_text()
    assert 'model = "coupled"' in text
    assert gsfric.Platform.from_toml(path) == platform
    old = "\n".join(line for line in text.splitlines() if line != 'model = "coupled"')
    path.write_text(old)
    assert gsfric.Platform.from_toml(path).friction.model == "paper"
    path.write_text(text.replace('model = "coupled"', 'model = "sticky"'))
    with pytest.raises(InputError, match=r"friction\.model: expected one of 'paper', 'coupled'"):
        gsfric.Platform.from_toml(path)
    path.write_text(text.replace("bushing_spacing = 0.1", "bushing_spacing = 0.0"))
    with pytest.raises(InputError, match=r"friction\.bushing_spacing"):
        gsfric.Platform.from_toml(path)


def test_defaults_and_written_files_name_their_model(tmp_path):
    """The physical default is the coupled model, the paper's platform keeps the paper's, and
    every platform file gsfric writes states its model (a file without it means "paper")."""

    assert models.reference_platform().friction.model == "coupled"
    assert models.reference_platform() == models.reference_platform("coupled")
    assert models.paper_platform().friction.model == "paper"
    for platform, model in ((models.reference_platform(), "coupled"),
                            (models.paper_platform(), "paper")):
        path = tmp_path / f"{model}.toml"
        platform.to_toml(path)
        friction = path.read_text().split("[friction]", 1)[1]
        assert f'model = "{model}"' in friction.split("\n[", 1)[0]
    template = tmp_path / "template.toml"
    template.write_text(platform_template())
    assert 'model = "coupled"' in template.read_text().split("[friction]", 1)[1]
    assert gsfric.Platform.from_toml(template).friction.model == "coupled"


def test_actuator_hot_path_equals_the_full_evaluation():
    platform = models.reference_platform("coupled")
    motion = _motion(11, 40)
    F = Evaluator(platform).actuator_forces(state_array(motion))
    assert np.allclose(F, gsfric.evaluate(platform, motion).F, rtol=1e-13, atol=1e-11)


def test_iterations_stated_in_the_docs():
    page = Path(__file__).resolve().parents[1] / "docs" / "explanation" / "friction.md"
    text = page.read_text()
    assert f"{coupled.N_ITERATIONS} iterations" in text
    assert f"mu r <= {MU_R_CONVERGED}" in text


@pytest.mark.parametrize("model", [1, 0])
def test_friction_loads_carry_the_moments_and_their_metric(model):
    """The solve iterates on the friction loads: the moments are affine in them, their value
    at the loads of given reactions is the moment formula's, and the squared norm of a change
    of the moments is the weighted sum of the loads' squared changes (the Anderson step's inner
    product), for the per-axis (coupled) and the vector (paper) universal joint."""
    rng = np.random.default_rng(5)

    def vec(scale=1.0):
        return sp.Matrix(rng.normal(size=3) * scale)

    u = vec()
    u = u / u.norm()
    a1 = vec()
    a1 = a1 / a1.norm()
    a2 = a1.cross(u)
    a2 = a2 / a2.norm()
    terms = coupled.joint_friction_terms(lambda name, value, latex=None: value, vec(0.3),
                                         vec(0.2), a1, a2, 0.7, 0.04, 0.05, 0.01, model)
    R_E, R_C = vec(500.0), vec(500.0)
    loads = coupled.joint_friction_loads(terms, R_E, R_C)
    assert len(loads) == (3 if model == 1 else 2)   # |R_E|, then |a_j x R_C| or |R_C|
    direct = coupled.joint_friction_moments(terms, R_E, R_C)
    from_loads = coupled.joint_friction_from_loads(terms, loads)
    for a, b in zip(direct, from_loads):
        assert np.allclose(np.array(a, float), np.array(b, float), rtol=1e-14, atol=1e-12)
    other = [x + rng.normal() * 10.0 for x in loads]
    ME0, MC0 = coupled.joint_friction_from_loads(terms, loads)
    ME1, MC1 = coupled.joint_friction_from_loads(terms, other)
    change = float(((ME1 - ME0).norm() ** 2 + (MC1 - MC0).norm() ** 2).evalf())
    weights = coupled.joint_friction_weights(terms)
    weighted = float(sum(w * (x - y) ** 2 for w, x, y in zip(weights, other, loads)).evalf())
    assert change > 0 and abs(weighted - change) <= 1e-12 * change
