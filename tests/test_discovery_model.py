"""The discovery's parametric model and design columns: the compiled Jacobian kept for the next
linearisation, the delay's secant columns computed from the forces."""

from __future__ import annotations

import numpy as np

from gsfric import models
from gsfric.discovery.model import ParametricModel
from gsfric.discovery.residuals import Columns


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


def test_columns_read_as_the_joined_array():
    # stored columns and delay columns ((F(t - d) - F(t)) / size times the weight), read by
    # rows and columns in any order, as one array holding them side by side
    rng = np.random.default_rng(1)
    t = np.arange(300) / 100.0
    F = rng.normal(size=(300, 6))
    used = slice(10, 290)
    stored = rng.normal(size=(280, 6, 4))
    weight = (rng.random((280, 6)) > 0.3).astype(float)
    delays = [(0.01, 0.01), (-0.02, 0.02)]
    columns = Columns(stored, t, F, used, weight, delays)
    shifted = [(np.stack([np.interp(t[used] - d, t, F[:, i]) for i in range(6)], axis=1)
                - F[used]) / size * weight for d, size in delays]
    joined = np.concatenate([stored, np.stack(shifted, axis=2)], axis=2)
    assert columns.shape == joined.shape
    for cols in (None, [5, 0, 4], [0, 1, 2, 3, 2, 4], [3, 1], [4]):
        for rows in (slice(0, 280), slice(7, 133)):
            expected = joined[rows] if cols is None else joined[rows][:, :, cols]
            assert np.array_equal(columns.rows(rows, cols), expected)
