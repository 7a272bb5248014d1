"""σ of the fields from the parameters' posterior: the state relation's Jacobian against finite
differences, the propagation, the calibration's shares."""

import numpy as np
import pytest

import operators as op
from invflame.experiments.uncertainty import (
    calibration,
    field_sigma,
    voxel_jacobian,
    z_scores,
)
from invflame.geometry import VoxelGrid
from invflame.representations.state_relation import StateRelation
from invflame.representations.voxel import VoxelRepresentation

GRID = VoxelGrid.poolfire(3)


def representation(state_relation=True):
    relation = StateRelation([300.0, 4e-4, 0.01, 2e-6]) if state_relation else None
    return VoxelRepresentation(GRID, op.Identity((4, *GRID.shape)), state_relation=relation)


def parameters(rep, seed=0):
    """Parameters inside the bounds, float64."""
    rng = np.random.default_rng(seed)
    lower, upper = rep.lower, rep.upper
    return lower + (upper - lower) * rng.uniform(0.1, 0.9, rep.dims)


def finite_difference_jacobian(rep, theta, step=1e-6):
    """∂fields/∂θ_p per voxel by central differences of ``rep.fields``."""
    columns = []
    for p in range(rep.dims[0]):
        shift = np.zeros(rep.dims)
        shift[p] = step
        columns.append((rep.fields(theta + shift) - rep.fields(theta - shift)) / (2 * step))
    return np.stack(columns, axis=1)


@pytest.mark.parametrize("state_relation", [True, False])
def test_the_voxel_jacobian_matches_finite_differences_of_the_fields(state_relation):
    rep = representation(state_relation)
    theta = parameters(rep)
    jacobian = voxel_jacobian(rep, theta)
    assert jacobian.shape == (4, rep.dims[0], *GRID.shape)
    expected = finite_difference_jacobian(rep, theta)
    scale = np.abs(expected).max(axis=(1, 2, 3, 4), keepdims=True)  # per field: K, 1
    np.testing.assert_allclose(jacobian / scale, expected / scale, atol=1e-7)


def test_sigma_of_temperature_is_the_propagated_two_by_two_block():
    """σ_T² = gᵀ Σ g per voxel, g the finite-difference gradient of T by (s, h)."""
    rep = representation()
    theta = parameters(rep, seed=1)
    rng = np.random.default_rng(2)
    factors = rng.standard_normal((2, 2, *GRID.shape)) * 0.01
    covariance = np.einsum("pkxyz,qkxyz->pqxyz", factors, factors)  # SPD per voxel
    sigma = field_sigma(voxel_jacobian(rep, theta), covariance)
    g = finite_difference_jacobian(rep, theta)[0]  # (2, nx, ny, nz), K per parameter unit
    expected = np.sqrt(np.einsum("pxyz,pqxyz,qxyz->xyz", g, covariance, g))
    np.testing.assert_allclose(sigma[0], expected, rtol=1e-6)
    # at the progress's bound s = 0 (ambient air) T depends on s only: σ_T = |∂T/∂s| σ_s
    theta[0] = 0.0
    jacobian = voxel_jacobian(rep, theta)
    np.testing.assert_allclose(jacobian[0, 1], 0.0, atol=1e-12)
    np.testing.assert_allclose(field_sigma(jacobian, covariance)[0],
                               np.abs(jacobian[0, 0]) * np.sqrt(covariance[0, 0]), rtol=1e-12)


def test_calibration_counts_the_truths_within_one_and_two_sigma():
    shape = (4, 4, 1, 1)
    truth = np.zeros(shape)
    truth[0] = np.array([300.0, 300.0, 900.0, 900.0]).reshape(4, 1, 1)
    sigma = np.ones(shape)
    errors = np.array([0.5, 1.5, 2.5, 0.0]).reshape(4, 1, 1)  # |z| per voxel
    estimate = truth + errors
    shares = calibration(truth, estimate, sigma, hot=500.0)
    assert shares["T"]["all"] == {"voxels": 4, "within_1sigma": 0.5, "within_2sigma": 0.75}
    assert shares["T"]["hot"] == {"voxels": 2, "within_1sigma": 0.5, "within_2sigma": 0.5}
    assert shares["expected"]["within_1sigma"] == pytest.approx(0.6827)
    cold = calibration(truth, estimate, sigma, hot=5000.0)
    assert cold["CO2"]["hot"] == {"voxels": 0, "within_1sigma": None, "within_2sigma": None}


def test_z_scores_of_exact_values_are_zero_even_where_sigma_is():
    z = z_scores(np.array([1.0, 1.0, 1.0]), np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 4.0]))
    np.testing.assert_array_equal(z, [0.0, np.inf, 0.5])
