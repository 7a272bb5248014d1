"""The learned multi-resolution feature grid of a network: its levels, interpolation and
derivatives."""

import numpy as np
import pytest
import torch

import operators
from invflame.geometry import VoxelGrid
from invflame.representations.neural import FieldNetwork, centre_points
from invflame.representations.neural.feature_grid import interpolate, level_shapes


def test_levels_halve_down_to_two_nodes():
    assert level_shapes((30, 30, 20), 3) == [(8, 8, 5), (15, 15, 10), (30, 30, 20)]
    assert level_shapes((6, 6, 6), 4) == [(2, 2, 2), (2, 2, 2), (3, 3, 3), (6, 6, 6)]
    with pytest.raises(ValueError, match="levels >= 1"):
        level_shapes((8, 8, 8), 0)


@pytest.mark.parametrize("shape", [(5, 4, 3), (2, 7, 1)])
def test_interpolation_is_torchs_trilinear_sampling_with_border_values(shape):
    generator = torch.Generator().manual_seed(0)
    values = torch.randn((1, 3, *shape), generator=generator, dtype=torch.float64)
    unit = 2.4 * torch.rand((400, 3), generator=generator, dtype=torch.float64) - 1.2
    expected = torch.nn.functional.grid_sample(
        values, unit.flip(-1).reshape(1, -1, 1, 1, 3), mode="bilinear",
        padding_mode="border", align_corners=False).reshape(3, -1).T
    torch.testing.assert_close(interpolate(values, unit), expected, rtol=0, atol=1e-13)


def test_interpolation_reproduces_a_linear_function_between_the_centres():
    shape = (4, 5, 6)
    axes = [(np.arange(n) + 0.5) / n * 2 - 1 for n in shape]  # node centres in [-1, 1]
    x, y, z = np.meshgrid(*axes, indexing="ij")
    values = torch.as_tensor((0.3 + 2 * x - y + 0.5 * z)[None, None])
    rng = np.random.default_rng(1)
    lows, highs = [a[0] for a in axes], [a[-1] for a in axes]
    unit = rng.uniform(lows, highs, size=(200, 3))
    expected = 0.3 + 2 * unit[:, 0] - unit[:, 1] + 0.5 * unit[:, 2]
    np.testing.assert_allclose(interpolate(values, torch.as_tensor(unit))[:, 0].numpy(),
                               expected, rtol=0, atol=1e-13)


@pytest.fixture(scope="module")
def network():
    grid = VoxelGrid(np.zeros(3), np.full(3, 0.3), (6, 5, 4))
    net = FieldNetwork(grid, n_frequencies=2, hidden=16, depth=2, grid_levels=2,
                       dtype=torch.float64)
    with torch.no_grad():  # features of order one, as after training
        for level in net.features.levels:
            level.normal_(generator=torch.Generator().manual_seed(2))
    return net


def test_the_finest_level_holds_one_feature_vector_per_voxel(network):
    finest = network.features.levels[-1]
    assert finest.shape == (1, 2, 6, 5, 4)
    unit = network.unit(centre_points(network.grid, torch.float64).reshape(-1, 3))
    values = interpolate(finest, unit).T.reshape(finest.shape[1:])
    torch.testing.assert_close(values, finest[0], rtol=0, atol=1e-14)
    levels = sum(level.numel() for level in network.features.levels)
    assert network.n_parameters == levels + sum(p.numel() for p in network.mlp.parameters())


def test_network_fields_pass_taylor_and_dot_tests_in_float64(network):
    points = centre_points(network.grid, torch.float64)
    op = operators.TorchOperator(lambda theta: network.evaluate(theta, points, normalized=True),
                                 (network.n_parameters,), (4, *network.grid.shape),
                                 dtype=np.float64)
    theta = network.parameter_vector()
    taylor = operators.taylor_test(op, theta, h0=1e-2, seed=0)
    assert taylor.passed, str(taylor)
    dot = operators.jacobian_dottest(op, theta, seed=0)
    assert dot.passed, str(dot)
