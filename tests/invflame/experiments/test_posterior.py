"""The Laplace posterior: its Hessian against finite differences of the gradient, its
standard deviations against the exact posterior of a small linear Gaussian problem."""

import jax.numpy as jnp
import numpy as np
import pytest

import operators as op
import solvers
from invflame.experiments.posterior import (
    SmoothnessPrior,
    laplace_posterior,
    misfit_hessian,
    randomized_eigenpairs,
    regularizer_prior,
)

DIMS = (2, 4, 4, 4)
SPACING = (0.25, 0.5, 0.25)
N = int(np.prod(DIMS))


def dense(apply, n=N):
    """The matrix of a linear map on flat float64 vectors of length ``n``."""
    return np.stack([np.ravel(apply(e.reshape(DIMS))) for e in np.eye(n)], axis=1)


def linear_problem(m=60, lam=40.0, regularizer="tikhonov", seed=0):
    """A whitened linear problem whose misfit Hessian decays: A = U diag(s) Vᵀ, s from 30 down
    to 0.03; noise σ of 0.5–2 per datum; and its matrices."""
    rng = np.random.default_rng(seed)
    u = np.linalg.qr(rng.standard_normal((m, m)))[0]
    v = np.linalg.qr(rng.standard_normal((N, m)))[0]
    matrix = u @ np.diag(np.logspace(np.log10(30), np.log10(0.03), m)) @ v.T
    sigma = rng.uniform(0.5, 2.0, m)
    forward = op.JaxOperator(lambda t: jnp.asarray(matrix) @ t.ravel(), DIMS, (m,),
                             dtype=np.float64, name="A")
    whiten = op.Diagonal(1.0 / sigma, name="whiten")
    reg = {"tikhonov": op.tikhonov, "tv": op.total_variation}[regularizer](DIMS, SPACING)
    data = rng.standard_normal(m)
    return solvers.Problem(whiten @ forward, data / sigma, regularizer=reg, lam=lam), matrix, sigma


def test_the_prior_square_root_precision_and_variance_agree_with_its_dense_matrix():
    prior = SmoothnessPrior(DIMS, SPACING, weight=3.0, floor=0.5)
    gamma = dense(prior.apply)
    differences = op.Gradient(DIMS, SPACING)
    precision = 3.0 * dense(lambda e: differences.adjoint(differences(e))) + 0.5 * np.eye(N)
    np.testing.assert_allclose(gamma @ precision, np.eye(N), atol=1e-12)
    root = dense(lambda e: prior.apply(e, 0.5))
    np.testing.assert_allclose(root, root.T, atol=1e-13)
    np.testing.assert_allclose(root @ root, gamma, atol=1e-13)
    np.testing.assert_allclose(dense(lambda e: prior.apply(e, -1.0)), precision, atol=1e-10)
    np.testing.assert_allclose(prior.variance().ravel(), np.diag(gamma), rtol=1e-12)


def test_the_gauss_newton_hessian_is_the_derivative_of_the_gradient_at_a_zero_residual():
    """F = whitened A tanh(θ), data F(θ̂): there Gauss–Newton is the full Hessian of L/2, and
    (∇L(θ̂ + εv) − ∇L(θ̂)) / (2ε) − Hv falls like ε."""
    rng = np.random.default_rng(3)
    matrix = rng.standard_normal((50, N))
    forward = op.JaxOperator(lambda t: jnp.asarray(matrix) @ jnp.tanh(t).ravel(), DIMS, (50,),
                             dtype=np.float64)
    x = 0.5 * rng.standard_normal(DIMS)
    problem = solvers.Problem(forward, forward(x), regularizer=op.tikhonov(DIMS, SPACING),
                              lam=7.0)
    prior = regularizer_prior(problem, x, prior_std=1e8)  # floor 1e-16: not part of L
    v = rng.standard_normal(DIMS)
    hv = misfit_hessian(problem, x)(v) + prior.apply(v, -1.0)
    gradient = problem.evaluate(x).grad
    steps = 1e-2 / 2.0 ** np.arange(6)
    errors = [np.linalg.norm((problem.evaluate(x + h * v).grad - gradient) / (2 * h) - hv)
              for h in steps]
    rates = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all(np.abs(rates - 1.0) < 0.1), (errors, rates)
    assert errors[-1] < 1e-3 * np.linalg.norm(hv)


