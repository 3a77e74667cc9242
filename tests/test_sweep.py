"""gsfric sweep: envelopes against direct evaluation, identical results wherever tasks run
(serial, a LocalCluster of 2 worker processes, a worker killed mid-sweep, an interrupted and
resumed sweep), limits, and one-line errors on bad input."""

from __future__ import annotations

import glob
import logging
import os
import pickle
import signal
import tracemalloc

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from scipy.spatial.transform import Rotation

import gsfric
from gsfric import io, models
from gsfric.compiled.state import state_layout
from gsfric.cli import main
from gsfric.errors import GsfricWarning, InputError
from gsfric.evaluation.evaluator import Evaluator
from gsfric.simulate.api import evaluate
from gsfric.evaluation.flags import FLAG_COUPLING, FLAG_STROKE
from gsfric.platform.description import Platform
from gsfric.signal.rotations import rotation_from_rpy
from gsfric.sweep import SweepResult, Workspace, blocks, load, run, sweep, tasks
from gsfric.sweep.plan import plan
from gsfric.sweep.result import fold, merge
from gsfric.sweep.variants import make_variants
from gsfric.sweep.workspace import check_reachable
from gsfric.trajectory import Motion

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

WORKSPACE = {
    "sampling": "lhs", "samples": 60, "states": 4, "seed": 3,
    "pose": {"x": [-0.04, 0.04], "y": [-0.04, 0.04], "z": [0.66, 0.74],
             "roll": [-0.08, 0.08], "pitch": [-0.08, 0.08], "yaw": [-0.1, 0.1]},
    "bounds": {"velocity": 0.2, "omega": 0.4, "acceleration": 2.0, "alpha": 4.0},
}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Two trajectory files, a workspace and payload/friction variants: a small sweep."""
    folder = tmp_path_factory.mktemp("sweep-inputs")
    for k in range(2):
        motion = models.random_motion(np.random.default_rng(k), np.linspace(0, 4, 801))
        io.write_table(motion.to_frame(), folder / f"motion{k}.csv")
    return dict(trajectories=str(folder / "motion*.csv"),
                workspace=Workspace.from_dict(WORKSPACE),
                vary={"platform.payload_mass": (0.0, 8.0), "friction.joint_coulomb": (0.02, 0.1)},
                tolerances={"geometry.base_joints": 0.001}, variants=3, seed=1,
                chunk_steps=1000)


@pytest.fixture(scope="module")
def serial(inputs, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "out"
    return sweep(out, scheduler="serial", plots=False, **inputs)


def _same(a, b):
    pd.testing.assert_frame_equal(a.envelopes, b.envelopes, check_exact=True)


def test_envelope_is_the_extreme_of_a_direct_evaluation(serial, inputs):
    """Every extreme, its step and the dissipated energy, from evaluate() and numpy alone."""
    path = sorted(glob.glob(inputs["trajectories"]))[0]
    motion = io.read_trajectory(path)
    result = evaluate(models.reference_platform(), motion)
    env = serial.envelopes
    env = env[(env.motion == "motion0.csv") & (env.variant == 0)].set_index(["quantity", "leg"])
    series = {"R_E": np.linalg.norm(result.R_E, axis=2), "R_C": np.linalg.norm(result.R_C, axis=2),
              "M_C": np.abs(result.M_C), "M_3": np.linalg.norm(result.M_3, axis=2),
              "F_max": result.F, "F_min": -result.F, "Ffr": np.abs(result.Ffr)}
    for q, s in series.items():
        for leg in range(6):
            row = env.loc[(q, leg + 1)]
            sign = -1 if q == "F_min" else 1
            assert sign * row.value == pytest.approx(s[:, leg].max(), rel=1e-12)
            assert row.step == int(np.argmax(s[:, leg]))
            assert row.t == motion.t[row.step]
            assert row.x == motion.position[row.step, 0]
    power = -result.Ffr * result.D_dot
    assert np.all(power >= 0)    # friction dissipates
    for leg in range(6):
        expected = np.trapezoid(power[:, leg], motion.t)
        assert env.loc[("W_3", leg + 1)].value == pytest.approx(expected, rel=1e-12)
        assert env.loc[("W_3", leg + 1)].value > 0
    assert (env.steps == len(motion)).all() and (env.flagged == 0).all()


def test_workspace_location_reproduces_the_extreme(serial):
    """Re-evaluating the reported workspace state gives the reported value."""
    ws = Workspace.from_dict(WORKSPACE)
    poses = ws.poses()
    row = serial.summary[(serial.summary.quantity == "R_C") &
                         (serial.summary.motion == "workspace")].iloc[0]
    pose_index, _ = divmod(int(row.step), ws.states)
    x = ws.states_of(poses[pose_index:pose_index + 1], pose_index)[int(row.step) % ws.states]
    motion = Motion(np.zeros(1), *state_layout().split(x[None]))
    platforms, _ = make_variants(models.reference_platform(),
                                 {"platform.payload_mass": (0.0, 8.0),
                                  "friction.joint_coulomb": (0.02, 0.1)},
                                 {"geometry.base_joints": 0.001}, 3, 1)
    result = evaluate(platforms[int(row.variant)], motion)
    assert np.linalg.norm(result.R_C[0, int(row.leg) - 1]) == pytest.approx(row.value,
                                                                             rel=1e-12)
    assert np.allclose([row.x, row.y, row.z], poses[pose_index, :3])


def test_chunking_does_not_change_the_envelopes(serial, inputs, tmp_path):
    whole = sweep(tmp_path / "out", scheduler="serial", plots=False,
                  **{**inputs, "chunk_steps": 10**7})
    assert whole.info["tasks"] < serial.info["tasks"]
    _same(whole, serial)


def test_variants_heavier_payload_loads_the_actuators_more(serial):
    """Static states: the actuators carry the weight, so a heavier payload raises sum(F_max)."""
    env, var = serial.envelopes, serial.variants
    ws = env[(env.motion == "workspace") & (env.quantity == "F_max")]
    total = ws.groupby("variant").value.sum()
    heaviest = var["platform.payload_mass"].idxmax()
    lightest = var["platform.payload_mass"].idxmin()
    assert total[heaviest] > total[lightest]
    assert len(var) == 4 and var.loc[0, "platform.payload_mass"] == 3.0


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=logging.ERROR) as c, \
            distributed.Client(c) as client:
        yield client


def test_local_cluster_of_two_workers_equals_serial(serial, inputs, cluster, tmp_path,
                                                    monkeypatch):
    monkeypatch.setattr(run, "MERGE_EVERY", 2)   # fold envelopes as they arrive, in any order
    result = sweep(tmp_path / "out", scheduler=cluster, plots=False, **inputs)
    assert len(cluster.scheduler_info()["workers"]) == 2
    _same(result, serial)
    pd.testing.assert_frame_equal(result.summary, serial.summary, check_exact=True)


def test_killing_a_worker_mid_sweep_gives_the_same_envelopes(serial, inputs, cluster, tmp_path):
    pids = list(cluster.run(os.getpid).values())
    killed = []

    def kill_one(done, total):
        if not killed and done < total:
            os.kill(pids[0], signal.SIGKILL)
            killed.append(done)

    result = sweep(tmp_path / "out", scheduler=cluster, plots=False, on_chunk=kill_one,
                   **inputs)
    assert killed and killed[0] < result.info["tasks"]
    _same(result, serial)


def test_resumed_sweep_equals_an_uninterrupted_one(serial, inputs, tmp_path, monkeypatch):
    monkeypatch.setattr(run, "MERGE_EVERY", 2)
    out = tmp_path / "out"

    class Stop(Exception):
        pass

    def stop_after_three(done, total):
        if done == 3:
            raise Stop

    with pytest.raises(Stop), pytest.warns(GsfricWarning, match=r"out\.partial: the unfinished "
                                           r"sweep is kept \(3 of [0-9]+ tasks done\)"):
        sweep(out, scheduler="serial", plots=False, on_chunk=stop_after_three, **inputs)
    assert not out.exists()
    assert len(list((tmp_path / "out.partial" / "chunks").glob("*.parquet"))) == 3
    seen = []
    resumed = sweep(out, scheduler="serial", plots=False,
                    on_chunk=lambda d, t: seen.append(d), **inputs)
    assert resumed.info["computed_tasks"] == serial.info["tasks"] - 3
    assert seen == list(range(4, serial.info["tasks"] + 1))
    assert not (tmp_path / "out.partial").exists()
    _same(resumed, serial)
    assert resumed.info["steps"] == serial.info["steps"]
    # the same sweep again: read back, nothing computed
    again = sweep(out, scheduler="serial", plots=False, **inputs)
    _same(again, serial)


def test_limits_list_exactly_the_exceeding_cases(serial, inputs, tmp_path):
    nominal = serial.envelopes[serial.envelopes.variant == 0]

    def median(q):
        return float(nominal[nominal.quantity == q].value.median())

    rating, lo, hi = median("R_E"), median("F_min"), median("F_max")
    limits = {"spherical_load": rating, "actuator_force": [lo, hi]}
    platform = models.reference_platform().replace(limits=limits)
    toml = tmp_path / "platform.toml"
    platform.to_toml(toml)
    args = {**inputs, "vary": None, "tolerances": None}
    result = sweep(tmp_path / "out", platform=toml, scheduler="serial", **args)
    env, bad = result.envelopes, result.exceeded
    for q, over in (("R_E", env.value > rating), ("F_max", env.value > hi),
                    ("F_min", env.value < lo)):
        expected = env[(env.quantity == q) & over]
        listed = bad[bad.quantity == q]
        assert len(listed) == len(expected) > 0
    assert (bad.ratio[bad.quantity != "F_min"] > 1).all()
    assert (result.out / "limits.csv").exists() and (result.out / "envelope.png").exists()
    cli = _cli("sweep", "--out", str(tmp_path / "cli"), "--trajectories", inputs["trajectories"],
               "--platform", str(toml), "--scheduler", "serial", "--no-plots", "--strict")
    assert cli.exit_code == 1, cli.stderr
    assert "case(s) exceed" in cli.stdout


def _cli(*args):
    """The command's exit code, stdout and stderr (in this process: click's runner)."""
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def _one_line_error(proc, *words):
    assert proc.exit_code == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gsfric: error:"), proc.stderr
    for w in words:
        assert w in lines[0]


def test_glob_matching_nothing(tmp_path):
    _one_line_error(_cli("sweep", "--out", str(tmp_path / "o"), "--trajectories",
                         str(tmp_path / "nothing*.csv")), "matches no file", "nothing*.csv")


def test_variant_range_min_above_max(inputs, tmp_path):
    _one_line_error(_cli("sweep", "--out", str(tmp_path / "o"), "--trajectories",
                         inputs["trajectories"], "--vary", "platform.payload_mass=5:2"),
                    "platform.payload_mass", "min 5 > max 2")
    with pytest.raises(InputError, match="unknown parameter"):
        make_variants(models.reference_platform(), {"platform.payload": (0, 1)})


def test_unreachable_workspace(tmp_path):
    ws = tmp_path / "ws.toml"
    ws.write_text('sampling = "grid"\npoints = 3\n[pose]\nz = [0.7, 1.4]\n')
    _one_line_error(_cli("sweep", "--out", str(tmp_path / "o"), "--workspace", str(ws)),
                    "unreachable", "outside the stroke")
    ws.write_text('[pose]\nz = [0.8, 0.6]\n')
    _one_line_error(_cli("sweep", "--out", str(tmp_path / "o"), "--workspace", str(ws)),
                    "pose.z", "min 0.8 > max 0.6")


def test_output_folder_of_another_sweep_is_not_overwritten(serial, inputs):
    with pytest.raises(InputError, match="exists"):
        sweep(serial.out, scheduler="serial", plots=False, **{**inputs, "seed": 2})


def test_gsfric_sweep_names_are_reachable():
    """``import gsfric`` reaches the package's entry points as attributes."""
    assert gsfric.sweep.sweep is sweep and gsfric.sweep.load is load
    assert gsfric.sweep.Workspace is Workspace and gsfric.sweep.SweepResult is SweepResult


