"""The NeRF-like representation: sampling, rendering against the voxel map, the problem."""

import numpy as np
import pytest
import torch

import operators
import solvers
from invflame.representations.neural import NeuralFieldRepresentation, NeuralRenderer
from invflame.representations.neural_sampling import (
    PlanckMeanOpacity,
    emission_weights,
    importance,
    sample_bounds,
    sample_lengths,
    stratified,
)


def test_sample_lengths_partition_the_chord():
    rng = np.random.default_rng(0)
    t_near = torch.tensor([0.2, 1.0, 0.0], dtype=torch.float64)
    t_far = torch.tensor([1.4, 1.1, 0.0], dtype=torch.float64)  # last ray misses the box
    t = stratified(t_near, t_far, torch.tensor(rng.random((3, 16))))
    assert torch.all(torch.diff(t, dim=1) >= 0)
    assert torch.all((t >= t_near[:, None]) & (t <= t_far[:, None]))
    lengths = sample_lengths(t, t_near, t_far)
    assert torch.all(lengths >= 0)
    torch.testing.assert_close(lengths.sum(dim=1), t_far - t_near)
    midpoints = stratified(t_near, t_far, torch.full((3, 16), 0.5, dtype=torch.float64))
    torch.testing.assert_close(sample_lengths(midpoints, t_near, t_far),
                               ((t_far - t_near) / 16)[:, None].expand(3, 16))


def test_importance_samples_follow_the_emission_weights():
    t_near, t_far = torch.zeros(1, dtype=torch.float64), torch.ones(1, dtype=torch.float64)
    t = stratified(t_near, t_far, torch.full((1, 10), 0.5, dtype=torch.float64))
    lengths = sample_lengths(t, t_near, t_far)
    kappa = torch.zeros(1, 10, dtype=torch.float64)
    kappa[0, 6] = 50.0  # one hot, opaque interval, 0.6-0.7 m
    weights = emission_weights(kappa, lengths)
    assert weights[0, 6] == pytest.approx(1 - np.exp(-5.0))
    u = torch.tensor(np.random.default_rng(1).random((1, 1000)))
    drawn = importance(sample_bounds(t, t_near, t_far), weights, u)
    assert torch.all((drawn >= 0) & (drawn <= 1))
    inside = ((drawn >= 0.6) & (drawn <= 0.7)).double().mean().item()
    assert inside > 0.95  # the floor leaves a little probability elsewhere
    assert torch.any(drawn < 0.6)


def test_planck_mean_opacity_interpolates_the_table(tiny_table):
    opacity = PlanckMeanOpacity.from_table(tiny_table)
    rng = np.random.default_rng(2)
    temperature = rng.uniform(300.0, 2400.0, 20)
    fractions = rng.uniform(0.0, 0.2, (3, 20))
    expected = tiny_table.planck_mean_kappa(temperature, fractions)
    got = opacity(torch.tensor(np.concatenate([temperature[None], fractions])))
    np.testing.assert_allclose(got.numpy(), expected, rtol=0.02)
    assert np.all(expected > 0)


def _voxel_lookup(grid, values):
    """The voxel field as a function of position: piecewise constant per voxel."""
    values = torch.tensor(values)
    lower, spacing = torch.tensor(grid.lower), torch.tensor(grid.spacing)
    top = torch.tensor(grid.shape) - 1

    def field(points):
        i = torch.minimum(torch.floor((points - lower) / spacing).long().clamp_min(0), top)
        return values[:, i[..., 0], i[..., 1], i[..., 2]]

    return field


def test_rendering_converges_to_the_voxel_forward_map(tiny_scene64, plume):
    """Sampled finely, the renderer of a voxel field reproduces the voxel forward map: the
    same emission physics; the only difference is where samples straddle voxel faces."""
    expected = tiny_scene64.simulate(plume)
    field = _voxel_lookup(tiny_scene64.grid, plume)
    renderer = NeuralRenderer(tiny_scene64, n_coarse=256, n_fine=256)
    coarse, fine = renderer.render(torch.arange(renderer.n_rays), field, field,
                                   *renderer.deterministic_draws())
    scale = np.abs(expected).max()
    assert np.abs(coarse.numpy() - expected).max() < 0.01 * scale
    assert np.abs(fine.numpy() - expected).max() < 0.01 * scale
    rough = NeuralRenderer(tiny_scene64, n_coarse=8, n_fine=0)
    coarse8, _ = rough.render(torch.arange(rough.n_rays), field, field,
                              *rough.deterministic_draws())
    assert np.abs(coarse8.numpy() - expected).max() > 0.02 * scale  # the test can fail