def exact_posterior(problem, matrix, sigma, prior_std):
    """(AᵀWA + a DᵀD + δI)⁻¹ as a dense matrix."""
    differences = op.Gradient(DIMS, SPACING)
    weight = problem.lam * problem.regularizer.functional.scale
    hessian = (matrix.T @ (matrix / sigma[:, None] ** 2)
               + weight * dense(lambda e: differences.adjoint(differences(e)))
               + np.eye(N) / prior_std**2)
    return np.linalg.inv(hessian)


@pytest.mark.parametrize("rank, tolerance", [(60, 1e-8), (25, 0.05)])
def test_standard_deviations_match_the_exact_linear_gaussian_posterior(rank, tolerance):
    """The misfit Hessian has rank 60: all of it gives the exact posterior, its leading 25
    eigenpairs the standard deviations to 5 %."""
    problem, matrix, sigma = linear_problem()
    exact = exact_posterior(problem, matrix, sigma, prior_std=2.0)
    posterior = laplace_posterior(problem, np.zeros(DIMS), rank=rank, prior_std=2.0,
                                  power_iterations=2)
    np.testing.assert_allclose(np.sqrt(posterior.variance()).ravel(), np.sqrt(np.diag(exact)),
                               rtol=tolerance)
    # the two fields of one voxel: their covariance, the off-diagonal of each 2×2 block
    blocks = posterior.voxel_covariance()
    voxels = np.arange(N // 2)
    np.testing.assert_allclose(blocks[0, 1].ravel(), exact[voxels, voxels + N // 2],
                               atol=tolerance * np.sqrt(np.diag(exact)).max() ** 2)
    # left-out directions would only lower the variances: never below the exact ones
    assert np.all(np.sqrt(posterior.variance()).ravel() >= np.sqrt(np.diag(exact)) * (1 - 1e-8))


def test_total_variation_uses_the_quadratic_that_touches_it_at_the_median_difference():
    problem, _, _ = linear_problem(regularizer="tv")
    x = np.random.default_rng(5).standard_normal(DIMS)
    differences = np.abs(op.Gradient(DIMS, SPACING)(x))
    tau = np.median(differences[differences > 0])
    prior = regularizer_prior(problem, x)
    assert prior.weight == pytest.approx(problem.lam / N / (2 * tau))
    assert prior.floor == 1.0


def test_without_a_regularizer_the_floor_is_the_prior():
    problem, _, _ = linear_problem()
    free = solvers.Problem(problem.forward, problem.data)
    prior = regularizer_prior(free, np.zeros(DIMS), prior_std=0.5)
    assert prior.weight == 0.0
    np.testing.assert_allclose(prior.variance(), 0.25)


def test_randomized_eigenpairs_recover_a_low_rank_spectrum():
    rng = np.random.default_rng(2)
    basis = np.linalg.qr(rng.standard_normal((40, 6)))[0]
    matrix = basis @ np.diag([9.0, 7.0, 5.0, 3.0, 2.0, 1.0]) @ basis.T
    values, vectors = randomized_eigenpairs(lambda v: matrix @ v, 40, 4, oversampling=3)
    np.testing.assert_allclose(values, [9.0, 7.0, 5.0, 3.0], rtol=1e-10)
    np.testing.assert_allclose(np.abs(vectors.T @ basis[:, :4]), np.eye(4), atol=1e-8)
    with pytest.raises(ValueError, match="rank must lie in 1..40"):
        randomized_eigenpairs(lambda v: v, 40, 41)


def test_bad_settings_are_refused_with_what_to_give():
    problem, _, _ = linear_problem()
    with pytest.raises(ValueError, match="prior_std must be a finite number > 0"):
        regularizer_prior(problem, np.zeros(DIMS), prior_std=0.0)
    other = solvers.Problem(problem.forward, problem.data,
                            regularizer=(op.SquaredL2(), op.Identity(DIMS)), lam=1.0)
    with pytest.raises(ValueError, match="is not the voxel grid's forward differences"):
        regularizer_prior(other, np.zeros(DIMS))
