"""The discovery's parametric model: the compiled Jacobian kept for the next linearisation."""

from __future__ import annotations

import numpy as np

from gsfric import models
from gsfric.discovery.model import ParametricModel


def _model() -> ParametricModel:
    t = np.linspace(0.0, 2.0, 401)
    return ParametricModel(models.reference_platform(), models.sinusoidal(t))


def test_jacobian_at_the_same_point_reuses_the_evaluation():
    model, fresh = _model(), _model()
    theta = model.theta0.copy()
    names = model.names[:model.n_compiled]
    rows = slice(10, 390)
    F3, J3 = model.jacobian(theta, names[:3], rows=rows)
    F3_given = F3.copy()
    F3[:] = 0.0                       # a caller's change of its F reaches no later result
    F_all, J_all = model.jacobian(theta, names, rows=rows)      # more columns, same point
    assert model.evaluations == 1
    F_ref, J_ref = fresh.jacobian(theta, names, rows=rows)
    assert np.array_equal(F_all, F_ref) and np.array_equal(J_all, J_ref)
    assert np.array_equal(F3_given, F_ref) and np.array_equal(J3, J_ref[:, :, :3])
    model.jacobian(theta, names[:3], rows=rows)                 # taken once: evaluated again
    assert model.evaluations == 2
    _, again = model.jacobian(theta, names[:2], rows=rows)
    assert model.evaluations == 2 and np.array_equal(again, J_ref[:, :, :2])


def test_another_point_or_evaluation_evaluates_again():
    model = _model()
    theta = model.theta0.copy()
    names = model.names[:model.n_compiled]
    model.jacobian(theta, names[:2])
    moved = theta.copy()
    moved[0] += 0.1
    F_moved, J_moved = model.jacobian(moved, names[:2])
    assert model.evaluations == 2
    model.forces(moved)                                         # releases the kept one
    F_again, J_again = model.jacobian(moved, names[:2])
    assert model.evaluations == 4
    assert np.array_equal(F_again, F_moved) and np.array_equal(J_again, J_moved)
    assert not np.array_equal(J_moved, model.jacobian(theta, names[:2])[1])
