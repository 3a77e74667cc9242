"""The NumPy implementations of gsfric.bench.numpy_engine against the compiled map, at random states.

The vectorised implementation reduces (2)-(16) to a 6x6 system per step; the per-step loop
solves the dense 42x42 system. Their agreement with each other and with the compiled
``Evaluator.actuator_forces`` checks the reduction, and the 42x42 system checks the compiled
reactions R_E, R_C, M_C equation by equation.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import perturbed_platform, random_states, with_every_effect

import gsfric
from gsfric import models
from gsfric.bench import numpy_engine as numpy_model
from gsfric.evaluation.evaluator import Evaluator, state_array

RTOL = 1e-9


def _platforms(rng):
    return {
        "reference": models.reference_platform("paper"),
        "perturbed rigid, every effect": with_every_effect(rng, perturbed_platform(rng)),
        "perturbed paper legs, every effect": with_every_effect(
            rng, perturbed_platform(rng, "paper")),
    }


def _relative_error(got, expected):
    return np.max(np.abs(got - expected)) / max(np.max(np.abs(expected)), 1e-300)


@pytest.mark.parametrize("case", range(3))
def test_vectorised_numpy_equals_compiled_at_random_states(rng, case):
    name, platform = list(_platforms(rng).items())[case]
    x = random_states(rng, 60)
    expected = Evaluator(platform).actuator_forces(x)
    got = numpy_model.actuator_forces_numpy(platform, x, chunk=25)
    assert got.shape == (60, 6)
    assert _relative_error(got, expected) < RTOL, name


@pytest.mark.parametrize("case", range(3))
def test_per_step_loop_equals_compiled_at_random_states(rng, case):
    name, platform = list(_platforms(rng).items())[case]
    x = random_states(rng, 8)
    expected = Evaluator(platform).actuator_forces(x)
    assert _relative_error(numpy_model.actuator_forces_loop(platform, x), expected) < RTOL, name


def test_the_42x42_system_holds_the_compiled_reactions(rng):
    platform = with_every_effect(rng, perturbed_platform(rng))
    motion = models.random_motion(rng, np.sort(rng.uniform(0, 5, 5)))
    result = gsfric.evaluate(platform, motion)
    x = state_array(motion)
    for k in range(len(motion)):
        A, b = numpy_model.system_42(platform, x[k])
        assert A.shape == (42, 42) and b.shape == (42,)
        z = np.linalg.solve(A, b)
        # the dense solution is the compiled one, unknown by unknown
        for got, expected in ((z[:18], result.R_E[k]), (z[18:36], result.R_C[k]),
                              (z[36:], result.M_C[k])):
            assert _relative_error(got, np.ravel(expected)) < RTOL
        # and the compiled reactions satisfy each of the 42 equations
        z_compiled = np.concatenate([np.ravel(result.R_E[k]), np.ravel(result.R_C[k]),
                                     result.M_C[k]])
        scale = np.abs(A) @ np.abs(z_compiled) + np.abs(b)
        assert np.all(np.abs(A @ z_compiled - b) <= RTOL * scale.max())
