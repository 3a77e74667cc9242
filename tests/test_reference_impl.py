"""The NumPy reference engine (tests/engines/numpy_reference.py) against the compiled map.

The vectorised implementation reduces (2)-(16) to a 6x6 system per step; the per-step loop
solves the dense 42x42 system. Their agreement with each other and with the compiled
``Evaluator.actuator_forces`` checks the reduction, and the 42x42 system checks the compiled
reactions R_E, R_C, M_C equation by equation.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from helpers import perturbed_platform, random_states, with_every_effect

import gsfric
from gsfric import models
from gsfric.evaluation.evaluator import Evaluator, state_array

try:
    from tests.engines import numpy_reference as numpy_model
except ImportError:
    from engines import numpy_reference as numpy_model

RTOL = 1e-9

INPUT_DEFINITIONS = {
    "gsfric.compiled.state": {"state_layout"},
    "gsfric.evaluation.parameters": {"JOINT_EPS", "PRISMATIC_EPS", "PRISMATIC_POINT"},
    "gsfric.platform.catalog": {"EFFECTS"},
    "gsfric.platform.description": {"Platform"},
}
"""All the reference engine may import from gsfric: the definitions of its inputs."""


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


def test_the_engine_imports_only_the_definitions_of_its_inputs():
    """Independent by design: no formula from derive/, generated/ or the compiled model."""
    tree = ast.parse(Path(numpy_model.__file__).read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
            assert not [n for n in names if n.split(".")[0] in ("gsfric", "derive")], names
        elif isinstance(node, ast.ImportFrom) and node.module.split(".")[0] in ("gsfric",
                                                                                  "derive"):
            imported = {a.name for a in node.names}
            assert imported <= INPUT_DEFINITIONS.get(node.module, set()), node.module
