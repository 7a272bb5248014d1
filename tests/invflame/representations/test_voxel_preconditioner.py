"""The voxel problem's preconditioner: the data's curvature per field, the regularizer's
weight, built only when a solver asks."""

import numpy as np
import pytest

import operators as op
from invflame.representations.curvature import by_field, group_curvature
from invflame.representations.voxel import VoxelRepresentation


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
    np.testing.assert_allclose(preconditioner.shift,
                               group_curvature(problem.forward, x0, by_field(rep.dims)))
    assert rep.problem(data, "none", x0=x0).preconditioner is None
