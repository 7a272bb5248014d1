"""The screened Poisson solve: the exact inverse of c I + a DᵀD, self-adjoint, checked input."""

import numpy as np
import pytest

import operators as op

DIMS = (2, 5, 6, 7)
SPACING = (0.1, 0.2, 0.3)


def test_it_inverts_the_screened_laplacian_of_the_forward_differences():
    solve = op.ScreenedPoissonSolve(DIMS, SPACING, weight=0.7, shift=[2.0, 0.5])
    gradient = op.Gradient(DIMS, SPACING)
    v = np.random.default_rng(0).standard_normal(DIMS)
    u = solve.matvec(v.ravel()).reshape(DIMS)
    shift = np.array([2.0, 0.5]).reshape(-1, 1, 1, 1)
    applied = shift * u + 0.7 * gradient.rmatvec(gradient.matvec(u.ravel())).reshape(DIMS)
    np.testing.assert_allclose(applied, v, rtol=0, atol=1e-12 * np.abs(v).max())


def test_it_is_self_adjoint_and_positive():
    solve = op.ScreenedPoissonSolve(DIMS, SPACING, weight=3.0, shift=0.1)
    rng = np.random.default_rng(1)
    u, v = rng.standard_normal((2, int(np.prod(DIMS))))
    assert abs(v @ solve.matvec(u) - u @ solve.matvec(v)) < 1e-12 * abs(v @ solve.matvec(u))
    assert op.dottest(solve, rtol=1e-12).passed
    assert u @ solve.matvec(u) > 0


@pytest.mark.parametrize(("weight", "shift", "match"), [
    (-1.0, 1.0, "weight must be a finite number >= 0"),
    (1.0, 0.0, "shift must be finite and positive per field"),
    (1.0, [1.0, np.nan], "shift must be finite and positive per field"),
])
def test_bad_weights_are_refused(weight, shift, match):
    with pytest.raises(ValueError, match=match):
        op.ScreenedPoissonSolve(DIMS, SPACING, weight, shift)
