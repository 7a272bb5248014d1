"""PDHG: the TV-denoising minimizer of pyproximal's PrimalDual, and TV with a nonlinear forward
map and bounds."""

import numpy as np
import pylops
import pyproximal
import pytest
from pyproximal.optimization.primaldual import PrimalDual

import operators as op
import solvers
from solvers.pdhg import stacked_operator


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
                              x0=np.zeros(dims))
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


def test_stacked_operator_is_an_operator_of_the_algebra_and_passes_dot_tests(numpy_forward):
    diff = op.aslinearoperator(pylops.FirstDerivative(10, kind="forward", edge=False))
    problem = solvers.Problem(numpy_forward, np.zeros(30), regularizer=(op.L1(), diff), lam=0.5)
    x = np.random.default_rng(2).standard_normal(10)
    ev = problem.evaluate(x)
    for use_reg in (False, True):
        A = stacked_operator(ev, use_reg)
        assert isinstance(A, op.LinearOperator)
        assert op.dottest(A, rtol=1e-12).passed
        assert pylops.utils.dottest(A, A.shape[0], A.shape[1], rtol=1e-12)
        v = np.random.default_rng(3).standard_normal(10)
        blocks = A.combination.split(A(v))
        np.testing.assert_allclose(blocks[0], numpy_forward.jvp(x, v), rtol=1e-12)
        if use_reg:
            np.testing.assert_allclose(blocks[1], np.append(np.diff(v), 0.0), rtol=1e-12,
                                       atol=1e-15)
        np.testing.assert_allclose(A.combination.join(blocks), A(v), rtol=0)
    # the step sizes' norm estimate is the stack's spectral norm
    dense = np.stack([A(e) for e in np.eye(10)], axis=1)
    assert op.operator_norm(A, 300) == pytest.approx(np.linalg.norm(dense, 2), rel=1e-6)