def test_platform_limits_round_trip_and_one_line_errors(tmp_path):
    platform = models.reference_platform().replace(
        limits={"actuator_force": 200.0, "universal_load": 300.0})
    assert platform.limits["actuator_force"] == (-200.0, 200.0)
    platform.to_toml(tmp_path / "p.toml")
    assert Platform.from_toml(tmp_path / "p.toml") == platform
    base = models.reference_platform().to_dict()
    for limits, words in (({"universal_lod": 1.0}, "did you mean 'universal_load'"),
                          ({"spherical_load": 0.0}, "must be positive"),
                          ({"actuator_force": [5.0, -5.0]}, "min = 5 must be less than")):
        with pytest.raises(InputError, match=words) as info:
            Platform.from_dict({**base, "limits": limits}, source="p.toml")
        assert "\n" not in str(info.value) and str(info.value).startswith("p.toml: limits.")


@pytest.mark.parametrize("keys, words", [
    ({"sampling": "lhs", "points": 3}, "points: applies to sampling = 'grid', not 'lhs'"),
    ({"sampling": "grid", "samples": 50}, "samples: applies to sampling = 'lhs', not 'grid'"),
    ({"samples": 10 ** 12}, "samples = 1000000000000 and states = 8 make 8e\\+12 states"),
    ({"sampling": "grid", "points": 10 ** 5}, "points = 100000 per varying coordinate \\(2\\)"),
])
def test_a_workspace_key_is_used_or_refused(keys, words):
    """A workspace key the sampling does not read is refused, not ignored; a workspace of
    more states than a sweep can evaluate is refused before its poses take any memory."""
    data = {**keys, "pose": {"z": [0.65, 0.75], "yaw": [-0.1, 0.1]}}
    with pytest.raises(InputError, match=words) as info:
        Workspace.from_dict(data, source="ws.toml")
    assert "\n" not in str(info.value) and str(info.value).startswith("ws.toml: ")


