"""Box bounds (solvers.bounds): one projection and projected gradient for NumPy and JAX."""

import jax
import numpy as np
import pytest

import operators as op
import solvers
from solvers.bounds import compact, project, projected_gradient

LOWER = np.array([-0.5, 0.0, -np.inf, 0.2])[:, None]
UPPER = np.array([0.5, np.inf, 1.0, 0.2])[:, None]
BOUNDS = {"both": (LOWER, UPPER), "lower": (LOWER, None), "upper": (None, UPPER),
          "scalars": (-0.3, 0.3)}


def points(seed=0):
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.5, 1.5, (4, 6))
    x[0, :2], x[1, :2], x[2, 3] = -0.5, 0.0, 1.0  # on bounds, both signs of gradient below
    g = rng.standard_normal((4, 6))
    g[0, 0], g[0, 1], g[1, 0], g[1, 1] = 1.0, -1.0, 2.0, -2.0
    return project(x, *BOUNDS["both"]), g


@pytest.mark.parametrize("bounds", BOUNDS)
def test_projection_and_projected_gradient_are_the_same_in_numpy_and_jax(bounds):
    lower, upper = BOUNDS[bounds]
    rng = np.random.default_rng(1)
    x, g = rng.uniform(-1.5, 1.5, (4, 6)), rng.standard_normal((4, 6))
    with jax.enable_x64(True):
        on_device = jax.jit(lambda x, g: (project(x, lower, upper),
                                          projected_gradient(project(x, lower, upper), g,
                                                             lower, upper)))(x, g)
        assert all(isinstance(a, jax.Array) for a in on_device)
        y = project(x, lower, upper)
        np.testing.assert_array_equal(np.asarray(on_device[0]), y)
        np.testing.assert_array_equal(np.asarray(on_device[1]),
                                      projected_gradient(y, g, lower, upper))
    assert np.all(y >= (-np.inf if lower is None else lower))
    assert np.all(y <= (np.inf if upper is None else upper))


def test_projected_gradient_zeroes_exactly_what_pushes_out_of_an_active_bound():
    x, g = points()
    lower, upper = BOUNDS["both"]
    expected = g.copy()
    outward = ((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0))
    assert outward.sum() >= 4  # the points' own cases: at a lower bound, and the fixed value
    expected[outward] = 0.0
    result = projected_gradient(x, g, lower, upper)
    np.testing.assert_array_equal(result, expected)
    assert result[0, 0] == 0 and result[0, 1] == -1.0  # at the lower bound: down zeroed only
    assert result[1, 0] == 0 and result[1, 1] == -2.0
    assert result.dtype == g.dtype and result is not g


def test_without_bounds_nothing_changes():
    x, g = points()
    assert project(x, None, None) is x
    np.testing.assert_array_equal(projected_gradient(x, g, None, None), g)


def test_compact_keeps_one_value_per_broadcast_axis():
    per_field = np.broadcast_to(np.arange(4.0)[:, None, None], (4, 5, 6))
    small = compact(per_field)
    assert small.shape == (4, 1, 1)
    np.testing.assert_array_equal(np.broadcast_to(small, per_field.shape), per_field)
    whole = np.ones((4, 5, 6))
    assert compact(whole).shape == whole.shape
    assert compact(np.broadcast_to(2.0, (3, 2))).shape == (1, 1)


def test_a_problem_keeps_a_bound_per_field_compact_in_its_own_dtype():
    dims = (2, 3, 4)
    lower = np.broadcast_to(np.array([0.5, -1.0])[:, None, None], dims)  # float64
    problem = solvers.Problem(op.Identity(dims, np.float32), np.zeros(dims, np.float32),
                              lower=lower, upper=2.0)
    assert problem.lower.dtype == np.float32 and problem.lower.shape == dims
    assert compact(problem.lower).shape == (2, 1, 1)
    np.testing.assert_array_equal(problem.lower, lower.astype(np.float32))
    assert [b.shape for b in problem.compiled.bounds] == [(2, 1, 1), (1, 1, 1)]
