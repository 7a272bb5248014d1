"""Gauss–Newton: fast local convergence on a zero-residual nonlinear problem."""

import numpy as np
import pylops

import operators as op
import solvers
from solvers.gauss_newton import stacked_jacobian


def test_gauss_newton_converges_quadratically(nonlinear_forward):
    forward = nonlinear_forward()
    truth = 0.5 * np.random.default_rng(1).standard_normal(10)
    problem = solvers.Problem(forward, forward(truth), x0=np.zeros(10))
    result = solvers.solve(problem, "gauss-newton", damping=1e-8, max_iter=20, gtol=1e-10)
    g = result.history["grad_norm"]
    assert result.stop_reason.startswith("gtol") and result.iterations <= 6, result
    np.testing.assert_allclose(result.x, truth, atol=1e-10)
    # quadratic: once in the local regime, g_{k+1} <= C g_k^2 with a moderate C,
    # i.e. the number of correct digits roughly doubles each iteration
    local = np.flatnonzero(g < 0.1)
    ratios = g[local[1:]] / g[local[:-1]] ** 2
    assert len(ratios) >= 2 and np.all(ratios < 1.0), g
    assert np.all(np.log(g[local[1:]]) < 1.7 * np.log(g[local[:-1]])), g


def test_gauss_newton_with_tikhonov_matches_a_first_order_solver(nonlinear_problem):
    gn = solvers.solve(nonlinear_problem, "gauss-newton", max_iter=20, gtol=1e-9)
    reference = solvers.solve(nonlinear_problem, "lbfgs", max_iter=300, ftol=1e-15,
                              pgtol=1e-12)
    assert gn.iterations < 12, gn
    np.testing.assert_allclose(gn.x, reference.x, atol=1e-6)
    assert np.all(np.isfinite(gn.history["damping"][1:]))


def test_stacked_jacobian_is_an_operator_of_the_algebra_and_passes_dot_tests(nonlinear_problem):
    p = nonlinear_problem
    x = np.linspace(-1, 1, 10)
    ev = p.evaluate(x)
    free = np.arange(10) % 3 != 0
    for mask in (None, free):
        A, residual = stacked_jacobian(p, ev, mask)
        assert isinstance(A, op.LinearOperator)
        assert op.dottest(A, rtol=1e-12).passed
        assert pylops.utils.dottest(A, A.shape[0], A.shape[1], rtol=1e-12)
        # the blocks: J_F and sqrt(lam c) I (Tikhonov on the identity), restricted to `mask`
        v = np.random.default_rng(4).standard_normal(10)
        kept = v if mask is None else v * mask
        expected = np.concatenate([p.forward.jvp(x, kept), np.sqrt(1e-3) * kept])
        np.testing.assert_allclose(A(v), expected, rtol=1e-12)
        np.testing.assert_allclose(
            residual, np.concatenate([p.forward(x) - p.data, np.sqrt(1e-3) * x]), rtol=1e-12)
