"""The neural field's regularizer is the voxel regularizer of the network at the voxel centres."""

import numpy as np
import pytest
import torch

from invflame.geometry import VoxelGrid
from invflame.representations.neural import CentreRegularizer, NeuralFieldRepresentation, pretrain
from invflame.representations.normalization import SCALES, normalize
from invflame.representations.voxel import regularizer_for

KINDS = ["tikhonov", "tv"]


def _hot_blob(points: torch.Tensor) -> torch.Tensor:
    """Physical fields (T in K, mole fractions) of a Gaussian hot blob at ``points`` (m):
    shape ``(4, ...)``; methane in a second, smaller blob."""
    def gaussian(centre, width):
        offset = points - torch.tensor(centre, dtype=points.dtype)
        return torch.exp(-0.5 * torch.sum(offset**2, dim=-1) / width**2)

    flame, fuel = gaussian([0.05, 0.35, -0.05], 0.18), gaussian([-0.1, 0.15, 0.1], 0.12)
    return torch.stack([300.0 + 1500.0 * flame, 0.1 * flame, 0.12 * flame, 0.05 * fuel])


def _normalized_blob(points: torch.Tensor) -> torch.Tensor:
    fields = _hot_blob(points)
    return fields / torch.tensor(SCALES, dtype=points.dtype).reshape(
        (4,) + (1,) * (fields.ndim - 1))


# an anisotropic grid, different sizes per axis: catches mixed-up axes or spacings
GRID = VoxelGrid(lower=[-0.5, 0.0, -0.4], upper=[0.5, 0.9, 0.4], shape=(7, 9, 6))


def _voxel_value(kind, grid, normalized_fields):
    return regularizer_for(kind, grid)(np.asarray(normalized_fields, dtype=np.float64))


@pytest.mark.parametrize("kind", KINDS)
def test_over_all_centres_it_is_the_voxel_regularizer(kind):
    estimate = CentreRegularizer(kind, GRID, torch.float64)
    centres = torch.tensor(GRID.centres())
    expected = _voxel_value(kind, GRID, _normalized_blob(centres).numpy())
    value = estimate(_normalized_blob, torch.arange(GRID.n_voxels)).item()
    assert value == pytest.approx(expected, rel=1e-12)
    assert expected > 0


@pytest.mark.parametrize("kind", KINDS)
def test_a_random_batch_is_an_unbiased_estimate(kind):
    """Batches of a random partition of the voxels average exactly to the full value (the mean
    over all equally likely batches is that average over partitions); single batches differ."""
    estimate = CentreRegularizer(kind, GRID, torch.float64)
    full = estimate(_normalized_blob, torch.arange(GRID.n_voxels)).item()
    order = torch.as_tensor(np.random.default_rng(0).permutation(GRID.n_voxels))
    batches = [estimate(_normalized_blob, b).item() for b in order.split(GRID.n_voxels // 6)]
    assert len(batches) == 6
    assert np.mean(batches) == pytest.approx(full, rel=1e-12)
    assert np.ptp(batches) > 0.05 * full


def test_unknown_kind_is_rejected():
    with pytest.raises(ValueError, match="'tikhonov' or 'tv'"):
        CentreRegularizer("l2", GRID)


@pytest.fixture(scope="module")
def fitted_blob(tiny_scene):
    """The representation with its fine network fitted to the hot blob at the voxel centres,
    and the blob's normalized values there."""
    rep = NeuralFieldRepresentation(tiny_scene, n_coarse=4, n_fine=4, batch_rays=8,
                                    n_frequencies=4)
    blob = _hot_blob(torch.tensor(rep.grid.centres())).numpy()
    pretrain(rep.fine, blob, iterations=400, lr=5e-3, progress=False)
    return rep, rep.initial_parameters(), normalize(blob)


@pytest.mark.parametrize("kind", KINDS)
def test_network_fitted_to_a_smooth_field_has_its_voxel_regularizer(fitted_blob, kind):
    """The network's regularizer is within 5 % of the voxel regularizer of the field it was
    fitted to; its deterministic and all-centre training values and the voxel regularizer of
    its fields are the same number to round-off."""
    rep, theta, blob = fitted_blob
    deterministic = rep.regularizer(kind)(theta)
    theta_f = rep.split(torch.tensor(theta))[1]
    training = CentreRegularizer(kind, rep.grid)(
        lambda p: rep.fine.evaluate(theta_f, p, normalized=True),
        torch.arange(rep.grid.n_voxels)).item()
    of_fields = _voxel_value(kind, rep.grid, normalize(rep.fields(theta).astype(np.float64)))
    assert deterministic == pytest.approx(of_fields, rel=1e-5)  # float32 network
    assert training == pytest.approx(of_fields, rel=1e-5)
    assert deterministic == pytest.approx(_voxel_value(kind, rep.grid, blob), rel=0.05)
    assert rep.regularizer("none") is None
