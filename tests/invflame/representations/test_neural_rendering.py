"""The NeRF-like representation: sampling, rendering against the voxel map, the problem."""

from types import SimpleNamespace

import numpy as np
import pytest
import torch

import operators
import solvers
from invflame.representations.neural import NeuralFieldRepresentation, NeuralRenderer
from invflame.representations.neural.renderer import voxel_lookup
from invflame.representations.neural.sampling import (
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
    """At the fixed broadening fractions it is the table's Planck mean, interpolated in T."""
    opacity = PlanckMeanOpacity.from_table(tiny_table)
    rng = np.random.default_rng(2)
    temperature = rng.uniform(300.0, 2400.0, 20)
    fractions = np.zeros((3, 20))
    fractions[0, ::2], fractions[1, 1::2] = 0.1, 0.2  # CO2 or H2O alone, at its fixed fraction
    expected = tiny_table.planck_mean_kappa(temperature, fractions)
    got = opacity(torch.tensor(np.concatenate([temperature[None], fractions])))
    np.testing.assert_allclose(got.numpy(), expected, rtol=0.02)
    assert np.all(expected > 0)


@pytest.mark.parametrize("scene_name", ["tiny_scene64", "pixel_scene64"])
def test_rendering_converges_to_the_voxel_forward_map(scene_name, plume, request):
    """Sampled finely, the renderer of a voxel field reproduces the voxel forward map: the
    same emission physics and the same mean over a pixel's sub-rays; the only difference is
    where samples straddle voxel faces."""
    scene = request.getfixturevalue(scene_name)
    expected = scene.simulate(plume)
    field = voxel_lookup(scene.grid, plume)
    renderer = NeuralRenderer(scene, n_coarse=256, n_fine=256)
    assert renderer.batch_sub_rays == scene.n_rays * scene.rays_per_pixel
    coarse, fine = renderer.render(torch.arange(renderer.n_rays), field, field,
                                   *renderer.deterministic_draws())
    assert coarse.shape == fine.shape == scene.data_shape
    scale = np.abs(expected).max()
    assert np.abs(coarse.numpy() - expected).max() < 0.01 * scale
    assert np.abs(fine.numpy() - expected).max() < 0.01 * scale
    rough = NeuralRenderer(scene, n_coarse=8, n_fine=0)
    coarse8, _ = rough.render(torch.arange(rough.n_rays), field, field,
                              *rough.deterministic_draws())
    assert np.abs(coarse8.numpy() - expected).max() > 0.02 * scale  # the test can fail


def test_a_pixel_is_the_mean_of_its_sub_rays(pixel_scene64, plume):
    """Rendered as pixels of their own, the sub-rays of a pixel differ; the pixel's spectrum
    is their mean."""
    scene = pixel_scene64
    as_pixels = SimpleNamespace(
        n_rays=scene.segments.n_rays, rays_per_pixel=1, segments=scene.segments,
        dtype=scene.dtype, ils=scene.ils, table=scene.table, tables=scene.tables,
        memory_budget=scene.memory_budget)
    field = voxel_lookup(scene.grid, plume)
    pixels, sub_rays = (NeuralRenderer(s, n_coarse=16, n_fine=0) for s in (scene, as_pixels))
    assert sub_rays.n_rays == 4 * pixels.n_rays
    mean = pixels.render(torch.arange(pixels.n_rays), field, field,
                         *pixels.deterministic_draws())[0].numpy()
    single = sub_rays.render(torch.arange(sub_rays.n_rays), field, field,
                             *sub_rays.deterministic_draws())[0].numpy()
    single = single.reshape(pixels.n_rays, 4, -1)
    np.testing.assert_allclose(mean, single.mean(axis=1), rtol=1e-12)
    hot = np.argmax(mean.max(axis=1))
    assert np.ptp(single[hot].max(axis=1)) > 0.01 * mean[hot].max()  # sub-rays differ


@pytest.fixture(scope="module")
def neural64(pixel_scene64, plume):
    rep = NeuralFieldRepresentation(pixel_scene64, n_coarse=8, n_fine=8, batch_rays=36,
                                    batch_centres=64)
    theta = rep.initial_parameters(plume, iterations=30, lr=3e-3, progress=False)
    return rep, theta


def test_deterministic_forward_operator_has_consistent_derivatives(neural64, plume):
    rep, theta = neural64
    sigma = np.linspace(1.0, 2.0, rep.scene.data_shape[1])
    data = rep.scene.simulate(plume)
    problem = rep.problem(data, "tikhonov", x0=theta, sigma=sigma)
    forward = problem.forward
    assert forward.dims == (rep.n_parameters,) and forward.dimsd == rep.scene.data_shape
    value = forward(theta)
    assert value.shape == rep.scene.data_shape and np.all(value > 0)
    np.testing.assert_allclose(problem.data, data / sigma)
    np.testing.assert_allclose(value * sigma, rep.problem(data).forward(theta), rtol=1e-12)
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


def test_epoch_batches_cover_every_pixel_without_repeats_in_a_batch(tiny_scene):
    rep = NeuralFieldRepresentation(tiny_scene, n_coarse=4, n_fine=4, batch_rays=10, seed=3)
    assert rep.iterations_per_epoch == 8  # ceil(72 / 10)
    batches = rep.epoch_batches(5)
    assert batches.shape == (8, 10)
    assert set(batches.ravel()) == set(range(72))
    assert all(len(set(batch)) == 10 for batch in batches)
    np.testing.assert_array_equal(batches, rep.epoch_batches(5))  # a resume sees the same
    assert not np.array_equal(batches, rep.epoch_batches(6))
    whole = NeuralFieldRepresentation(tiny_scene, n_coarse=4, n_fine=4, batch_rays=500)
    assert whole.iterations_per_epoch == 1 and whole.renderer.batch_rays == 72


def test_an_epoch_of_batch_losses_averages_to_the_deterministic_objective(pixel_scene64, plume):
    """With the samples of the evaluation (bin midpoints), equal coarse and fine weights (no
    importance samples, so both renderings agree) and the regularizer over all centres, the
    batch losses of an epoch average to the deterministic, noise-weighted objective: the
    training loss estimates the same sum of squares and the same λΦ."""
    rep = NeuralFieldRepresentation(pixel_scene64, n_coarse=8, n_fine=0, batch_rays=24,
                                    batch_centres=10**6)
    fine = rep.initial_parameters(plume, iterations=20, lr=3e-3, progress=False)
    theta = np.concatenate([fine[rep.coarse.n_parameters:]] * 2)
    sigma = np.linspace(0.5, 1.5, rep.scene.data_shape[1]) * 1e-3
    start = plume.copy()
    start[0] = 0.9 * plume[0] + 30.0
    data = rep.scene.simulate(start)
    for kind in ("none", "tv"):
        problem = rep.problem(data, kind, lam=0.3, x0=theta, sigma=sigma)
        objective = problem.value_and_grad
        draws = rep.renderer.deterministic_draws()
        centres = torch.arange(rep.grid.n_voxels)
        losses = [objective.loss(torch.tensor(theta), torch.as_tensor(pixels), *draws,
                                 centres).item()
                  for pixels in rep.epoch_batches(0)]
        assert rep.iterations_per_epoch == len(losses) == 3
        assert np.mean(losses) == pytest.approx(problem.objective(theta), rel=1e-10)
        assert np.ptp(losses) > 0.01 * np.mean(losses)  # the batches do differ


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
