"""Identification: recovery of known parameters, what a poor motion cannot reach, implausible
data kept out of the platform file, the command's round trip."""

from __future__ import annotations

import dataclasses

import json

import numpy as np
import pytest
from click.testing import CliRunner

import gsfric
from gsfric.cli import main
from gsfric.errors import InputTypeError
from gsfric.evaluation import state_array
from gsfric.identification import excite, files, validate
from gsfric.identification.parameters import (
    body_from_factor,
    body_standard,
    consistent,
    factor_of_body,
    parameter_set,
)
from gsfric.identification.regressor import Model, structure
from gsfric.identification.settings import WEAK_RELATIVE_STD
from gsfric.models import reference_platform, sinusoidal
from gsfric.platform.description import Platform
from gsfric.platform.text import commented_toml
from gsfric.platform.usable import home_height
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


def test_regressor_of_a_pose_held_still_reaches_only_static_loads():
    """At rest the forces are six static loads: no friction, no inertia acts, and the rank is
    at most six."""
    ps = parameter_set(reference_platform())
    still = sinusoidal(np.arange(50) / 100.0, amplitude=np.zeros(6))
    _, J = Model(ps, state_array(still), still.t).jacobian(ps.prior)
    st = structure(J, np.ones(6), ps.units)
    assert st.rank <= 6
    idle = {n for n, i in zip(ps.names, st.idle) if i}
    assert {"platform.inertia_origin.xx", "platform.inertia_origin.zz",
            "friction.prismatic_viscous", "friction.joint_viscous"} <= idle
    assert not any(st.identifiable[ps.names.index(n)] for n in idle)


def test_compiled_and_difference_columns_agree():
    """The compiled Jacobian's friction columns equal central differences of the forces."""
    ps = parameter_set(reference_platform())
    motion = sinusoidal(np.linspace(0.0, 2.0, 101))
    model = Model(ps, state_array(motion), motion.t)
    F, J = model.jacobian(ps.prior)
    np.testing.assert_array_equal(F, model.forces(ps.prior))
    for name in ("friction.prismatic_coulomb", "friction.joint_viscous"):
        k = ps.names.index(name)
        h = 1e-6
        up, down = ps.prior.copy(), ps.prior.copy()
        up[k] += h
        down[k] -= h
        difference = (model.forces(up) - model.forces(down)) / (2 * h)
        np.testing.assert_allclose(J[:, :, k], difference, rtol=1e-5, atol=1e-6)


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
@pytest.mark.parametrize("change, message", [
    (lambda F: -F, "the load cells' sign is the opposite of gsfric's"),
    # a static load near zero, too small for a reversed sign: a mass no rig has
    (lambda F: F - 1.25 * F.mean(), "implausible result, platform file not written"),
])
def test_forces_of_the_wrong_sign_never_reach_the_platform_file(tmp_path, change, message):
    data, _ = _record(seed=4, samples=600)
    frame = data.frame.copy()
    for i in range(1, 7):
        frame[f"F{i}"] = change(frame[f"F{i}"])
    path = tmp_path / "flipped.csv"
    gsfric.io.write_table(frame, path)
    out = tmp_path / "out"
    run = CliRunner().invoke(main, ["identify", "--measured", str(path), "--out", str(out)])
    assert run.exit_code == 2
    assert message in run.output
    assert not (out / "platform.toml").exists()


@pytest.mark.integration
def test_command_round_trip(tmp_path):
    data, _ = _record(seed=5)
    measured = tmp_path / "measured.csv"
    gsfric.io.write_table(data.frame, measured)
    prior = tmp_path / "prior.toml"
    prior.write_text(_toml(_wrong_prior()))
    check, _ = _record(seed=6, samples=1500)
    second = tmp_path / "second.csv"
    gsfric.io.write_table(check.frame, second)
    out = tmp_path / "out"
    run = CliRunner().invoke(main, ["identify", "--measured", str(measured), "--platform",
                                    str(prior), "--out", str(out), "--validate", str(second)])
    assert run.exit_code == 0, run.output
    validation = json.loads((out / "identification.json").read_text())["validation"]
    assert max(validation["rms_after_N"]) < 1.1 * NOISE < min(validation["rms_before_N"])
    summary = json.loads((out / "identification.json").read_text())
    assert "validation on" in run.output
    identified = Platform.from_toml(out / "platform.toml")
    mass = summary["parameters"]["platform.mass"]
    assert identified.platform.mass == pytest.approx(mass["value"], rel=1e-12)
    assert identified.legs.upper_mass == pytest.approx(
        summary["parameters"]["legs.upper_mass"]["value"], rel=1e-12)
    assert summary["source_sha256"] in (out / "platform.toml").read_text()
    assert abs(mass["value"] - 13.0) < 4 * mass["std"]


