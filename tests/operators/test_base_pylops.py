"""Our linear operators inside pylops and pyproximal solvers, unchanged."""

import jax.numpy as jnp
import numpy as np
import pylops
import pyproximal
import pytest

import operators as op


def test_cgls_solves_least_squares_through_a_composed_operator():
    rng = np.random.default_rng(4)
    dims = (1, 6, 5, 4)
    A = op.aslinearoperator(pylops.MatrixMult(rng.standard_normal((150, 120))))
    smooth = op.aslinearoperator(pylops.Identity(120)) + 0.1 * (op.D_x(dims).H @ op.D_x(dims))
    composed = A @ smooth
    x_true = rng.standard_normal(120)
    y = composed @ x_true
    x, *_ = pylops.optimization.basic.cgls(composed, y, x0=np.zeros(120), niter=400, tol=1e-14)
    np.testing.assert_allclose(x, x_true, rtol=1e-7, atol=1e-8)


def test_lsqr_on_a_linearized_jacobian():
    rng = np.random.default_rng(5)
    M = rng.standard_normal((30, 10))
    F = op.Operator.from_jax(jnp.tanh, (30,), (30,)) @ op.aslinearoperator(pylops.MatrixMult(M))
    x0 = 0.1 * rng.standard_normal(10)
    J = F.linearize(x0)
    b = rng.standard_normal(30)
    dx = pylops.optimization.basic.lsqr(J, b, x0=np.zeros(10), niter=100, atol=1e-14,
                                        btol=1e-14)[0]
    Jdense = np.stack([J @ e for e in np.eye(10)], axis=1)
    np.testing.assert_allclose(dx, np.linalg.lstsq(Jdense, b, rcond=None)[0], rtol=1e-8)


def test_pyproximal_primal_dual_runs_with_our_gradient():
    rng = np.random.default_rng(6)
    dims = (1, 12, 10, 3)
    truth = np.zeros(dims)
    truth[0, 3:9, 2:7] = 1.0
    noisy = truth + 0.2 * rng.standard_normal(dims)
    G = op.Gradient(dims)
    l2 = pyproximal.L2(b=noisy.ravel())
    l1 = pyproximal.L1(sigma=0.1)
    tau = mu = 0.95 / np.sqrt(12.0)  # ||G||^2 <= 4 * 3 directions
    x = pyproximal.optimization.primaldual.PrimalDual(
        l2, l1, G, x0=np.zeros(noisy.size), tau=tau, mu=mu, niter=200, show=False
    )
    error_denoised = np.linalg.norm(x - truth.ravel())
    error_noisy = np.linalg.norm(noisy - truth)
    assert error_denoised < 0.6 * error_noisy


@pytest.mark.parametrize("dtype", [np.float64])
def test_pylops_dottest_accepts_linearized_jacobian(dtype):
    M = np.random.default_rng(7).standard_normal((8, 5))
    F = op.Operator.from_jax(jnp.sin, (8,), (8,)) @ op.aslinearoperator(pylops.MatrixMult(M))
    J = F.linearize(np.ones(5))
    assert pylops.utils.dottest(J, 8, 5, rtol=1e-10)