def test_merge_is_independent_of_arrival_order_and_folding(serial, inputs):
    """Task envelopes folded in a shuffled order, in steps, give the serial envelopes."""
    p = plan(**inputs)
    frames = [tasks.run_task(t) for t in p.tasks]
    order = np.random.default_rng(5).permutation(len(frames))
    shuffled = [frames[i].sample(frac=1.0, random_state=1) for i in order]
    folded = fold(shuffled[:3])
    pd.testing.assert_frame_equal(merge([folded, *shuffled[3:]]), serial.envelopes,
                                  check_exact=True)


# -- the block evaluation and reduction ---------------------------------------------------------


def _flagging_workspace():
    """Poses of which some put a leg beyond the stroke (flagged steps), in dynamic states."""
    ws = Workspace.from_dict({**WORKSPACE, "samples": 40, "pose": {
        **WORKSPACE["pose"], "z": [0.66, 1.12]}})
    return ws, ws.poses()


def _platforms():

    reference = models.reference_platform()
    locking = models.reference_platform("coupled").with_friction(
        model="coupled", joint_radius=0.05, joint_coulomb=0.05 / 0.05)
    sensor = reference.with_effect("force_scale", g1=0.1, g4=-0.05)
    paper = models.reference_platform("paper").with_effect("stribeck", static=3.0) \
        .with_effect("payload_offset", x=0.02, z=0.01).with_effect("sensor_bias", b2=0.7)
    return {"reference": reference, "coupled, locking": locking, "load-cell gains": sensor,
            "paper friction, effects": paper}


