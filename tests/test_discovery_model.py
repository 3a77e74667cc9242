"""The discovery's parametric model and design columns: the compiled Jacobian evaluated chunk
by chunk, the delay's secant columns computed from the forces."""

from __future__ import annotations

import numpy as np

from gsfric import models
from gsfric.discovery.model import ParametricModel
from gsfric.discovery.residuals import Columns


def _model() -> ParametricModel:
    t = np.linspace(0.0, 2.0, 401)
    return ParametricModel(models.reference_platform(), models.sinusoidal(t))


def test_the_jacobian_by_chunks_equals_one_pass_and_counts_each_evaluation():
    model = _model()
    theta = model.theta0.copy()
    names = model.names[:model.n_compiled]
    rows = slice(10, 390)
    F_one, J_one = model.jacobian(theta, names, rows=rows, chunk=1000)
    F_given = F_one.copy()
    F_one[:] = 0.0                    # a caller's change of its F reaches no later result
    F_chunks, J_chunks = model.jacobian(theta, names, rows=rows, chunk=37)
    assert model.evaluations == 2
    np.testing.assert_allclose(F_chunks, F_given, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(J_chunks, J_one, rtol=1e-13, atol=1e-12)
    _, J3 = model.jacobian(theta, names[:3], rows=rows, chunk=50)
    np.testing.assert_allclose(J3, J_one[:, :, :3], rtol=1e-13, atol=1e-12)
    assert J3.shape == (380, 6, 3) and model.evaluations == 3
    moved = theta.copy()
    moved[0] += 0.1
    assert not np.allclose(model.jacobian(moved, names[:2], rows=rows)[1], J_one[:, :, :2])


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
