"""The breakdown of the actuator forces into their parts, and the signed friction columns."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import gsfric
from gsfric import io, models
from gsfric.cli import main
from gsfric.evaluation.breakdown import PARTS


@pytest.fixture(scope="module")
def case():
    platform = models.reference_platform("coupled").with_effect("seal_friction", force=1.0) \
        .with_effect("sensor_bias", b1=0.5)
    motion = models.sinusoidal(np.linspace(0.0, 4.0, 201))
    result = gsfric.evaluate(platform, motion)
    return platform, motion, result, _arrays(result.breakdown())


def _arrays(frame) -> dict:
    """Each part's (N, 6) array of a breakdown frame."""
    return {name: frame[name].to_numpy() for name in (*PARTS, "F")}


def test_breakdown_is_a_frame_by_step_with_a_column_per_part_and_leg(case):
    _, motion, result, parts = case
    frame = result.breakdown()
    assert frame.index.name == "step" and len(frame) == len(motion.t)
    assert list(frame["gravity"].columns) == [1, 2, 3, 4, 5, 6]
    assert np.array_equal(frame["t"].to_numpy(), result.t)
    assert frame.attrs["units"]["t"] == "s"
    assert all(frame.attrs["units"][name] == "N" for name in PARTS)
    assert np.array_equal(frame["prismatic_seal"][3].to_numpy(),
                          parts["prismatic_seal"][:, 2])


def test_parts_add_up_to_the_actuator_force(case):
    _, _, result, parts = case
    total = sum(parts[name] for name in PARTS)
    assert np.allclose(total, result.F, rtol=0, atol=1e-9)
    assert np.array_equal(parts["F"], result.F)


def test_gravity_is_the_static_solve_and_payload_its_weight_at_rest(case):
    platform, motion, _, parts = case
    zero = np.zeros_like(motion.velocity)
    at_rest = gsfric.Motion.from_arrays(motion.t, motion.position, motion.rotation, zero, zero,
                                        zero, zero.copy())
    still = _arrays(gsfric.evaluate(platform, at_rest).breakdown())
    assert np.allclose(still["inertia"], 0.0, atol=1e-9)
    assert np.allclose(still["gravity"], parts["gravity"], atol=1e-12)
    # at rest the legs' axial forces carry the weights: the vertical parts add up to m g
    u_z = gsfric.evaluate(platform, at_rest).u[:, :, 2]
    payload_weight = platform.platform.payload_mass * platform.gravity
    lift = np.sum(still["payload"] * u_z, axis=1)
    # the payload's weight is carried by the axial forces (transverse parts are unchanged)
    assert np.allclose(lift, payload_weight, rtol=0.05)
    assert np.all(np.abs(parts["inertia"]).max(axis=0) > 1e-3)


def test_friction_parts_are_the_model_outputs(case):
    platform, _, result, parts = case
    assert np.array_equal(parts["joint_friction"], result.F_joint)
    assert np.abs(parts["joint_friction"]).max() > 0.1          # coupled model carries it
    assert np.all(parts["prismatic_coulomb"] == 0.0)             # (35) with R_3: paper model
    # friction opposes the sliding: the actuator pushes harder while the leg extends
    assert np.all(parts["prismatic_bushing"] * result.D_dot >= -1e-12)
    assert np.all(parts["prismatic_seal"] * result.D_dot >= -1e-12)
    # effects: the seal_friction effect (1 N against the motion) and the 0.5 N bias of F1
    moving = np.abs(result.D_dot[:, 0]) > 1e-2
    assert np.allclose(parts["effects"][moving, 0],
                       0.5 + np.sign(result.D_dot[moving, 0]) * 1.0, atol=1e-3)
    # every leg: an expected value that does not come from the remainder F - (other parts),
    # so the parts' sum is checked against the effects' own size
    sliding = np.abs(result.D_dot) > 1e-2
    expected = np.sign(result.D_dot) * 1.0 + np.array([0.5, 0, 0, 0, 0, 0])
    assert sliding.any(axis=0).all()
    assert np.allclose(parts["effects"][sliding], expected[sliding], atol=1e-3)


def test_signed_friction_columns(case):
    _, _, result, _ = case
    frame = result.to_frame()
    for i in range(1, 7):
        assert np.array_equal(frame[f"Ffr{i}"], result.Ffr[:, i - 1])
        assert np.all(frame[f"Ffr{i}"] * result.D_dot[:, i - 1] <= 1e-12)
        assert np.all(frame[f"Ffr_s{i}"] <= 0.0)   # the paper's negative magnitudes stay
        for j, ax in enumerate("xyz"):
            assert np.array_equal(frame[f"MfrE{ax}{i}"], result.MfrE[:, i - 1, j])
            assert np.array_equal(frame[f"MfrC{ax}{i}"], result.MfrC[:, i - 1, j])
    # the vectors oppose the relative rotation: negative power
    assert np.all(np.einsum("nki,nki->nk", result.MfrC, result.omega_leg) <= 1e-12)


def test_simulate_breakdown_option(tmp_path):
    motion = models.sinusoidal(np.linspace(0.0, 2.0, 201))
    traj = tmp_path / "motion.csv"
    io.write_table(motion.to_frame(), traj)
    out, parts_file = tmp_path / "forces.csv", tmp_path / "parts.csv"
    run = CliRunner().invoke(main, ["simulate", "--trajectory", str(traj), "--out", str(out),
                                    "--breakdown", str(parts_file)])
    assert run.exit_code == 0, run.output
    forces, parts = pd.read_csv(out), pd.read_csv(parts_file)
    assert len(parts) == len(forces)
    for i in range(1, 7):
        total = sum(parts[f"{name}{i}"] for name in PARTS)
        assert np.allclose(total, forces[f"F{i}"], atol=1e-6)
    run = CliRunner().invoke(main, ["simulate", "--trajectory", str(traj), "--out",
                                    str(tmp_path / "p.csv"), "--mode", "paper",
                                    "--breakdown", str(parts_file)])
    assert run.exit_code == 2
    assert "--breakdown: only in the kinematic mode" in run.stderr
    assert not (tmp_path / "p.csv").exists()
