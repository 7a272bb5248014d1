"""Runs that meet NaN stop with a clear reason and keep the last finite iterate."""

import numpy as np
import pytest

import operators as op
import solvers


class Cliff(op.Operator):
    """F(x) = A x, whose value (``where="loss"``) or derivatives (``where="grad"``) are NaN
    once x[0] passes 0.5; the solvers start at 0 towards x = 1."""

    def __init__(self, a, where):
        super().__init__(a.shape[1], a.shape[0], name=f"cliff ({where})")
        self.a, self.where = a, where

    def _nan_past_the_cliff(self, x, y, kind):
        return np.full_like(y, np.nan) if kind == self.where and x[0] > 0.5 else y

    def _forward(self, x):
        return self._nan_past_the_cliff(x, self.a @ x, "loss")

    def _jvp(self, x, v):
        return self._nan_past_the_cliff(x, self.a @ v, "grad")

    def _vjp(self, x, w):
        return self._nan_past_the_cliff(x, self.a.T @ w, "grad")


OPTIONS = {"adam": {"lr": 0.1}}
#: Solvers whose own line search evaluates trial gradients, meets the NaN first and stops.
OWN_LINE_SEARCH = {"jaxopt-lbfgs": "line search failed"}


def cliff_problem(where):
    a = (np.random.default_rng(0).standard_normal((30, 10)) / 3).astype(np.float32)
    return solvers.Problem(Cliff(a, where), a @ np.ones(10, np.float32),
                           x0=np.zeros(10, np.float32), name="cliff")


@pytest.mark.parametrize("name", solvers.available())
def test_a_nan_gradient_stops_the_run_at_the_last_finite_iterate(name):
    problem = cliff_problem("grad")
    result = solvers.solve(problem, name, max_iter=200, **OPTIONS.get(name, {}))
    expected = OWN_LINE_SEARCH.get(name, f"non-finite: the gradient at iteration "
                                         f"{result.iterations}")
    assert result.stop_reason.startswith(expected)
    assert np.isfinite(result.x).all()
    assert problem.evaluate(result.x).loss == result.history["loss"][-1]
    assert len(result.history["loss"]) == result.iterations + 1


@pytest.mark.parametrize("name", solvers.available())
def test_a_nan_loss_is_never_taken(name):
    problem = cliff_problem("loss")
    result = solvers.solve(problem, name, max_iter=200, **OPTIONS.get(name, {}))
    assert np.isfinite(result.x).all() and result.x[0] <= 0.5
    assert np.isfinite(result.history["loss"]).all()
    assert problem.evaluate(result.x).loss == result.history["loss"][-1]


def test_adam_stops_where_an_uninterrupted_run_of_that_length_ends():
    problem = cliff_problem("loss")
    result = solvers.solve(problem, "adam", max_iter=200, lr=0.1)
    assert result.stop_reason.startswith(f"non-finite: the loss is nan at iteration "
                                         f"{result.iterations + 1}; kept iteration "
                                         f"{result.iterations}")
    shorter = solvers.solve(problem, "adam", max_iter=result.iterations, lr=0.1)
    np.testing.assert_array_equal(result.x, shorter.x)
