"""The compiled functions against the lambdified SymPy chain, Jacobians, staleness, fallback."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from helpers import chain_values, numpy_flags, perturbed_platform, random_states, with_every_effect
from scipy.spatial.transform import Rotation

from derive import build as dbuild
from derive import effects as fx
from derive import model as mdl
from gsfric import models
from gsfric.cli import main
from gsfric.compiled import native
from gsfric.compiled.functions import _tuples_readable
from gsfric.compiled.manifest import function as manifest_function
from gsfric.compiled.state import state_layout, state_of
from gsfric.errors import GsfricError, InputError
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import FLAG_NONFINITE, FLAG_ROTATION
from gsfric.evaluation.paper_constants import paper_constants
from gsfric.evaluation.parameters import _slots, effect_vector, jacobian_parameters
from gsfric.evaluation.result import DETAILS
from gsfric.platform.catalog import SENSOR, describe, parameter_names, sensor_parameters
from gsfric.trajectory import Motion

ROOT = Path(__file__).resolve().parents[1]


def _relative_error(a, b, reference=None):
    """max |a - b| relative to the largest |b| (or |reference|)."""
    scale = max(np.max(np.abs(b if reference is None else reference)), 1e-300)
    return np.max(np.abs(a - b)) / scale


@pytest.mark.integration  # the whole symbolic chain evaluated by SymPy
@pytest.mark.parametrize("mode, model", [("kinematic", "paper"), ("kinematic", "coupled"),
                                         ("paper", "paper")])
def test_compiled_equals_lambdified_sympy_at_random_states(rng, mode, model):
    """Each friction model runs the function derived with it fixed (eval_posthoc,
    eval_coupled): against the generic symbolic chain, the model read from P."""
    platform = with_every_effect(rng, perturbed_platform(rng, "paper" if mode == "paper"
                                                       else "rigid"))
    platform = platform.with_friction(model=model)
    x = random_states(rng, 40)
    model = mdl.build(mode)
    K = paper_constants() if mode == "paper" else None
    expected = model.chain.evaluate(chain_values(platform, x, K=K), model.outputs)
    ev = Evaluator(platform, mode=mode)
    got = ev._full([x, ev.P, ev.Q] + ([ev.K] if K is not None else []))
    assert set(got) == set(expected)
    for name in expected:
        # the last change of a converged iteration is rounding: measured against F0
        reference = expected["F0"] if name == "coupling_change" else expected[name]
        assert _relative_error(got[name], expected[name], reference) < 1e-10, name


def test_friction_map_equals_the_friction_of_the_full_map(rng):
    platform = with_every_effect(rng, perturbed_platform(rng))
    x = random_states(rng, 30)
    ev = Evaluator(platform)
    full = ev._full([x, ev.P, ev.Q])
    names = ["R_E", "R_C", "R_3", "M_3", "omega_rel", "omega_leg", "D_dot", "D", "u"]
    fric = native.get("friction")([full[n] for n in names] + [ev.P, ev.Q])
    for name in ("MfrE", "MfrC", "Ffr", "MfrE_s", "MfrC_s", "Ffr_s"):
        assert _relative_error(fric[name], full[name]) < 1e-12, name
    reactions = native.get("reactions")([x, ev.P, ev.Q])
    for name, value in reactions.items():
        assert _relative_error(value, full[name]) < 1e-12, name


def test_actuator_map_equals_the_full_map_also_on_two_threads(rng):
    platform = with_every_effect(rng, perturbed_platform(rng))
    x = random_states(rng, 1001)
    ev = Evaluator(platform, n_threads=2)
    full = ev._full([x, ev.P, ev.Q])
    np.testing.assert_allclose(ev.actuator_forces(x), full["F"], rtol=1e-12, atol=1e-12)
    out = np.empty((x.shape[0], 6))
    assert ev.actuator_forces(x, out=out) is out


@pytest.mark.parametrize("model", ["paper", "coupled"])
def test_fixed_model_functions_equal_the_generic_ones(rng, model):
    """A platform of each friction model runs the functions derived with its model fixed
    (no fixed-point iterations for the paper's): every output equals the generic function's,
    which reads the model from P, and the fixed actuator map equals the fixed full map's F."""
    platform = with_every_effect(rng, perturbed_platform(rng)).with_friction(model=model)
    x = random_states(rng, 203)
    ev = Evaluator(platform)
    suffix = "posthoc" if model == "paper" else "coupled"
    assert ev._full.name == f"eval_{suffix}" and ev._actuator == f"actuator_{suffix}"
    fixed = ev._full([x, ev.P, ev.Q])
    generic = native.get("eval")([x, ev.P, ev.Q])
    assert set(fixed) == set(generic)
    for name, value in generic.items():
        # the last change of a converged iteration is rounding: measured against F0
        reference = generic["F0"] if name == "coupling_change" else value
        assert _relative_error(fixed[name], value, reference) < 1e-12, name
    F = ev.actuator_forces(x)
    np.testing.assert_allclose(F, fixed["F"], rtol=1e-12, atol=1e-12)
    P = np.tile(ev.P, (x.shape[0], 1))
    np.testing.assert_allclose(ev.actuator_forces(x, P=P), F, rtol=1e-12, atol=1e-12)
    P[::2, _model_slot()] = 1.0 - P[0, _model_slot()]                # mixed: the generic map
    mixed = ev.actuator_forces(x, P=P)
    other = Evaluator(platform.with_friction(model="coupled" if model == "paper" else "paper"))
    np.testing.assert_allclose(mixed[1::2], F[1::2], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(mixed[::2], other.actuator_forces(x[::2]), rtol=1e-12,
                               atol=1e-12)
    assert dbuild.FIXED_MODELS[suffix] == ev.P[_model_slot()]


def _model_slot() -> int:

    return next(start for name, start, _ in _slots("eval", "P")[1] if name == "friction_model")


def test_paper_and_coupled_models_agree_without_joint_and_bushing_friction(rng):
    """Without joint friction and with no Coulomb friction in the prismatic joint the two
    models describe the same mechanism: the paper's function (no iterations) and the coupled
    one (six of them) give the same forces and reactions; with joint friction they differ."""
    base = with_every_effect(rng, perturbed_platform(rng))
    x = random_states(rng, 101)
    out = {}
    for model in ("paper", "coupled"):
        for joint in (0.0, 0.04):
            platform = base.with_friction(model=model, joint_coulomb=joint,
                                          joint_viscous=joint / 2, prismatic_coulomb=0.0)
            ev = Evaluator(platform)
            out[model, joint] = ev._full([x, ev.P, ev.Q])
    for name in ("F", "F0", "Ffr", "R_E", "R_C", "M_C", "R_3", "M_3", "F_joint"):
        scale = max(np.abs(out["paper", 0.0][name]).max(), 1.0)
        np.testing.assert_allclose(out["coupled", 0.0][name], out["paper", 0.0][name],
                                   rtol=0, atol=1e-11 * scale, err_msg=name)
    assert np.abs(out["coupled", 0.0]["F_joint"]).max() == 0.0
    assert np.abs(out["coupled", 0.04]["F"] - out["paper", 0.04]["F"]).max() > 1e-3


def test_parameter_jacobian_equals_finite_differences(rng):
    platform = with_every_effect(rng, perturbed_platform(rng))
    x = random_states(rng, 20)
    ev = Evaluator(platform)
    F, dF = ev.jacobian(x)
    names = jacobian_parameters()
    assert dF.shape == (20, 6, len(names))
    np.testing.assert_allclose(F, ev.actuator_forces(x), rtol=1e-12, atol=1e-12)
    p_layout = {b["name"]: b["offset"] for b in
                json.loads((ROOT / "generated" / "manifest.json").read_text())
                ["functions"][0]["inputs"][1]["layout"]}
    q_names = [n for n in names if "." in n]
    for k, name in enumerate(names):
        P, Q = ev.P.copy(), ev.Q.copy()
        if "." in name:
            vec, idx = Q, q_names.index(name)
        else:
            vec, idx = P, p_layout[name]
        h = 1e-6 * max(1.0, abs(vec[idx]))
        vec[idx] += h
        Fp = ev.actuator_forces(x, P=P, Q=Q)
        vec[idx] -= 2 * h
        Fm = ev.actuator_forces(x, P=P, Q=Q)
        fd = (Fp - Fm) / (2 * h)
        scale = max(np.max(np.abs(fd)), np.max(np.abs(dF[:, :, k])), 1e-8)
        assert np.max(np.abs(fd - dF[:, :, k])) < 1e-5 * scale + 1e-9, name


def test_the_jacobian_where_a_friction_level_is_zero_is_the_rising_one():
    """The Coulomb level of the catalog's prismatic effects is max(0, level). Far above its
    speed a Stribeck term is 0, so with the other effects at their default 0 the level is 0:
    the Jacobian of the parameters that grow it from there is the one-sided derivative upward
    (the direction a fit from zero takes), at every step and in every build."""
    platform = models.reference_platform().with_effect("stribeck", static=2.0, velocity=0.01)
    x = state_array(models.sinusoidal(np.linspace(0.0, 40.0, 4000)))
    ev = Evaluator(platform)
    F, dF = ev.jacobian(x)
    names = jacobian_parameters()
    q_names = [n for n in names if "." in n]
    for name in ("seal_friction.force", "bushing_friction.coefficient"):
        Q = ev.Q.copy()
        assert Q[q_names.index(name)] == 0.0
        h = 1e-6
        Q[q_names.index(name)] = h
        rising = (ev.actuator_forces(x, Q=Q) - F) / h
        k = names.index(name)
        scale = np.max(np.abs(rising))
        assert np.max(np.abs(rising - dF[:, :, k])) < 1e-5 * scale, name


def test_parameters_vary_per_step(rng):
    platform = perturbed_platform(rng)
    x = random_states(rng, 10)
    ev = Evaluator(platform)
    P = np.tile(ev.P, (10, 1))
    P[5:, 0] *= 2.0  # gravity doubled on the second half
    F = ev.actuator_forces(x, P=P)
    F_ref = Evaluator(platform.replace(gravity=2 * platform.gravity)).actuator_forces(x[5:])
    np.testing.assert_allclose(F[5:], F_ref, rtol=1e-13)
    np.testing.assert_allclose(F[:5], ev.actuator_forces(x[:5]), rtol=1e-13)


def test_import_gsfric_works_with_sympy_blocked():
    code = ("import sys; sys.modules['sympy'] = None\n"
            "import numpy as np, gsfric\n"
            "r = gsfric.evaluate(gsfric.reference_platform(), gsfric.models.paper_motion())\n"
            "assert r.F.shape == (40, 6) and np.isfinite(r.F).all()\n"
            "assert 'sympy' not in [m.split('.')[0] for m in sys.modules if sys.modules[m]]\n"
            "print('ok')")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "ok"


def test_generated_is_up_to_date_with_derive():
    assert dbuild.is_stale() is None, "generated/ is stale: run `gsfric derive`"


def test_check_detects_a_changed_derive_source(tmp_path, monkeypatch):
    files = {p.name: p.read_bytes() for p in (ROOT / "generated").iterdir() if p.is_file()}
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    assert dbuild.is_stale(tmp_path) is None
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    manifest["source_hash"] = "0" * 64
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    assert "derive/ changed" in dbuild.is_stale(tmp_path)
    (tmp_path / "manifest.json").write_bytes(files["manifest.json"])
    (tmp_path / "gsfric_model.c").write_bytes(files["gsfric_model.c"] + b"\n")
    assert "gsfric_model.c" in dbuild.is_stale(tmp_path)


@pytest.mark.integration
def test_regeneration_is_byte_identical():
    fresh = dbuild.generate()
    for name, data in fresh.items():
        assert (ROOT / "generated" / name).read_bytes() == data, name


def test_cli_derive_check_exits_zero_when_fresh():


    result = CliRunner().invoke(main, ["derive", "--check"])
    assert result.exit_code == 0, result.output


def test_the_compiled_model_equals_casadis_own_evaluation(rng):
    """The compiled build and CasADi's virtual machine evaluating the serialized function
    (generated/gsfric_model.casadi) at random states with every effect: the same numbers to
    rounding (the SIMD code and CasADi order some sums differently), relative to each
    output's size."""
    platform = with_every_effect(rng, perturbed_platform(rng))
    x = random_states(rng, 37)
    ev = Evaluator(platform)
    compiled = native.get("eval")([x, ev.P, ev.Q])
    function = native.serialized("eval")
    values = function.map(len(x))(x.T, np.tile(ev.P[:, None], len(x)),
                                  np.tile(ev.Q[:, None], len(x)))
    for (name, size, _), value in zip(native.get("eval").outputs, values):
        expected = np.array(value).reshape(size, len(x)).T
        scale = max(np.abs(expected).max(), 1e-300)
        np.testing.assert_allclose(compiled[name], expected, rtol=0, atol=1e-12 * scale,
                                   err_msg=name)


def test_effect_vector_follows_the_catalog_order(platform):

    p = platform.with_effect("seal_friction", force=2.5).with_effect("sensor_bias", b3=0.7)
    q = effect_vector(p)
    names = parameter_names()
    assert q[names.index("seal_friction.force")] == 2.5
    assert q[names.index("sensor_bias.b3")] == 0.7
    assert q[names.index("stribeck.velocity")] > 0


def test_runtime_catalog_is_derives_catalog_and_only_generated_effects_are_in_Q():
    """Every effect of derive/effects.py, sensor effects included, reaches the runtime through
    the manifest with its kind, defaults, units and descriptions; Q (the compiled functions'
    input, the Jacobian's effect columns) holds the generated effects' parameters only, so a
    sensor effect leaking into Q would change its size."""
    entries = [{"name": e.name, "description": e.description, "term": e.term,
                "kind": e.kind,
                "parameters": [{"name": p.name, "default": p.default, "unit": p.unit,
                                "description": p.description} for p in e.parameters]}
               for e in fx.CATALOG]
    assert describe() == entries
    assert {e["kind"] for e in entries} == {fx.GENERATED, fx.SENSOR}
    names = parameter_names()
    assert names == fx.parameter_names()
    q_size = next(i["size"] for i in manifest_function("eval")["inputs"] if i["name"] == "Q")
    assert len(names) == q_size
    assert jacobian_parameters()[-q_size:] == names
    sensor = {f"{e['name']}.{p['name']}" for e in entries if e["kind"] == SENSOR
              for p in e["parameters"]}
    assert sensor and not sensor & set(names)


def test_sensor_parameters_default_to_the_catalogs_values():
    gains, delay = sensor_parameters({"force_scale": {"g2": 0.1}})
    defaults = {p["name"]: p["default"] for e in describe() if e["kind"] == SENSOR
                for p in e["parameters"]}
    assert gains.tolist() == [0.1 if k == 2 else defaults[f"g{k}"] for k in range(1, 7)]
    assert delay == defaults["delay"]


def test_bound_hot_path_equals_the_general_call_and_checks_its_buffers(rng):

    platform = perturbed_platform(rng)
    x = random_states(rng, 13)
    ev = Evaluator(platform)
    out = np.empty((13, 6))
    assert ev.actuator_forces(x, out=out) is out
    np.testing.assert_array_equal(out, native.get(ev._actuator)([x, ev.P, ev.Q])["F"])
    with pytest.raises(GsfricError, match="C-contiguous float64"):
        ev.actuator_forces(np.asfortranarray(x), out=out)
    with pytest.raises(GsfricError, match="C-contiguous float64"):
        ev.actuator_forces(x, out=np.empty((12, 6)))


def _motion_with_bad_steps(rng, n):
    """A random motion over n steps with a singular, an out-of-stroke and an overflowing step."""


    m = models.random_motion(rng, np.sort(rng.uniform(0, 20, n)))
    position, rotation = m.position.copy(), m.rotation.copy()
    rotation[n // 3] = Rotation.from_rotvec([0.0, 0.0, np.pi / 2]).as_matrix()
    position[n // 3] = [0.0, 0.0, models.HOME_HEIGHT]
    position[n // 2] = [0.0, 0.0, 1.4]
    position[n - 5] = [1e200, 0.0, 1e200]
    return Motion(m.t, position, rotation, m.velocity, m.omega, m.acceleration, m.alpha)


@pytest.mark.parametrize("threads, model", [(1, "coupled"), (2, "coupled"), (1, "paper")])
def test_motion_input_in_blocks_equals_the_state_array(rng, threads, model):
    """evaluate lays out the states in C block by block (4096 steps) and keeps only the
    non-detail outputs, whose SIMD pass skips the instructions only the details need: every
    output and flag equals the state-array call's (every output asked for) over several
    blocks and threads, the details (computed on first access) too, NaN where non-finite."""

    n = 2 * 4096 + 37
    motion = _motion_with_bad_steps(rng, n)
    ev = Evaluator(models.reference_platform(model), n_threads=threads)
    result = ev.evaluate_quiet(motion)
    assert not set(DETAILS) & set(result.arrays.kept())
    assert {1, 2, 4} <= {b for b in (1, 2, 4) if (result.flag & b).any()}
    x = state_array(motion)
    raw = ev._full([x, ev.P, ev.Q], n_threads=threads)
    stroke = ev.platform.geometry.stroke
    np.testing.assert_array_equal(numpy_flags(x, raw, stroke), result.flag)   # NaN if non-finite
    for name, value in raw.items():
        np.testing.assert_array_equal(value.reshape(result.arrays[name].shape),
                                      result.arrays[name], err_msg=name)
    assert set(DETAILS) <= set(result.arrays.kept())
    bad = (result.flag & FLAG_NONFINITE) != 0
    assert np.isnan(result.N_bushing[bad]).all() and np.isfinite(result.N_bushing[~bad]).all()
    F = ev.forces(motion.position, motion.rotation, motion.velocity, motion.omega,
                  motion.acceleration, motion.alpha)
    np.testing.assert_array_equal(F, native.get(ev._actuator)([x, ev.P, ev.Q])["F"])


def test_control_loop_calls_read_views_and_slices_as_the_general_call(rng):
    """The bound calls get arrays as objects (their data pointer read in C): views with an
    offset, slices and converted arrays give the general call's numbers."""

    motion = models.random_motion(rng, np.sort(rng.uniform(0, 5, 50)))
    ev = Evaluator(perturbed_platform(rng))
    x = state_array(motion)
    expected = native.get(ev._actuator)([x[7:47], ev.P, ev.Q])["F"]
    out = np.zeros((60, 6))[10:50]
    assert ev.actuator_forces(x[7:47], out=out) is out
    np.testing.assert_array_equal(out, expected)
    parts = [motion.position[7:47], motion.rotation[7:47], motion.velocity[7:47].tolist(),
             np.asfortranarray(motion.omega[7:47]), motion.acceleration[7:47].astype(np.float32)
             .astype(np.float64), motion.alpha[7:47]]
    rounded = native.get(ev._actuator)([state_of(parts), ev.P, ev.Q])["F"]
    np.testing.assert_array_equal(ev.forces(*parts), rounded)
    with pytest.raises(GsfricError, match=r"rotation \(N, 3, 3\)"):
        ev.forces(*parts[:1], parts[1][:-1], *parts[2:])
    with pytest.raises(GsfricError, match="out must be"):
        ev.forces(*parts, out=np.empty((40, 5)))


def _offset_empty(n, size, offset):
    """An uninitialised C-contiguous (n, size) float64 array whose data starts ``offset``
    bytes (a multiple of 8) past a 64-byte boundary."""
    raw = np.empty(n * size + 16)
    start = (-raw.ctypes.data % 64 + offset) // 8
    return raw[start:start + n * size].reshape(n, size)


@pytest.mark.parametrize("n, threads", [(37, 1), (4096 + 13, 1), (2 * 4096 + 21, 2)])
def test_vector_row_stores_equal_the_scalar_ones(rng, n, threads):
    """A full group's output rows are written with vector stores into 64-byte aligned outputs
    (streamed past the caches from 4096 steps on) and row by row otherwise: the numbers are the
    same bit for bit, the partial last group and the second thread's range included."""
    motion = _motion_with_bad_steps(rng, n)
    ev = Evaluator(perturbed_platform(rng), n_threads=threads)

    x = state_array(motion)
    f = ev._full
    results = []
    for offset in (0, 8, 24):
        outs = {name: _offset_empty(n, size, offset) for name, size, _ in f.outputs}
        flag = np.empty(n, dtype=np.int64)
        f([x, ev.P, ev.Q], outs, threads, flags=ev.flag_spec(), flag=flag)
        results.append((outs, flag))
    (aligned, flag0), others = results[0], results[1:]
    assert (flag0 & 1).any() and np.isfinite(aligned["F"][flag0 == 0]).all()
    for outs, flag in others:
        np.testing.assert_array_equal(flag, flag0)
        for name in aligned:
            np.testing.assert_array_equal(outs[name], aligned[name], err_msg=name)


def test_evaluate_keeps_c_contiguous_aligned_result_arrays(rng):
    """Result arrays keep their public shapes, C-contiguous, on 64-byte boundaries (whole
    lines for the vector stores), fresh and reused alike."""
    motion = models.random_motion(rng, np.linspace(0.0, 1.0, 101))
    ev = Evaluator(models.reference_platform())
    fresh = ev.evaluate_quiet(motion)
    reused = ev.evaluate_quiet(motion, buffers={})
    for result in (fresh, reused):
        for name, value in result.arrays.kept().items():
            assert value.flags.c_contiguous and value.ctypes.data % 64 == 0, name
        assert result.F.shape == (101, 6) and result.R_E.shape == (101, 6, 3)
        np.testing.assert_array_equal(result.F, fresh.F)


@pytest.mark.skipif(sys.implementation.name != "cpython", reason="reads CPython's tuples")
def test_control_loop_calls_pass_their_arrays_as_one_tuple():
    """On CPython the bound calls hand C one tuple of arrays (fewest ctypes conversions):
    the library reads the tuple's items as Python does."""
    lib = native.library()
    assert _tuples_readable(lib)
    t = (np.zeros(2), np.ones((3, 4)), None)
    assert [lib.gsfric_tuple_item(t, k) for k in range(3)] == [id(v) for v in t]


def _with_non_rotations(x: np.ndarray, steps) -> np.ndarray:
    """A copy of states x whose rotation blocks at ``steps`` are scaled, mirrored (det -1) or
    sheared in turn, each far enough for ``ROTATION_TOL``."""
    x = x.copy()
    changes = [np.diag([2.0, 2.0, 2.0]), np.diag([-1.0, 1.0, 1.0]), np.eye(3) + np.eye(3, k=1)
               * 1e-4]
    for j, k in enumerate(steps):
        T = x[k, state_layout().rotation].reshape(3, 3)
        x[k, state_layout().rotation] = (T @ changes[j % 3]).ravel()
    return x


@pytest.mark.parametrize("threads", [1, 2])
def test_control_loop_calls_name_the_first_non_rotation_of_any_thread_or_block(rng, threads):
    """Over 2 x 4096 + 21 steps (two threads' ranges, several blocks of a range) the rotation
    test in C reports the earliest bad step however the steps are split, the bound call (into
    ``out``) as the general one and the motion's; ``out`` holds NaN at every bad step and the
    forces of a clean call elsewhere; blocks rounded within the tolerance pass."""
    n = 2 * 4096 + 21
    ev = Evaluator(models.reference_platform(), n_threads=threads)
    x = random_states(rng, n)
    clean = ev.actuator_forces(x)
    rounded = x.copy()
    rounded[:, state_layout().rotation] += rng.uniform(-1e-12, 1e-12, (n, 9))
    np.testing.assert_allclose(ev.actuator_forces(rounded, np.empty((n, 6))), clean,
                               rtol=1e-6, atol=1e-6)
    for steps in ([n - 1], [6000, 3001, 5000], [4097, 4200], [0, n - 1]):
        bad = _with_non_rotations(x, steps)
        first = min(steps)
        out = np.zeros((n, 6))
        with pytest.raises(InputError, match=rf"^actuator_forces: x\[{first}\]: the rotation "
                                             r"block is not a rotation \("):
            ev.actuator_forces(bad, out)
        assert np.isnan(out[steps]).all()
        keep = np.setdiff1d(np.arange(n), steps)
        np.testing.assert_array_equal(out[keep], clean[keep])
        with pytest.raises(InputError, match=rf"^actuator_forces: x\[{first}\]"):
            ev.actuator_forces(bad)
        T = bad[:, state_layout().rotation].reshape(n, 3, 3)
        p, _, v, w, a, al = state_layout().split(bad)
        with pytest.raises(InputError, match=rf"^forces: rotation\[{first}\]: not a rotation"):
            ev.forces(p, T, v, w, a, al)


def test_evaluation_flags_a_non_rotation_as_the_exported_library_does(rng):
    """With flags (evaluate's pass over raw states) a step whose rotation block is not a
    rotation is flagged FLAG_ROTATION alone, its outputs NaN (as the library of ``gsfric
    export`` does), the others as without it; the NumPy reference agrees."""
    n = 300
    ev = Evaluator(models.reference_platform())
    x = random_states(rng, n)
    steps = [0, 7, 150, n - 1]
    bad = _with_non_rotations(x, steps)
    bad[150, 5] = np.nan           # T[0, 2]: its sheared columns 0, 1 still flag it alone
    results = []
    for states in (x, bad):
        outs = {name: np.empty((n, size)) for name, size, _ in ev._full.outputs}
        flag = np.empty(n, dtype=np.int64)
        ev._full([states, ev.P, ev.Q], outs, flags=ev.flag_spec(), flag=flag)
        results.append((outs, flag))
    (clean, flag0), (outs, flag) = results
    assert (flag[steps] == FLAG_ROTATION).all()
    keep = np.setdiff1d(np.arange(n), steps)
    np.testing.assert_array_equal(flag[keep], flag0[keep])
    raw = ev._full([bad, ev.P, ev.Q])
    np.testing.assert_array_equal(numpy_flags(bad, raw, ev.platform.geometry.stroke), flag)
    for name, value in outs.items():
        assert np.isnan(value[steps]).all(), name
        np.testing.assert_array_equal(value[keep], clean[name][keep], err_msg=name)