def _expected_values(r):
    """Each step's 13 x 6 enveloped values from evaluate_quiet's outputs, NumPy alone."""
    def dot(a, b):
        return (a * b).sum(axis=2)

    rows = [np.linalg.norm(getattr(r, k), axis=2) ** 2
            for k in ("R_E", "R_C", "R_3", "M_3", "MfrE", "MfrC")]
    rows += [np.abs(r.M_C), r.F, -r.F, np.abs(r.Ffr), -dot(r.MfrE, r.omega_rel),
             -dot(r.MfrC, r.omega_leg), -r.Ffr * r.D_dot]
    return np.stack(rows, axis=1)


@pytest.mark.parametrize("name", list(_platforms()))
def test_block_evaluation_is_evaluate_quiet(name):
    """Each step's enveloped values (the generated function ``envelope``), evaluated block by
    block, equal the norms and products of Evaluator.evaluate_quiet's outputs to 1e-12, with
    exactly its step flags (stroke and coupled-friction flags included)."""
    platform = _platforms()[name]
    ws, poses = _flagging_workspace()
    x = ws.states_of(poses, 0)
    n = len(x)
    t = np.linspace(0.0, 1.0, n)
    motion = Motion(t, *state_layout().split(x))
    with np.errstate(all="ignore"):
        expected = Evaluator(platform).evaluate_quiet(motion)
    assert np.any(expected.flag & FLAG_STROKE) and not np.all(expected.flag)
    if name.startswith("coupled"):
        assert np.any(expected.flag & FLAG_COUPLING)
    G = _expected_values(expected)
    scale = np.abs(G).max(axis=0, initial=0.0, where=np.isfinite(G)) + 1e-300  # (13, 6)
    block = blocks.Block(37)                    # blocks that do not divide the steps
    seen = 0
    for s, e in blocks.Evaluation(platform).blocks(block, x, t):
        assert s == seen and e - s <= 37
        np.testing.assert_array_equal(block.flag, expected.flag[s:e])
        ok = np.isfinite(G[s:e]).all(axis=(1, 2))      # flagged steps included
        assert ok.any()
        assert np.all(np.abs(block.values[ok] - G[s:e][ok]) <= 1e-12 * scale)
        seen = e
    assert seen == n


