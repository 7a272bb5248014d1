"""L-BFGS with a preconditioner and bounds: the bounded minimizer, and fewer iterations with a
preconditioner that matches the objective's curvature."""

import numpy as np
import pytest

import operators as op
import solvers

DIMS = (2, 12, 12, 12)
SPACING = (0.05, 0.05, 0.05)
LAM = 1e5


def _smooth_problem(preconditioned: bool) -> solvers.Problem:
    """A Tikhonov-dominated denoising of a 3-D field bounded below by 0: data weights 0.5-2
    per voxel, a noisy blob on a floor of -1 (held at the bound where the blob is low), the
    smoothness term's curvature up to about 1000 times the data's."""
    rng = np.random.default_rng(3)
    weights = op.Diagonal(rng.uniform(0.5, 2.0, DIMS))
    centre = np.linspace(-1.0, 1.0, DIMS[1]) ** 2
    blob = 3.0 * np.exp(-(centre[:, None, None] + centre[None, :, None]
                          + centre[None, None, :]) * 2.0) - 1.0
    truth = blob + 0.3 * rng.standard_normal(DIMS)
    regularizer = op.tikhonov(DIMS, SPACING)
    shift = np.mean(weights.diagonal.reshape(2, -1) ** 2, axis=1)
    preconditioner = op.ScreenedPoissonSolve(DIMS, SPACING, LAM * regularizer.functional.scale,
                                             shift) if preconditioned else None
    x0 = np.clip(truth + rng.standard_normal(DIMS), 0.0, 3.0)
    return solvers.Problem(weights, weights.matvec(truth.ravel()).reshape(DIMS),
                           regularizer=regularizer, lam=LAM, lower=0.0, upper=3.0, x0=x0,
                           preconditioner=preconditioner)


@pytest.fixture(scope="module")
def minimum():
    """The bounded minimizer's loss, from SciPy's L-BFGS-B run to its own tolerances."""
    result = solvers.solve(_smooth_problem(False), "lbfgs", max_iter=3000, ftol=1e-15,
                           pgtol=1e-12)
    assert result.stop_reason.startswith("scipy"), result.stop_reason
    return result.loss


def _iterations_to(minimum, preconditioned: bool) -> int:
    result = solvers.solve(_smooth_problem(preconditioned), "preconditioned-lbfgs",
                           max_iter=400)
    losses = np.asarray(result.history["loss"])
    reached = np.flatnonzero(losses <= minimum * (1 + 1e-4))
    assert reached.size, f"not within 1e-4 of the minimum in 400 iterations: {losses[-1]}"
    assert losses.min() >= minimum * (1 - 1e-9)  # the bounds hold: nothing below the minimum
    return int(reached[0])


def test_the_preconditioner_reaches_the_bounded_minimum_in_fewer_iterations(minimum):
    with_it, without = _iterations_to(minimum, True), _iterations_to(minimum, False)
    assert with_it * 5 <= without, (with_it, without)


def test_steps_stay_inside_the_bounds(minimum):
    result = solvers.solve(_smooth_problem(True), "preconditioned-lbfgs", max_iter=20)
    assert result.x.min() >= 0.0 and result.x.max() <= 3.0
    assert np.any(result.x == 0.0)  # the lower bound is active at the minimizer


def test_a_preconditioner_of_another_shape_is_refused():
    problem = _smooth_problem(False)
    wrong = op.ScreenedPoissonSolve((1, *DIMS[1:]), SPACING, 1.0, 1.0)
    with pytest.raises(ValueError, match=r"must map the parameters' shape \(2, 12, 12, 12\)"):
        solvers.Problem(problem.forward, problem.data, preconditioner=wrong)
    with pytest.raises(TypeError, match="preconditioner must be an operators.LinearOperator"):
        solvers.Problem(problem.forward, problem.data, preconditioner=np.eye(3))


def test_a_gradient_that_does_not_descend_stops_the_run_with_a_reason():
    """A gradient of the wrong sign: no step along it lowers the loss."""

    class WrongGradient(op.Operator):
        def __init__(self):
            super().__init__(3, 3, name="x with a negated derivative")

        def _forward(self, x):
            return x

        def _jvp(self, x, v):
            return -v

        def _vjp(self, x, w):
            return -w

    problem = solvers.Problem(WrongGradient(), np.ones(3), lam=0.0, x0=np.zeros(3))
    result = solvers.solve(problem, "preconditioned-lbfgs", max_iter=10, max_backtracks=5)
    assert result.stop_reason.startswith("line search failed"), result.stop_reason
    np.testing.assert_array_equal(result.x, np.zeros(3))


def test_a_preconditioner_given_as_a_function_is_built_once_when_a_solver_asks():
    built = []
    problem = _smooth_problem(False)

    def build():
        built.append(1)
        return op.ScreenedPoissonSolve(DIMS, SPACING, LAM / np.prod(DIMS), 1.0)

    lazy = solvers.Problem(problem.forward, problem.data, regularizer=problem.regularizer,
                           lam=LAM, lower=0.0, x0=problem.x0, preconditioner=build)
    solvers.solve(lazy, "lbfgs", max_iter=2)
    assert not built  # SciPy's L-BFGS-B never asks
    solvers.solve(lazy, "preconditioned-lbfgs", max_iter=2)
    solvers.solve(lazy, "preconditioned-lbfgs", max_iter=2)
    assert built == [1]
    none = solvers.Problem(problem.forward, problem.data, x0=problem.x0,
                           preconditioner=lambda: None)
    assert none.preconditioner is None
