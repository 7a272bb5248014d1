"""A run whose objective explodes stops as diverged and keeps the iterate before."""

import numpy as np

import operators as op
import solvers


class Matrix(op.Operator):
    """F(x) = A x."""

    def __init__(self, a):
        super().__init__(a.shape[1], a.shape[0], name="matrix")
        self.a = a

    def _forward(self, x):
        return self.a @ x

    def _jvp(self, x, v):
        return self.a @ v

    def _vjp(self, x, w):
        return self.a.T @ w


def near_its_solution():
    """Least squares started close to its solution x = 1, inside bounds [-100, 100]."""
    a = (np.random.default_rng(0).standard_normal((30, 10)) / 3).astype(np.float32)
    return solvers.Problem(Matrix(a), a @ np.ones(10, np.float32), lower=-100.0, upper=100.0,
                           x0=np.full(10, 0.99, np.float32), name="near")


def test_an_exploding_objective_stops_the_run_as_diverged():
    problem = near_its_solution()
    result = solvers.solve(problem, "adam", max_iter=50, lr=1e30)
    assert result.stop_reason.startswith("diverged: the loss rose from ")
    assert "more than 1000 times its start at iteration 1; kept iteration 0" in result.stop_reason
    assert result.diverged and not result.converged and result.iterations == 0
    np.testing.assert_array_equal(result.x, problem.x0)


def test_a_sound_step_is_not_taken_for_divergence():
    result = solvers.solve(near_its_solution(), "adam", max_iter=50, lr=1e-3)
    assert result.stop_reason.startswith("max_iter") and not result.diverged
