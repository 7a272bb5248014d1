"""The voxel problem's preconditioner: the data's curvature per field, the regularizer's
weight, built only when a solver asks."""

import numpy as np
import pytest

import operators as op
from invflame.representations.voxel import VoxelRepresentation, data_curvature


def test_data_curvature_is_the_mean_squared_jacobian_column_per_field():
    """For a diagonal map the Rademacher probes are exact: sum of d² per field over its size."""
    weights = np.random.default_rng(0).uniform(0.5, 2.0, (2, 3, 4, 5))
    forward = op.Diagonal(weights)
    expected = (weights.reshape(2, -1) ** 2).mean(axis=1)
    np.testing.assert_allclose(data_curvature(forward, np.zeros(weights.shape)), expected,
                               rtol=1e-12)


def test_a_field_the_data_do_not_see_gets_the_smallest_seen_curvature():
    weights = np.ones((2, 3, 3, 3))
    weights[1] = 0.0
    np.testing.assert_allclose(data_curvature(op.Diagonal(weights), np.zeros(weights.shape)),
                               [1.0, 1.0])


@pytest.mark.parametrize("regularizer", ["tikhonov", "tv"])
def test_the_preconditioner_matches_the_regularizer(tiny_scene64, plume, regularizer):
    rep = VoxelRepresentation(tiny_scene64.grid, tiny_scene64.operator)
    x0 = rep.initial_parameters(plume)
    data = tiny_scene64.simulate(plume)
    problem = rep.problem(data, regularizer, lam=1e-2, sigma=1e-3, x0=x0)
    assert callable(problem._preconditioner)  # not built before a solver asks
    preconditioner = problem.preconditioner
    assert isinstance(preconditioner, op.ScreenedPoissonSolve)
    scale = 1e-2 / np.prod(rep.dims)
    if regularizer == "tikhonov":
        assert preconditioner.weight == pytest.approx(scale)
    else:  # lam s / (2 tau), tau the median nonzero |Du| at the start
        du = np.abs(op.Gradient(rep.dims, tuple(rep.grid.spacing)).matvec(x0.ravel()))
        tau = np.median(du[du > 0])
        assert preconditioner.weight == pytest.approx(scale / (2 * tau), rel=1e-6)
    np.testing.assert_allclose(preconditioner.shift, data_curvature(problem.forward, x0))
    assert rep.problem(data, "none", x0=x0).preconditioner is None