def _toml(platform: Platform) -> str:
    return commented_toml(platform)


@pytest.mark.integration
def test_discover_starts_from_the_identified_platform(tmp_path):
    """identify -> discover: the platform file identify writes is discover's starting model
    (the refit's *model* values are the file's, far from the reference platform's)."""
    truth = reference_platform().with_friction(prismatic_coulomb=0.16, prismatic_viscous=30.0)
    data, _ = _record(seed=7, samples=2000, platform=truth)
    measured = tmp_path / "measured.csv"
    gsfric.io.write_table(data.frame, measured)
    identified = tmp_path / "identified"
    run = CliRunner().invoke(main, ["identify", "--measured", str(measured), "--out",
                                    str(identified)])
    assert run.exit_code == 0, run.output
    start = Platform.from_toml(identified / "platform.toml")
    found = tmp_path / "found"
    run = CliRunner().invoke(main, ["discover", "--measured", str(measured), "--platform",
                                    str(identified / "platform.toml"), "--out", str(found),
                                    "--quiet", "--no-plots"])
    assert run.exit_code == 0, run.output
    refit = json.loads((found / "summary.json").read_text())["refit"]["parameters"]
    reference = reference_platform().friction
    for name in ("prismatic_coulomb", "prismatic_viscous"):
        model = refit[name]["model"]
        assert model == pytest.approx(getattr(start.friction, name), rel=1e-12)
        assert abs(model - getattr(truth.friction, name)) < 0.5 * abs(
            getattr(truth.friction, name) - getattr(reference, name))


@pytest.mark.integration
def test_excitation_starts_and_ends_at_rest_within_the_limits():
    result = excite(duration=8.0, rate=100.0, max_speed=0.2, max_acceleration=2.0)
    motion = result.motion
    assert motion.t[-1] == pytest.approx(8.0)
    for rates in (motion.velocity, motion.omega, motion.acceleration, motion.alpha):
        np.testing.assert_allclose(rates[[0, -1]], 0.0, atol=1e-9)
    p = reference_platform()
    lengths = p.leg_lengths(motion.position, motion.rotation)
    assert p.geometry.stroke[0] < lengths.min() and lengths.max() < p.geometry.stroke[1]
    speed = np.gradient(lengths, motion.t, axis=0)
    assert np.abs(speed).max() <= 0.2 * 1.01
    assert result.rank == len(result.expected_std)
    assert np.isfinite(result.condition) and np.isfinite(result.sinusoid_condition)
    # no fit knows a parameter better than the noise over its largest effect allows (the
    # Cramer-Rao bound of the parameter alone, with every force at that effect)
    forces = 6 * len(motion)
    for name, std in result.expected_std.items():
        value = abs(result.prior[name])
        if std is not None and value > 0:
            bound = result.force_noise * value / (np.sqrt(forces) * result.largest_effect[name])
            assert std >= bound * (1 - 1e-9), name


@pytest.mark.integration
def test_excite_command_writes_a_trajectory_simulate_reads(tmp_path):
    out = tmp_path / "traj.csv"
    run = CliRunner().invoke(main, ["excite", "--out", str(out), "--duration", "4",
                                    "--rate", "100"])
    assert run.exit_code == 0, run.output
    assert "condition number" in run.output and "plain sinusoid" in run.output
    motion = gsfric.read_trajectory(out)
    assert len(motion) == 401


@pytest.mark.slow
def test_designed_excitation_identifies_every_parameter_to_5_percent():
    """60 s at 500 Hz, force noise 0.5 % of the static load: every parameter with a non-zero
    true value is within 5 % (relative std), except the prismatic joints' viscous coefficient,
    whose force (0.02 N s/m at most 0.3 m/s) is far below the noise; and the identified model
    predicts a second record to within the noise."""
    design = excite(duration=60.0, rate=500.0)
    true = reference_platform()
    data = synthesize(true, motion=design.motion, noise=design.force_noise, seed=11)
    result = gsfric.identify(data.motion, data.frame.filter(regex="^F").to_numpy(),
                             _wrong_prior())
    truth = parameter_set(true)
    loose = [n for n, v in zip(truth.names, truth.prior)
             if v != 0 and n != "friction.prismatic_viscous"
             and not result.parameters[n].rel_std <= 0.05]
    assert loose == []
    check = synthesize(true, samples=4000, rate=500.0, noise=design.force_noise, seed=12)
    v = validate(result, check.motion, check.frame.filter(regex="^F").to_numpy())
    assert np.all(v.after < 1.05 * design.force_noise)
    assert np.all(v.before > 2 * design.force_noise)


