"""The neural reparameterization at voxel centres: derivatives and solvers on weights."""

import numpy as np
import pytest

import operators
import solvers
from invflame.representations.neural import NeuralCentresRepresentation


@pytest.fixture(scope="module")
def centres64(tiny_scene64, plume):
    rep = NeuralCentresRepresentation(tiny_scene64, seed=0)
    theta = rep.initial_parameters(plume, iterations=30, lr=3e-3, progress=False)
    return rep, theta


def test_forward_map_passes_a_taylor_test_in_float64(centres64):
    rep, theta = centres64
    assert rep.forward.dims == (rep.n_parameters,)
    assert rep.forward.dimsd == rep.scene.data_shape
    result = operators.taylor_test(rep.forward, theta, h0=1e-3, seed=0)
    assert result.passed, str(result)


def test_forward_is_the_voxel_map_of_the_network_fields(centres64):
    rep, theta = centres64
    fields = rep.fields(theta)
    assert fields.shape == (4, 8, 8, 8)
    np.testing.assert_allclose(rep.forward(theta), rep.scene.simulate(fields), rtol=1e-10)


@pytest.mark.parametrize("kind", ["tikhonov", "tv"])
def test_regularizer_is_the_voxel_one_on_normalized_network_fields(centres64, kind):
    rep, theta = centres64
    expected = operators.tikhonov if kind == "tikhonov" else operators.total_variation
    normalized = rep.fields(theta) / np.array([1000.0, 0.1, 0.1, 0.1])[:, None, None, None]
    value = rep.regularizer(kind)(theta)
    assert value == pytest.approx(expected((4, 8, 8, 8), tuple(rep.grid.spacing))(normalized))
    assert value > 0
    assert rep.regularizer("none") is None


@pytest.fixture(scope="module")
def centres32(tiny_scene, plume):
    rep = NeuralCentresRepresentation(tiny_scene, seed=0)
    start = plume.copy()
    start[0] = 0.8 * plume[0] + 60.0  # a cooler flame than the data's
    theta = rep.initial_parameters(start, iterations=40, lr=3e-3, progress=False)
    return rep, theta, tiny_scene.simulate(plume)


def test_adam_lowers_the_neural_centres_loss(centres32):
    rep, theta, data = centres32
    problem = rep.problem(data, "tv", x0=theta)
    assert problem.metadata["representation"] == "neural-centres"
    result = solvers.solve(problem, "adam", lr=2e-3, max_iter=10)
    assert problem.objective(result.x) < 0.85 * problem.objective(theta)


def test_gauss_newton_runs_on_network_weights(centres32):
    rep, theta, data = centres32
    problem = rep.problem(data, "tikhonov", x0=theta)
    result = solvers.solve(problem, "gauss-newton", max_iter=2, inner_iter=10)
    assert result.iterations >= 1
    assert problem.objective(result.x) < 0.5 * problem.objective(theta)


def test_noise_weighted_objective_divides_the_residuals_by_sigma(centres32):
    rep, theta, data = centres32
    sigma = np.linspace(1.0, 3.0, data.shape[1]) * 1e-2 * np.abs(data).max()
    problem = rep.problem(data, "tv", lam=0.5, x0=theta, sigma=sigma)
    residual = (rep.forward(theta) - data) / sigma
    expected = np.sum(residual**2) + 0.5 * rep.regularizer("tv")(theta)
    assert problem.objective(theta) == pytest.approx(expected, rel=1e-5)
    assert rep.iterations_per_epoch == 1


@pytest.fixture(scope="module")
def grid_network(tiny_scene, plume):
    rep = NeuralCentresRepresentation(tiny_scene, n_frequencies=2, hidden=16, depth=2, seed=0,
                                      grid_levels=2)
    theta = rep.initial_parameters(plume, iterations=40, lr=3e-3, progress=False)
    return rep, theta, tiny_scene.simulate(plume)


def test_a_feature_grid_network_is_rendered_and_taylor_tested(grid_network):
    rep, theta, _ = grid_network
    assert rep.n_parameters > sum(level.numel() for level in rep.network.features.levels)
    result = operators.taylor_test(rep.forward, theta, h0=1e-3, seed=0)
    assert result.passed, str(result)


def test_the_preconditioner_is_the_inverse_curvature_of_each_weight_tensor(grid_network):
    rep, theta, data = grid_network
    problem = rep.problem(data, "tikhonov", lam=1.0, x0=theta)
    assert callable(problem._preconditioner)  # built when a solver asks
    diagonal = problem.preconditioner.diagonal.ravel()
    sizes = [p.numel() for p in rep.network.parameters()]
    per_tensor = np.split(diagonal, np.cumsum(sizes)[:-1])
    assert all(np.all(d == d[0]) and d[0] > 0 for d in per_tensor)
    assert len({float(d[0]) for d in per_tensor}) == len(sizes)  # tensors differ
    unweighted = rep.problem(data, "tikhonov", lam=0.0, x0=theta).preconditioner.diagonal
    assert np.all(diagonal <= unweighted.ravel())  # the regularizer adds curvature
    assert rep.problem(data, "none").preconditioner is None


def test_preconditioned_lbfgs_lowers_the_feature_grid_networks_objective(grid_network):
    rep, theta, data = grid_network
    problem = rep.problem(data, "tikhonov", lam=1.0, x0=theta)
    result = solvers.solve(problem, "preconditioned-lbfgs", max_iter=5)
    assert problem.objective(result.x) < 0.5 * problem.objective(theta)
