"""PDHG: the TV-denoising minimizer of pyproximal's PrimalDual, and TV with a nonlinear forward
map and bounds."""

import numpy as np
import pylops
import pyproximal
from pyproximal.optimization.primaldual import PrimalDual

import operators as op
import solvers


def test_pdhg_matches_pyproximal_primal_dual_on_tv_denoising():
    rng = np.random.default_rng(1)
    dims = (1, 16, 12, 1)
    truth = np.zeros(dims)
    truth[0, 4:11, 3:9, 0] = 1.0
    noisy = truth + 0.1 * rng.standard_normal(dims)
    lam = 0.3
    grad = op.Gradient(dims)
    identity = op.aslinearoperator(pylops.Identity(dims), name="I")
    problem = solvers.Problem(identity, noisy, regularizer=(op.L1(), grad), lam=lam,
                              x0=np.zeros(dims), kind="voxel")
    result = solvers.solve(problem, "pdhg", inner_iter=100, max_iter=50)

    # pyproximal: min_x sigma/2 ||x - b||^2 + lam ||grad x||_1 with sigma = 2 is our objective
    step = 0.99 / np.sqrt(8.0)  # ||grad||^2 <= 8 in 2-D with unit spacing
    reference = PrimalDual(pyproximal.L2(b=noisy.ravel(), sigma=2.0), pyproximal.L1(sigma=lam),
                           grad, x0=np.zeros(noisy.size), tau=step, mu=step, theta=1.0,
                           niter=5000)
    np.testing.assert_allclose(result.x.ravel(), reference, atol=1e-8)
    assert abs(result.loss - problem.objective(reference)) < 1e-8 * result.loss
    # the TV solution is piecewise flat: far fewer distinct values than pixels
    assert len(np.unique(np.round(result.x, 6))) < noisy.size // 4


def test_pdhg_with_a_nonlinear_forward_tv_and_bounds(numpy_forward, nonlinear_forward):
    forward = numpy_forward
    assert op.jacobian_dottest(forward, np.ones(10)).passed
    np.testing.assert_allclose(forward(np.ones(10)), nonlinear_forward()(np.ones(10)))
    rng = np.random.default_rng(0)
    truth = 0.5 * rng.standard_normal(10)
    data = forward(truth) + 0.05 * rng.standard_normal(30)
    diff = op.aslinearoperator(pylops.FirstDerivative(10, kind="forward", edge=False))
    problem = solvers.Problem(forward, data, regularizer=(op.L1(), diff), lam=0.5, lower=-0.5,
                              upper=0.5, x0=np.zeros(10))
    result = solvers.solve(problem, "pdhg", max_iter=15, inner_iter=30)
    loss = result.history["loss"]
    assert np.all(np.diff(loss) <= 1e-12 * loss[0]), loss  # backtracking: never increases
    assert np.all(np.abs(result.x) <= 0.5)
    # at least as good as a long first-order run on the same nonsmooth objective
    adam = solvers.solve(problem, "adam", lr=3e-3, max_iter=2000)
    assert result.loss <= adam.loss + 1e-9
    np.testing.assert_allclose(result.x, adam.x, atol=3e-3)


def test_pdhg_refuses_a_composite_outer_functional(nonlinear_forward):
    forward = nonlinear_forward(4, 8)
    diff = op.aslinearoperator(pylops.FirstDerivative(4, kind="forward", edge=False))
    nested = op.Composite(op.L1(), diff)
    problem = solvers.Problem(forward, np.zeros(8), regularizer=(nested, diff), x0=np.zeros(4))
    try:
        solvers.solve(problem, "pdhg")
    except solvers.UnsupportedProblemError as err:
        assert "proximal map" in str(err)
    else:
        raise AssertionError("pdhg accepted a regularizer without a proximal map")