@pytest.mark.slow
def test_95_percent_intervals_contain_the_truth_95_percent_of_the_time():
    truth = parameter_set(reference_platform())
    inside = total = 0
    for seed in range(40):
        data, forces = _record(seed=100 + seed, samples=2000)
        result = gsfric.identify(data.motion, forces, _wrong_prior())
        for name, value in zip(truth.names, truth.prior):
            e = result.parameters[name]
            if e.std is not None:
                inside += abs(e.value - value) <= 1.96 * e.std
                total += 1
    assert 0.91 <= inside / total <= 0.985, inside / total


@pytest.mark.parametrize("noise", [0.0, -1.0, [1.0, 2.0], float("nan")])
def test_a_force_noise_that_is_not_positive_is_refused(noise):
    motion = sinusoidal(np.arange(40) / 100.0)
    with pytest.raises(gsfric.InputError, match="--force-noise"):
        gsfric.identify(motion, np.zeros((40, 6)), force_noise=noise)


@pytest.mark.parametrize("noise", [1e9, 1e-30])
def test_a_force_noise_implausible_against_the_channels_is_refused_as_discover_does(noise):
    """A noise far above a channel's spread (a unit error) or below what a converter
    resolves: refused by name, as ``discover`` refuses it, before any fit."""
    data, forces = _record(1, samples=400)
    with pytest.raises(gsfric.InputError, match=r"--force-noise: F1: a force noise of .* is "
                                                r"implausible against the measured channel"):
        gsfric.identify(data.motion, forces, force_noise=noise)


def test_weakly_determined_parameters_are_named_with_their_effect_against_the_noise():
    """A parameter the record determines to worse than WEAK_RELATIVE_STD of its prior value is
    named once, with the force it moves against the noise; none better determined is."""
    data, forces = _record(3, samples=2000)
    result = gsfric.identify(data.motion, forces, reference_platform())
    weak = {line.split(":")[0]: line for line in result.weak}
    for name, e in result.parameters.items():
        loose = e.std is not None and e.prior != 0 and e.std > WEAK_RELATIVE_STD * abs(e.prior)
        assert (name in weak) == loose, name
    assert weak, "a 4 s record at 0.5 N of noise leaves the viscous friction weak"
    line = weak["friction.prismatic_viscous"]
    assert "N of noise" in line and "needs faster leg motion" in line
    assert all(f"weakly determined: {w}" in result.statement() for w in result.weak)
    assert result.summary()["weak"] == result.weak


@pytest.mark.parametrize("options, message", [
    ({"period": 0.002}, r"period: 0\.002 s at 500 Hz holds 1 samples; .* at least 0\.2 s"),
    ({"rate": 1.0, "duration": 4.0}, r"period: 4 s at 1 Hz holds 4 samples"),
    ({"duration": 1e9}, r"duration: 1e\+09 s at 500 Hz is 500,000,000,001 samples, more than"),
    ({"rate": 1e6, "duration": 600.0}, r"duration: 600 s at 1e\+06 Hz is 600,000,001 samples"),
    ({"period": 4000.0}, (r"period: 4000 s \(the duration of 60 s rounded up to whole "
                          r"periods: 4000 s\) at 500 Hz is 2,000,001 samples")),
])
def test_excite_refuses_a_motion_of_too_few_or_too_many_samples(options, message):
    """A period of a sample or two would be a motion that does not move; a duration of
    billions of samples would exhaust the memory before any output: both refused at once."""
    with pytest.raises(gsfric.InputError, match=message):
        excite(**options)


def _dead_f3(frame):
    frame = frame.copy()
    frame["F3"] = 50.0
    return frame


def _platform_with(**changes):
    platform = reference_platform()
    return dataclasses.replace(platform, **changes)


def _legs_sharing_joints():
    platform = reference_platform()
    g = platform.geometry
    base, top = np.array(g.base_joints, float), np.array(g.platform_joints, float)
    base[1], top[1] = base[0], top[0]
    return dataclasses.replace(platform, geometry=dataclasses.replace(
        g, base_joints=base, platform_joints=top))