@pytest.fixture(scope="module")
def neural64(tiny_scene64, plume):
    rep = NeuralFieldRepresentation(tiny_scene64, n_coarse=8, n_fine=8, batch_rays=36,
                                    batch_centres=64)
    theta = rep.initial_parameters(plume, iterations=30, lr=3e-3, progress=False)
    return rep, theta


def test_deterministic_forward_operator_has_consistent_derivatives(neural64, plume):
    rep, theta = neural64
    problem = rep.problem(rep.scene.simulate(plume), "tikhonov", x0=theta)
    forward = problem.forward
    assert forward.dims == (rep.n_parameters,) and forward.dimsd == rep.scene.data_shape
    value = forward(theta)
    assert value.shape == rep.scene.data_shape and np.all(value > 0)
    assert operators.jacobian_dottest(forward, theta, rtol=1e-9).passed
    fine_only = np.zeros_like(theta)
    fine_only[rep.coarse.n_parameters:] = np.random.default_rng(0).standard_normal(
        rep.fine.n_parameters)
    assert operators.taylor_test(forward, theta, fine_only, h0=1e-3).passed


def test_stochastic_gradient_passes_a_taylor_test(neural64, plume):
    """With the sample of one iteration fixed, the loss is a smooth function of the fine
    weights (the coarse weights move the importance samples, which are not differentiated)."""
    rep, theta = neural64
    problem = rep.problem(rep.scene.simulate(plume), "tikhonov", lam=1e-2, x0=theta)

    def loss(x):
        return problem.value_and_grad(x, 0, np.random.default_rng(7))[0]

    direction = np.zeros_like(theta)
    direction[rep.coarse.n_parameters:] = np.random.default_rng(1).standard_normal(
        rep.fine.n_parameters)
    grad = problem.value_and_grad(theta, 0, np.random.default_rng(7))[1]
    result = operators.gradient_taylor_test(loss, grad, theta, direction, h0=1e-4)
    assert result.passed, str(result)


def test_stochastic_regularizer_estimates_the_deterministic_one(neural64):
    rep, theta = neural64
    theta_f = rep.split(torch.tensor(theta))[1]
    for kind in ("tikhonov", "tv"):
        full = rep._regularizer(kind)(theta)
        assert rep.regularizer_terms(theta_f, rep.centres, kind).item() == pytest.approx(full)
        batches = [rep.regularizer_terms(theta_f, rep.centres[i], kind).item()
                   for i in np.random.default_rng(0).integers(0, 512, (10, 128))]
        assert np.mean(batches) == pytest.approx(full, rel=0.15)


def test_adam_lowers_the_neural_field_loss(tiny_scene, plume):
    rep = NeuralFieldRepresentation(tiny_scene, n_coarse=8, n_fine=8, batch_rays=36,
                                    batch_centres=64)
    truth = rep.scene.simulate(plume)
    start = plume.copy()
    start[0] = 0.8 * plume[0] + 60.0  # a cooler flame than the data's
    theta = rep.initial_parameters(start, iterations=40, lr=3e-3, progress=False)
    problem = rep.problem(truth, "tikhonov", x0=theta)
    result = solvers.solve(problem, "adam", lr=2e-3, max_iter=12, seed=0)
    assert result.iterations == 12
    assert problem.objective(result.x) < 0.7 * problem.objective(theta)
    fields = rep.fields(result.x)
    assert fields.shape == (4, 8, 8, 8) and np.all(fields[0] >= 250.0)
    assert rep.parameter_bytes(result.x) == 4 * rep.n_parameters


def test_gauss_newton_refuses_the_neural_field_with_advice(tiny_scene, plume):
    rep = NeuralFieldRepresentation(tiny_scene, n_coarse=4, n_fine=4, batch_rays=8)
    problem = rep.problem(np.zeros(tiny_scene.data_shape), x0=rep.initial_parameters())
    with pytest.raises(solvers.UnsupportedProblemError,
                       match="(?s)neural-field.*neural-centres.*adam"):
        solvers.solve(problem, "gauss-newton", max_iter=1)


def test_unknown_regularizer_is_rejected(tiny_scene):
    rep = NeuralFieldRepresentation(tiny_scene, n_coarse=4, n_fine=4, batch_rays=8)
    with pytest.raises(ValueError, match="choose one of none, tikhonov, tv"):
        rep.problem(np.zeros(tiny_scene.data_shape), "l2")
