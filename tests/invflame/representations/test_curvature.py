"""The objective's curvature per group of parameters (Hutchinson), for preconditioners."""

import numpy as np
import pytest

import operators as op
from invflame.representations.curvature import by_field, group_curvature, quadratic_weight


def test_curvature_is_the_mean_squared_jacobian_column_per_field():
    """For a diagonal map the Rademacher probes are exact: sum of d² per field over its size."""
    weights = np.random.default_rng(0).uniform(0.5, 2.0, (2, 3, 4, 5))
    expected = (weights.reshape(2, -1) ** 2).mean(axis=1)
    curvature = group_curvature(op.Diagonal(weights), np.zeros(weights.shape),
                                by_field(weights.shape))
    np.testing.assert_allclose(curvature, expected, rtol=1e-12)


def test_any_grouping_and_a_weighted_regularizer_add_up():
    weights = np.random.default_rng(1).uniform(0.5, 2.0, 12)
    regularizer = np.random.default_rng(2).uniform(0.5, 2.0, 12)
    groups = np.array([0, 1, 2, 0, 1, 2, 2, 2, 1, 0, 0, 1])
    curvature = group_curvature(op.Diagonal(weights), np.zeros(12), groups,
                                regularizer=op.Diagonal(regularizer), weight=3.0)
    squares = weights**2 + 3.0 * regularizer**2
    expected = [squares[groups == g].mean() for g in range(3)]
    np.testing.assert_allclose(curvature, expected, rtol=1e-12)


def test_a_group_nothing_sees_gets_the_smallest_seen_curvature():
    weights = np.ones((2, 3, 3, 3))
    weights[1] = 0.0
    curvature = group_curvature(op.Diagonal(weights), np.zeros(weights.shape),
                                by_field(weights.shape))
    np.testing.assert_allclose(curvature, [1.0, 1.0])


def test_groups_of_the_wrong_shape_or_empty_are_refused():
    forward = op.Diagonal(np.ones(6))
    with pytest.raises(ValueError, match="parameters' shape"):
        group_curvature(forward, np.zeros(6), np.zeros(5, int))
    with pytest.raises(ValueError, match=r"groups \[1\] hold no parameter"):
        group_curvature(forward, np.zeros(6), np.array([0, 0, 2, 2, 0, 2]))


def test_the_quadratic_weight_of_tv_touches_the_absolute_value_at_the_median():
    x0 = np.array([0.0, 1.0, -3.0, 2.0])
    tikhonov = op.Composite(op.SquaredL2(scale=0.5), op.Identity(4))
    assert quadratic_weight(tikhonov, 10.0, x0) == pytest.approx(5.0)
    tv = op.Composite(op.L1(scale=0.5), op.Identity(4))
    assert quadratic_weight(tv, 10.0, x0) == pytest.approx(5.0 / (2 * 2.0))