def test_excite_moves_about_the_platforms_own_home_pose():
    """A platform twice the reference's size (home 1.5 m up): the design starts and ends at
    its home pose, level with the legs at mid-stroke, and stays within its stroke."""
    platform = reference_platform()
    g = platform.geometry
    big = dataclasses.replace(platform, geometry=dataclasses.replace(
        g, base_joints=2 * np.asarray(g.base_joints), platform_joints=2 * np.asarray(
            g.platform_joints), stroke=(2 * g.stroke[0], 2 * g.stroke[1])))
    design = excite(big, duration=4.0, rate=100.0)
    home = home_height(big)
    assert home > 1.4
    np.testing.assert_allclose(design.motion.position[[0, -1]], [[0, 0, home]] * 2, atol=1e-9)
    lengths = big.leg_lengths(design.motion.position, design.motion.rotation)
    assert big.geometry.stroke[0] < lengths.min() and lengths.max() < big.geometry.stroke[1]
    assert np.ptp(lengths) > 0.1 * (big.geometry.stroke[1] - big.geometry.stroke[0])


def test_excite_says_the_duration_it_made():
    """A duration is rounded up to whole periods: the report says how long the motion is."""
    design = excite(duration=0.001, rate=100.0)
    assert design.motion.t[-1] == pytest.approx(design.period)
    assert design.report().startswith(f"excitation: {design.period:g} s (1 period of "
                                      f"{design.period:g} s: a duration is rounded up")


@pytest.mark.parametrize("platform, options, message", [
    (lambda: _platform_with(gravity=0.0), {},
     r"force_noise: the legs carry no static load at the home pose .*--force-noise"),
    (_legs_sharing_joints, {"force_noise": 0.1}, r"platform at home: 8 of 8 steps are flagged "
                                                 r".*FLAG_SINGULAR"),
    (reference_platform, {"force_noise": 1e9}, r"force_noise: 1e\+09 N is implausible"),
    (reference_platform, {"force_noise": -1.0}, r"force_noise: must be a positive number"),
    (reference_platform, {"max_speed": 1e9}, r"max_speed: 1e\+09 m/s crosses the legs' stroke"),
])
def test_excite_refuses_what_no_rig_has(platform, options, message):
    """A design needs a force noise (the default is a share of the static load: none without
    gravity), a platform the model can evaluate at its home pose, and limits a hexapod of this
    stroke can reach: each refused at once with the field to fix, never a traceback."""
    with pytest.raises(gsfric.InputError, match=message):
        excite(platform(), duration=4.0, rate=100.0, **options)


@pytest.mark.parametrize("change, message", [
    (lambda f: f.drop(columns="F6"), r"bad\.csv: missing column 'F6'"),
    (_dead_f3, r"bad\.csv: F3: constant \(50 N in every row\): a dead channel"),
])
def test_a_bad_validation_record_is_refused_before_the_fit(tmp_path, monkeypatch, change,
                                                           message):
    """--validate's file is read and checked as the measured one is, before the fit: a bad
    one costs no fit."""
    data, _ = _record(seed=6, samples=400)
    good, bad = tmp_path / "good.csv", tmp_path / "bad.csv"
    gsfric.io.write_table(data.frame, good)
    gsfric.io.write_table(change(data.frame), bad)
    monkeypatch.setattr(files, "identify", lambda *a, **k: pytest.fail("fitted first"))
    with pytest.raises(gsfric.InputError, match=message):
        files.identify_file(good, validate_file=bad)


def test_a_prior_effect_the_record_does_not_show_is_removed_and_said_so(tmp_path):
    """A prior with a Stribeck peak on a record without one: the fit removes the peak. A
    parameter that then no longer acts, or acts only with another, is named so, with the
    values the fit moved it between, never as the prior's value kept."""
    data, forces = _record(seed=9, samples=1500)
    prior = reference_platform().with_effect("stribeck", static=2.0, velocity=0.01)
    result = gsfric.identify(data.motion, forces, prior)
    assert result.parameters["effects.stribeck.static"].value < 0.1
    lines = {u.split(":")[0]: u for u in result.unreachable}
    assert any(name.startswith("effects.stribeck.") for name in lines)
    files.write_outputs(result, tmp_path / "out")
    text = (tmp_path / "out" / "platform.toml").read_text()
    for name, e in result.parameters.items():
        if e.std is None and e.moved:
            assert ("the fit moved it from the prior's" in lines[name]
                    or "only in combination" in lines[name]), lines[name]
            assert f"{name} not identified alone (prior {e.prior:.6g};" in text


