"""Checks of a problem's capability flags that several solvers share."""

from __future__ import annotations

from solvers.base import UnsupportedProblemError
from solvers.problem import Problem


def require_linearizable(solver: str, problem: Problem) -> None:
    """Refuse a problem whose Jacobians may not be applied many times per iteration.

    Parameters
    ----------
    solver : str
        Name of the solver asking, for the message.
    problem : solvers.Problem
        The problem; its ``linearizable`` flag is read.

    Raises
    ------
    UnsupportedProblemError
        When ``problem.linearizable`` is False, naming the solvers that fit and adding the
        problem's ``advice``.
    """
    if isinstance(problem, Problem) and not problem.linearizable:
        advice = f" {problem.advice}" if problem.advice else ""
        raise UnsupportedProblemError(
            f"solver {solver!r} applies the Jacobians of the problem many times per iteration, "
            f"but {problem.name} is not linearizable (one Jacobian product costs a whole pass "
            f"over the data).{advice} First-order solvers ('adam', 'gd') and 'lbfgs' take it."
        )