def test_sweep_with_the_paper_friction_model_and_effects(inputs, tmp_path):
    """A platform file of the paper's friction model with effects: every motion envelope is
    the extreme of evaluate() on that platform, and its friction differs from the nominal's."""
    platform = models.reference_platform("paper").with_effect("stribeck", static=3.0) \
        .with_effect("sensor_bias", b1=1.5)
    platform.to_toml(tmp_path / "paper.toml")
    result = sweep(tmp_path / "out", trajectories=inputs["trajectories"],
                   platform=tmp_path / "paper.toml", scheduler="serial", plots=False)
    env = result.envelopes.set_index(["motion", "quantity", "leg"])
    for path in sorted(glob.glob(inputs["trajectories"])):
        motion = io.read_trajectory(path)
        r = evaluate(platform, motion)
        name = os.path.basename(path)
        for q, s in {"R_C": np.linalg.norm(r.R_C, axis=2), "F_max": r.F, "F_min": r.F,
                     "Ffr": np.abs(r.Ffr)}.items():
            extreme = s.min(axis=0) if q == "F_min" else s.max(axis=0)
            got = np.array([env.loc[(name, q, leg), "value"] for leg in range(1, 7)])
            np.testing.assert_allclose(got, extreme, rtol=1e-12)
    nominal = evaluate(models.reference_platform("paper"), motion)
    assert np.abs(nominal.Ffr).max() < np.abs(r.Ffr).max()      # the Stribeck peak counts