def test_a_fit_that_does_not_reproduce_the_forces_says_so():
    """From a prior with no masses and no friction the nonlinear fit stops far from the rig
    (2.6 N RMS left on 0.1 N of noise); with the noise estimated from its own residual it
    would look within the noise. The forces' own high-frequency noise does not depend on the
    fit: the statement says the model does not reproduce the forces. A fit from the rig's
    values says nothing of the kind."""
    data = synthesize(samples=2000, rate=200.0, noise=0.1, seed=0)
    forces = data.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()
    zero = reference_platform()
    zero = dataclasses.replace(
        zero, platform=dataclasses.replace(zero.platform, mass=0.0, payload_mass=0.0),
        legs=dataclasses.replace(zero.legs, lower_mass=0.0, upper_mass=0.0),
        friction=dataclasses.replace(zero.friction, joint_viscous=0.0, joint_coulomb=0.0,
                                     prismatic_viscous=0.0, prismatic_coulomb=0.0,
                                     prismatic_seal=0.0))
    good = gsfric.identify(data.motion, forces)
    assert good.misfit == [] and "misfit" not in good.statement()
    far = gsfric.identify(data.motion, forces, zero)
    assert np.sqrt(np.mean(far.residual ** 2)) > 10 * np.sqrt(np.mean(good.residual ** 2))
    assert far.misfit and "the model does not reproduce the forces" in far.statement()
    assert far.summary()["misfit"] == far.misfit


def test_a_dead_load_cell_is_refused_as_discover_refuses_it():
    """A channel that no model effect explains (constant, saturated, held samples) is never
    fitted: identify refuses it with discover's words, before any parameter moves."""
    data, forces = _record(seed=7, samples=600)
    forces = forces.copy()
    forces[:, 2] = 50.0
    with pytest.raises(gsfric.InputError, match=r"F3: constant \(50 N in every row\): a dead"):
        gsfric.identify(data.motion, forces)


def test_the_measured_record_is_no_validation(tmp_path):
    data, _ = _record(seed=6, samples=400)
    gsfric.io.write_table(data.frame, tmp_path / "a.csv")
    gsfric.io.write_table(data.frame, tmp_path / "copy.csv")
    with pytest.raises(gsfric.InputError, match=r"--validate: .*copy\.csv holds the same record"):
        files.identify_file(tmp_path / "a.csv", validate_file=tmp_path / "copy.csv")


def test_a_validation_record_of_the_wrong_sign_is_refused(tmp_path):
    """The second record gets the sign check of the first: reversed load cells are no
    validation of anything."""
    data, forces = _record(seed=8, samples=600)
    result = gsfric.identify(data.motion, forces)
    with pytest.raises(gsfric.InputError, match=r"second\.csv: .*negate F1\.\.F6"):
        validate(result, data.motion, -forces, "second.csv")


@pytest.mark.parametrize("options, error, message", [
    ({"duration": "5"}, InputTypeError, r"duration: expected a number, got '5'"),
    ({"duration": None}, InputTypeError, r"duration: expected a number, got None"),
    ({"seed": -1}, gsfric.InputError, r"seed: must be an integer >= 0, got -1"),
    ({"seed": 1.5}, InputTypeError, r"seed: expected an integer, got 1\.5"),
    ({"sensors": "no"}, InputTypeError, r"sensors: expected True or False, got 'no'"),
    ({"force_noise": True}, InputTypeError, r"force_noise: expected a number, got True"),
])
def test_excite_names_an_argument_of_the_wrong_kind(options, error, message):
    with pytest.raises(error, match=message):
        excite(**options)


def test_a_duration_shorter_than_a_period_is_one_period():
    design = excite(duration=1e-9, rate=100.0)
    assert len(design.motion) == round(design.period * 100.0) + 1


def test_identify_names_an_argument_of_the_wrong_kind_and_the_first_bad_force():
    data, forces = _record(seed=6, samples=400)
    cases = [((None, forces), {}, InputTypeError,
              r"identify: motion must be a gsfric\.Motion, got None"),
             ((data.motion, forces), {"force_noise": "abc"}, InputTypeError,
              r"--force-noise: expected a number \(N\) or six, got 'abc'"),
             ((data.motion, forces), {"force_noise": True}, InputTypeError,
              r"--force-noise: expected a number \(N\) or six, got True"),
             ((data.motion, forces), {"sensors": "no"}, InputTypeError,
              r"sensors: expected True or False, got 'no'")]
    bad = forces.copy()
    bad[3, 2] = np.nan
    cases.append(((data.motion, bad), {}, gsfric.InputError,
                  r"forces\[3\]\[2\]: must be finite, got nan"))
    for args, options, error, message in cases:
        with pytest.raises(error, match=message):
            gsfric.identify(*args, **options)


