"""Concurrent calls give the same numbers as serial ones, bit for bit.

Threads share Evaluators (one, or several of different platforms) and call every entry point
(the control loop's ``actuator_forces`` with and without an output buffer, ``forces`` from the
motion's arrays, ``evaluate`` with its flags) with random sizes, some large enough to split
into POSIX threads inside the call. Each result is compared with the same call made serially.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from helpers import perturbed_platform, with_every_effect

from gsfric import models
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.memory import POOL_MIN_BYTES

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

CALLS = 10_000
THREADS = 8


def _jobs(rng, n_evaluators, calls, largest):
    evaluators = [Evaluator(with_every_effect(rng, perturbed_platform(rng)),
                            n_threads=int(rng.integers(1, 3))) for _ in range(n_evaluators)]
    motions = []
    for size in rng.integers(1, largest, calls // 50 + 1):
        motions.append(models.random_motion(rng, np.sort(rng.uniform(0, 5, size))))
    kinds = ("bound", "call", "forces", "evaluate")
    jobs = [(int(rng.integers(len(evaluators))), int(rng.integers(len(motions))),
             kinds[int(rng.integers(len(kinds)))]) for _ in range(calls)]
    return evaluators, motions, [state_array(m) for m in motions], jobs


def _run(evaluator, motion, x, kind):
    if kind == "bound":
        return evaluator.actuator_forces(x, np.empty((x.shape[0], 6)))
    if kind == "call":
        return evaluator.actuator_forces(x)
    if kind == "forces":
        return evaluator.forces(motion.position, motion.rotation, motion.velocity,
                                motion.omega, motion.acceleration, motion.alpha)
    result = evaluator.evaluate(motion)
    return np.concatenate([result.F, result.R_E.reshape(len(motion), -1), result.h[:, None],
                           result.flag[:, None].astype(float)], axis=1)


@pytest.mark.parametrize("n_evaluators", [1, 3])
def test_concurrent_calls_equal_serial_calls(n_evaluators):
    rng = np.random.default_rng(14 + n_evaluators)
    evaluators, motions, states, jobs = _jobs(rng, n_evaluators, CALLS // 2, 400)
    serial = [_run(evaluators[e], motions[m], states[m], kind) for e, m, kind in jobs]
    with ThreadPoolExecutor(THREADS) as pool:
        concurrent = list(pool.map(lambda job: _run(evaluators[job[0]], motions[job[1]],
                                                    states[job[1]], job[2]), jobs))
    wrong = [k for k, (a, b) in enumerate(zip(serial, concurrent))
             if a.shape != b.shape or a.tobytes() != b.tobytes()]
    assert not wrong, f"{len(wrong)} of {len(jobs)} concurrent results differ from serial"


def test_calls_split_into_threads_equal_one_thread():
    """Large calls on n_threads=2 (POSIX threads inside the call), run from 4 Python threads."""
    rng = np.random.default_rng(7)
    platform = with_every_effect(rng, perturbed_platform(rng))
    one, two = Evaluator(platform), Evaluator(platform, n_threads=2)
    motions = [models.random_motion(rng, np.linspace(0, 5, n))
               for n in rng.integers(4096, 20000, 12)]
    serial = [one.actuator_forces(state_array(m)) for m in motions]
    with ThreadPoolExecutor(4) as pool:
        split = list(pool.map(lambda m: two.actuator_forces(state_array(m)), motions))
    for a, b in zip(serial, split):
        assert a.tobytes() == b.tobytes()


def test_large_results_from_threads_own_their_memory_and_equal_serial():
    """Results large enough for reused memory blocks (``evaluation._POOL``), from 6 threads with
    some dropped as others are computed: every one equals the serial result bit for bit, and
    no two results alive at once share memory."""

    rng = np.random.default_rng(23)
    evaluator = Evaluator(with_every_effect(rng, perturbed_platform(rng)))
    sizes = [POOL_MIN_BYTES // (18 * 8) + 1000, POOL_MIN_BYTES // (6 * 8) + 7]
    motions = [models.random_motion(rng, np.linspace(0, 5, sizes[k % 2])) for k in range(24)]

    def flat(result):
        return np.concatenate([result.F, result.R_E.reshape(len(result), -1),
                               result.flag[:, None].astype(float)], axis=1)

    serial = [flat(evaluator.evaluate_quiet(m)) for m in motions]
    alive = []

    def job(k):
        result = evaluator.evaluate_quiet(motions[k])
        if k % 3 == 0:
            alive.append(result)   # kept while the others are computed and dropped
        return flat(result)

    with ThreadPoolExecutor(6) as pool:
        concurrent = list(pool.map(job, range(len(motions))))
    for k, (a, b) in enumerate(zip(serial, concurrent)):
        assert a.tobytes() == b.tobytes(), k
    for result in alive:   # still what they were when computed
        k = next(k for k, m in enumerate(motions) if m is result.source[1])
        assert flat(result).tobytes() == serial[k].tobytes()
    arrays = [r.R_E for r in alive] + [r.F for r in alive]
    for i, a in enumerate(arrays):
        for b in arrays[i + 1:]:
            assert not np.shares_memory(a, b)