def test_workspace_envelope_leaves_the_flagged_steps_out(monkeypatch):
    """A task's envelope is the extreme over the unflagged steps of evaluate_quiet, block
    boundaries and all; flagged steps are counted."""
    monkeypatch.setattr(tasks, "BLOCK_STEPS", 24)
    ws, poses = _flagging_workspace()
    platform = models.reference_platform()
    task = tasks.Task(0, "workspace", [0], [platform], len(poses) * ws.states, poses=poses,
                      first_pose=0, workspace=ws)
    frame = tasks.run_task(task).set_index(["quantity", "leg"])
    x = ws.states_of(poses, 0)
    n = len(x)
    r = Evaluator(platform).evaluate_quiet(Motion(np.zeros(n), *state_layout().split(x)))
    ok = r.flag == 0
    assert 0 < ok.sum() < n
    assert (frame.flagged == n - ok.sum()).all() and (frame.steps == n).all()
    power = -np.einsum("nij,nij->ni", r.MfrC, r.omega_leg)
    series = {"R_E": np.linalg.norm(r.R_E, axis=2), "M_3": np.linalg.norm(r.M_3, axis=2),
              "F_max": r.F, "F_min": -r.F, "P_C": power}
    for q, s in series.items():
        s = np.where(ok[:, None], s, -np.inf)
        for leg in range(6):
            row = frame.loc[(q, leg + 1)]
            k = int(np.argmax(s[:, leg]))
            assert row.step == k and ok[k]
            assert (-row.value if q == "F_min" else row.value) == pytest.approx(s[k, leg],
                                                                                rel=1e-14)
            assert np.allclose([row.x, row.y, row.z], poses[k // ws.states, :3], rtol=0,
                               atol=0)
            assert np.allclose([row.roll, row.pitch, row.yaw], poses[k // ws.states, 3:],
                               atol=1e-12)
    assert frame.loc[("W_C", 1)].value != frame.loc[("W_C", 1)].value   # NaN: no motion


def test_task_memory_follows_the_block_not_the_task():
    """Peak memory (numpy's traced allocations) of a task 8 times larger grows only by its
    poses, not by its evaluated outputs (313 values per step)."""
    ws = Workspace.from_dict({**WORKSPACE, "samples": 16_000, "states": 8})
    poses = ws.poses()
    platform = models.reference_platform()
    tasks.run_task(tasks.Task(0, "workspace", [0], [platform], 8, poses=poses[:1], workspace=ws))

    def peak(n_poses):
        task = tasks.Task(0, "workspace", [0], [platform], n_poses * 8, poses=poses[:n_poses],
                          first_pose=0, workspace=ws)
        tracemalloc.start()
        try:
            tasks.run_task(task)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    small, large = peak(2_000), peak(16_000)   # 16 000 and 128 000 steps
    per_pose = 3 * 9 * 8                        # the task's rotations and their copies
    assert large - small < 14_000 * per_pose + 2**20
    assert large < 64 * 2**20                   # all outputs of the task: 320 MB


def test_workspace_states_follow_their_definition():
    """Each component at -bound where the pose's Philox stream draws a double below 0.5, else
    +bound; state 0 static; the same whatever block a pose is drawn in."""
    ws = Workspace.from_dict({**WORKSPACE, "states": 5, "bounds": {
        "velocity": [0.2, 0.0, 0.1], "omega": 0.4, "acceleration": 2.0, "alpha": 4.0}})
    poses = ws.poses()
    x = ws.states_of(poses, 0)
    bits = np.random.Philox(key=WORKSPACE["seed"])
    u = np.random.Generator(bits).random((len(poses), 5, 12))
    bound = np.array([0.2, 0.0, 0.1] + [0.4] * 3 + [2.0] * 3 + [4.0] * 3)
    expected = np.where(u < 0.5, -bound, bound)
    expected[:, 0] = 0.0
    np.testing.assert_array_equal(x[:, 12:].reshape(len(poses), 5, 12), expected)
    buffer = np.empty(7 * 5 * 36)
    part = ws.states_of(poses[13:20], 13, out=buffer)
    np.testing.assert_array_equal(part, x[13 * 5:20 * 5])
    rotation = Rotation.from_euler("ZYX", poses[:, [5, 4, 3]]).as_matrix()
    np.testing.assert_allclose(x[::5, 3:12].reshape(-1, 3, 3), rotation, rtol=0, atol=1e-15)


def test_reachability_reports_the_first_unreachable_pose_of_any_block(monkeypatch):
    """Platform.leg_lengths checked block by block: the count of unreachable poses and the
    first one (its leg and length) whatever the blocks and the threads sharing them;
    reachable poses pass."""
    _, poses = _flagging_workspace()
    platform = models.reference_platform()
    lengths = platform.leg_lengths(poses[:, :3], rotation_from_rpy(poses[:, 3:6]))
    lo, hi = platform.geometry.stroke
    outside = (lengths < lo) | (lengths > hi)
    bad = outside.any(axis=1)
    k = int(np.flatnonzero(bad)[0])
    leg = int(np.flatnonzero(outside[k])[0])
    assert 0 < k and bad.sum() > 1
    messages = []
    for size, threads in ((3, 1), (3, 4), (8192, 4)):
        monkeypatch.setattr("gsfric.sweep.workspace._LENGTH_BLOCK", size)
        monkeypatch.setattr("gsfric.sweep.workspace.CHECK_THREADS", threads)
        with pytest.raises(InputError) as info:
            check_reachable(platform, poses, "ws.toml")
        messages.append(str(info.value))
    assert messages[0] == messages[1] == messages[2]
    assert messages[0].startswith(f"ws.toml: unreachable: {int(bad.sum())} of {len(poses)} ")
    assert f"first: pose {k} (" in messages[0]
    assert f"leg {leg + 1} length {lengths[k, leg]:.4g} m" in messages[0]
    check_reachable(platform, poses[~bad])


def test_workspace_tasks_with_many_variants_carry_few_poses():
    """Every (pose, variant) pair is in exactly one task; with many variants a task carries a
    block of the poses and a group of the variants, near the chunk size, not all the poses."""
    ws = Workspace.from_dict({**WORKSPACE, "samples": 125_000, "states": 8})
    p = plan(workspace=ws, vary={"platform.payload_mass": (0.0, 8.0)}, variants=200,
             chunk_steps=10**6)
    counts = np.zeros((125_000, 201), dtype=int)
    for task in p.tasks:
        counts[task.first_pose:task.first_pose + len(task.poses), task.variants] += 1
        assert task.steps == len(task.poses) * 8 * len(task.variants)
        assert 0.5e6 <= task.steps <= 1e6
    assert (counts == 1).all()
    sizes = [len(pickle.dumps(task)) for task in p.tasks[:5]]
    assert max(sizes) < 0.1 * 125_000 * 48           # all the poses: 6 MB


def test_the_local_clusters_processes_leave_ctrl_c_to_the_command():
    """Ctrl-C reaches the whole foreground process group: the local cluster's worker
    processes ignore SIGINT (inherited from their start), so that only the command handles
    it, closing the cluster and printing one line, without a traceback per worker."""
    distributed = pytest.importorskip("distributed")
    from gsfric.sweep.run import local_cluster
    before = signal.getsignal(signal.SIGINT)
    cluster = local_cluster(1)
    try:
        assert signal.getsignal(signal.SIGINT) is before        # restored in this process
        with distributed.Client(cluster) as client:
            handlers = client.run(lambda: signal.getsignal(signal.SIGINT))
        assert list(handlers.values()) == [signal.SIG_IGN]
    finally:
        cluster.close()
