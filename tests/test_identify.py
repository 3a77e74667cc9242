"""Identification: recovery of known parameters, what a poor motion cannot reach, implausible
data kept out of the platform file, the command's round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest

import gsfric
from gsfric.identification.parameters import (body_from_factor, body_standard, consistent,
                                              factor_of_body, parameter_set)
from gsfric.identification.regressor import Model
from gsfric.evaluation import state_array
from gsfric.models import reference_platform, sinusoidal
from gsfric.platform.description import Platform
from gsfric.synth import synthesize

NOISE = 0.5


def _record(seed: int, samples: int = 3000, platform=None, motion=None):
    data = synthesize(platform or reference_platform(), samples=samples, rate=500.0,
                      noise=NOISE, seed=seed, motion=motion)
    return data, data.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()


def _wrong_prior():
    p = reference_platform()
    return p.with_body(mass=12.0).with_legs(upper_mass=0.9).with_friction(
        prismatic_coulomb=0.05, prismatic_seal=1.0)


def test_model_of_the_prior_gives_the_platforms_forces():
    """The parameter set packs the prior (payload folded into the body) without changing F."""
    p = reference_platform().with_body(payload_com=[0.01, 0.0, 0.02])
    motion = sinusoidal(np.linspace(0.0, 2.0, 201))
    ps = parameter_set(p)
    F = Model(ps, state_array(motion), motion.t).forces(ps.prior)
    expected = gsfric.Evaluator(p).actuator_forces(state_array(motion))
    np.testing.assert_allclose(F, expected, atol=1e-9)


def test_log_cholesky_round_trip_and_consistency():
    pi = body_standard(reference_platform().with_body(com=[0.01, -0.02, 0.03]))
    np.testing.assert_allclose(body_from_factor(factor_of_body(pi)), pi, atol=1e-12)
    rng = np.random.default_rng(0)
    assert all(consistent(body_from_factor(rng.normal(size=10))) for _ in range(50))
    bad = pi.copy()
    bad[4] = -1.0                           # negative Ixx about the origin
    assert not consistent(bad)


@pytest.mark.integration
def test_identify_recovers_the_true_parameters_within_their_intervals():
    data, forces = _record(seed=1)
    result = gsfric.identify(data.motion, forces, _wrong_prior())
    truth = parameter_set(reference_platform())
    assert result.rank == len(result.parameters)
    misses = [name for name, value in zip(truth.names, truth.prior)
              if abs(result.parameters[name].value - value) > 4 * result.parameters[name].std]
    assert misses == []
    assert np.all(np.abs(result.residual / NOISE - 1) < 0.05)
    assert result.platform.platform.mass > 0


@pytest.mark.integration
def test_a_pose_held_still_names_what_it_cannot_reach():
    t = np.arange(600) / 200.0
    still = sinusoidal(t, amplitude=np.zeros(6))
    data, forces = _record(seed=2, motion=still)
    result = gsfric.identify(data.motion, forces)
    assert result.rank < len(result.parameters)
    unreached = {line.split(":")[0] for line in result.unreachable}
    assert {"friction.prismatic_viscous", "platform.inertia_origin.zz"} <= unreached
    assert any("needs rotations" in line for line in result.unreachable)
    assert not result.parameters["platform.inertia_origin.zz"].identifiable


@pytest.mark.integration
def test_a_motion_without_rotation_cannot_reach_the_inertia():
    t = np.arange(2000) / 500.0
    motion = sinusoidal(t, amplitude=(0.05, 0.05, 0.04, 0.0, 0.0, 0.0),
                        frequency=(0.7, 1.1, 1.3, 0.0, 0.0, 0.0))
    data, forces = _record(seed=3, motion=motion)
    result = gsfric.identify(data.motion, forces)
    for axis in ("xx", "yy", "zz"):
        assert not result.parameters[f"platform.inertia_origin.{axis}"].identifiable
    assert result.parameters["platform.mass"].identifiable


@pytest.mark.integration
def test_forces_of_the_wrong_sign_never_reach_the_platform_file(tmp_path):
    data, forces = _record(seed=4, samples=1500)
    frame = data.frame.copy()
    for i in range(1, 7):
        frame[f"F{i}"] = -frame[f"F{i}"]
    path = tmp_path / "flipped.csv"
    gsfric.io.write_table(frame, path)
    from click.testing import CliRunner
    from gsfric.cli import main
    out = tmp_path / "out"
    run = CliRunner().invoke(main, ["identify", "--measured", str(path), "--out", str(out)])
    assert run.exit_code == 2
    assert "negative mass" in run.output
    assert not (out / "platform.toml").exists()


@pytest.mark.integration
def test_command_round_trip(tmp_path):
    from click.testing import CliRunner
    from gsfric.cli import main
    data, _ = _record(seed=5)
    measured = tmp_path / "measured.csv"
    gsfric.io.write_table(data.frame, measured)
    prior = tmp_path / "prior.toml"
    prior.write_text(_toml(_wrong_prior()))
    out = tmp_path / "out"
    run = CliRunner().invoke(main, ["identify", "--measured", str(measured), "--platform",
                                    str(prior), "--out", str(out)])
    assert run.exit_code == 0, run.output
    summary = json.loads((out / "identification.json").read_text())
    identified = Platform.from_toml(out / "platform.toml")
    mass = summary["parameters"]["platform.mass"]
    assert identified.platform.mass == pytest.approx(mass["value"], rel=1e-12)
    assert identified.legs.upper_mass == pytest.approx(
        summary["parameters"]["legs.upper_mass"]["value"], rel=1e-12)
    assert summary["source_sha256"] in (out / "platform.toml").read_text()
    assert abs(mass["value"] - 13.0) < 4 * mass["std"]


def _toml(platform: Platform) -> str:
    from gsfric.platform.text import commented_toml
    return commented_toml(platform)