def test_steps_the_model_flags_are_left_out_of_the_fit_and_said(tmp_path):
    """A stroke that the record leaves for a third of its steps: those steps' forces are not
    the model's (a leg beyond its stroke), left out and counted; the rest identify as a
    whole record does. Most steps flagged: refused, as discover refuses it."""
    data, forces = _record(seed=3, samples=2000)
    lengths = gsfric.evaluate(reference_platform(), data.motion).D
    short = reference_platform().with_geometry(
        stroke=(0.5, float(np.quantile(lengths.max(axis=1), 0.7))))
    result = gsfric.identify(data.motion, forces, short)
    outside = np.any(lengths > short.geometry.stroke[1], axis=1)
    assert result.flagged == np.count_nonzero(outside) and 0 < result.flagged < 1000
    assert result.samples == 2000 - result.flagged
    assert f"left out: {result.flagged} of 2000 steps" in result.statement()
    assert result.summary()["flagged_left_out"] == result.flagged
    whole = gsfric.identify(data.motion, forces)
    mass, same = result.parameters["platform.mass"], whole.parameters["platform.mass"]
    assert abs(mass.value - same.value) < 3 * mass.std
    tight = reference_platform().with_geometry(
        stroke=(0.5, float(np.quantile(lengths.max(axis=1), 0.3))))
    with pytest.raises(gsfric.InputError, match=r"steps are flagged by the model"):
        gsfric.identify(data.motion, forces, tight)


def test_a_parameter_the_fit_leaves_at_its_prior_is_not_said_to_have_moved():
    """Translations only: the inertia does not act; the rows that hold it leave it at the
    prior to rounding, which is no move."""
    t = np.arange(1200) / 200.0
    motion = sinusoidal(t, amplitude=(0.05, 0.04, 0.05, 0.0, 0.0, 0.0))
    forces = gsfric.evaluate(reference_platform(), motion).F
    forces = forces + np.random.default_rng(2).normal(0.0, 0.1, forces.shape)
    result = gsfric.identify(motion, forces)
    lines = [u for u in result.unreachable if u.startswith("platform.inertia_origin.xx")]
    assert lines and "does not act on the forces along this motion" in lines[0]
    assert not result.parameters["platform.inertia_origin.xx"].moved


def test_a_prior_tens_of_times_too_light_is_a_guess_to_correct_not_a_unit_error():
    """The rig weighs 50 times the prior (masses and seals): discover, which trusts its
    platform, refuses the forces as another unit; identify, whose prior is a guess, fits them
    and finds the rig's mass. The forces of a rig of the prior's weight in kN read as N (a
    factor of 1000) are refused."""
    prior = reference_platform()
    heavy = prior.with_body(mass=50 * prior.platform.mass,
                            payload_mass=50 * prior.platform.payload_mass).with_legs(
        lower_mass=50 * prior.legs.lower_mass, upper_mass=50 * prior.legs.upper_mass
    ).with_friction(prismatic_seal=50 * prior.friction.prismatic_seal)
    data = synthesize(heavy, samples=1500, rate=500.0, noise=25.0, seed=5)
    forces = data.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()
    with pytest.raises(gsfric.InputError, match=r"times the model's along the same poses"):
        gsfric.discover(data.motion, forces, prior)
    mass = gsfric.identify(data.motion, forces, prior).parameters["platform.mass"]
    assert abs(mass.value - 50 * 13.0) < 4 * mass.std
    with pytest.raises(gsfric.InputError, match=r"forces in kN read as N"):
        gsfric.identify(data.motion, forces / 50 / 1000, prior)    # the prior's rig, in kN


def test_a_record_the_platforms_model_mostly_flags_is_refused_naming_it(tmp_path):
    data, _ = _record(seed=4, samples=600)
    gsfric.io.write_table(data.frame, tmp_path / "r.csv")
    reference_platform().with_friction(joint_coulomb=0.5).to_toml(tmp_path / "locked.toml")
    with pytest.raises(gsfric.InputError, match=r"r\.csv: \d+ of 600 steps are flagged by the "
                                                r"model, .*FLAG_COUPLING"):
        files.identify_file(tmp_path / "r.csv", tmp_path / "locked.toml")
