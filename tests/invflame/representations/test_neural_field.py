"""The field network: shapes, ranges, flat weights, pretraining."""

import numpy as np
import pytest
import torch

from invflame.geometry import VoxelGrid
from invflame.representations.neural import network as network_module
from invflame.representations.neural.network import (
    AMBIENT_START,
    FieldNetwork,
    centre_points,
    pretrain,
)
from invflame.representations.normalization import SCALES
from invflame.representations.state_relation import StateRelation

GRID = VoxelGrid.poolfire(8)


def test_outputs_have_field_shape_and_stay_in_range_for_any_weights():
    network = FieldNetwork(GRID, temperature_range=(250.0, 2500.0), seed=3)
    assert network.encode(torch.zeros(5, 3)).shape == (5, 63)
    points = torch.tensor(np.random.default_rng(0).uniform(-2.0, 3.0, (7, 11, 3)),
                          dtype=torch.float32)
    wild = 30.0 * torch.randn(network.n_parameters, generator=torch.Generator().manual_seed(1))
    out = network.evaluate(wild, points)
    assert out.shape == (4, 7, 11)
    assert torch.all((out[0] >= 250.0) & (out[0] <= 2500.0))
    assert torch.all((out[1:] >= 0.0) & (out[1:] <= 1.0))
    assert out[0].max() - out[0].min() > 100.0  # the range is used, not a constant


def test_points_run_in_passes_give_the_values_and_derivatives_of_one_pass(monkeypatch):
    network = FieldNetwork(GRID, seed=2, dtype=torch.float64)
    points = torch.tensor(np.random.default_rng(4).uniform(0.0, 1.0, (5, 9, 3)))
    theta = torch.tensor(network.parameter_vector())
    tangent, cotangent = torch.randn_like(theta), torch.randn(4, 5, 9, dtype=torch.float64)

    def value_and_products():
        fun = lambda t: network.evaluate(t, points)  # noqa: E731
        value, pull = torch.func.vjp(fun, theta)
        return value, torch.func.jvp(fun, (theta,), (tangent,))[1], pull(cotangent)[0]

    whole = value_and_products()
    monkeypatch.setattr(network_module, "POINTS_PER_PASS", 7)  # 45 points: 7 passes
    for passes, one in zip(value_and_products(), whole, strict=True):
        torch.testing.assert_close(passes, one, rtol=1e-13, atol=1e-13)


def test_untrained_network_starts_near_ambient():
    out = FieldNetwork(GRID)(centre_points(GRID)).detach().numpy()
    np.testing.assert_allclose(out.reshape(4, -1).mean(axis=1), AMBIENT_START, rtol=0.05)


def test_flat_weights_round_trip_and_drive_the_evaluation():
    a, b = FieldNetwork(GRID, seed=0), FieldNetwork(GRID, seed=1)
    points = centre_points(GRID)
    theta_b = torch.tensor(b.parameter_vector())
    assert a.n_parameters == 63 * 64 + 64 + 3 * (64 * 64 + 64) + 64 * 4 + 4
    assert not torch.allclose(a(points), b(points))
    torch.testing.assert_close(a.evaluate(theta_b, points), b(points))
    a.load_vector(theta_b.numpy())
    torch.testing.assert_close(a(points), b(points))
    torch.testing.assert_close(a.evaluate(theta_b, points, normalized=True),
                               b(points) / torch.tensor(SCALES, dtype=torch.float32)[:, None,
                                                                                    None, None])
    with pytest.raises(ValueError, match="weight vector must have shape"):
        a.evaluate(theta_b[:-1], points)


def test_pretraining_fits_the_target_field(plume):
    network = FieldNetwork(GRID, seed=0)
    target = plume / SCALES[:, None, None, None]

    def error():
        with torch.no_grad():
            fit = network.normalized(centre_points(GRID)).numpy()
        return np.mean((fit - target) ** 2)

    before = error()
    losses = pretrain(network, plume, iterations=150, lr=3e-3, seed=0, progress=False)
    assert losses.shape == (150,)
    assert error() < 0.1 * before
    assert losses[-10:].mean() < 0.1 * losses[:10].mean()


def test_pretraining_rejects_a_field_on_another_grid(plume):
    with pytest.raises(ValueError, match="target must have shape"):
        pretrain(FieldNetwork(VoxelGrid.poolfire(4)), plume, iterations=1, progress=False)


def _relation_fields():
    relation = StateRelation([300.0, 4e-4, 0.01, 2e-6])
    rng = np.random.default_rng(5)
    progress = rng.uniform(0.05, 0.5, GRID.shape)
    progress[:2] = 0.0  # ambient air
    fields = np.stack(relation.states(progress, rng.uniform(0.5, 1.8, GRID.shape)))
    return relation, fields


def test_a_network_offset_by_fields_starts_at_them_and_interpolates_between_centres():
    relation, fields = _relation_fields()
    network = FieldNetwork(GRID, 4, seed=1, dtype=torch.float64, state_relation=relation)
    network.offset_by(fields)
    out = network(centre_points(GRID, torch.float64)).detach().numpy()
    s, h = relation.invert(fields)
    margin = relation.progress_max * network_module.OFFSET_MARGIN
    expected = np.stack(relation.states(np.maximum(s, margin), h))
    np.testing.assert_allclose(out, expected, rtol=1e-10, atol=1e-12)
    assert np.all(np.abs(out[0][2:] - fields[0][2:]) < 1e-8)  # exact inside the flame
    assert np.all(out[0][:2] - 300.0 < 3.0)  # air stays within a few K of ambient
    centres = centre_points(GRID, torch.float64)
    between = 0.25 * centres[1, 2, 3] + 0.75 * centres[2, 2, 3]
    pre = network.preactivations(fields)
    np.testing.assert_allclose(network._offset_at(between[None]).numpy()[0],
                               0.25 * pre[:, 1, 2, 3] + 0.75 * pre[:, 2, 2, 3], rtol=1e-12)
    last = network.mlp[-1]
    assert not last.weight.any() and not last.bias.any()


def test_offset_needs_a_state_relation_and_fields_on_the_grid():
    relation, fields = _relation_fields()
    with pytest.raises(ValueError, match="state relation"):
        FieldNetwork(GRID).offset_by(fields)
    with pytest.raises(ValueError, match="on the network's grid"):
        FieldNetwork(GRID, state_relation=relation).offset_by(fields[:, :4])
