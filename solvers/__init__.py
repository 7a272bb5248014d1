r"""Generic solvers for :math:`\min_\theta \|F(\theta) - d\|^2 + \lambda\,\Phi(\theta)`.

Solvers work on :class:`Problem` objects built from :mod:`operators` and do not care whether
the parameters are voxel values or network weights. Pick one by name::

    import solvers
    problem = solvers.Problem(forward, data, regularizer=operators.total_variation(dims),
                              lam=1e-3, lower=0.0, x0=x0)
    result = solvers.solve(problem, "adam", lr=1e-2, max_iter=500,
                           callbacks=[solvers.ProgressBar(), solvers.Checkpoint("run.npz")])
    result = solvers.solve(problem, "adam", lr=1e-2, max_iter=1000, resume="run.npz")

``solvers.available()`` lists the names; ``solvers.get(name)`` returns the class;
``@solvers.register(name)`` adds one. Imports :mod:`operators`, never :mod:`invflame`.
"""

from solvers import adam, gauss_newton, gradient_descent, jaxopt_lbfgs, pdhg, scipy_lbfgs  # noqa: F401
from solvers.base import RunState, Solver, Step, UnsupportedProblemError
from solvers.callbacks import Callback, Checkpoint, ProgressBar
from solvers.checkpoint import load_checkpoint
from solvers.history import History, Result
from solvers.parameter_choice import (
    ParameterChoice,
    discrepancy_principle,
    l_curve,
    plot_l_curve,
    problem_weight,
)
from solvers.problem import Evaluation, Problem, Regularizer
from solvers.registry import UnknownSolverError, available, get, register
from solvers.stopping import StoppingRule


def solve(problem: Problem, method: str, *, x0=None, callbacks=(), seed: int = 0, resume=None,
          **options) -> Result:
    """Solve ``problem`` with the solver registered as ``method``.

    Parameters
    ----------
    problem : Problem
    method : str
        Solver name (see :func:`available`).
    x0, callbacks, seed, resume
        As in :meth:`Solver.run`.
    **options
        The solver's options and stopping rules (``max_iter``, ``rtol_loss``, ``rtol_x``,
        ``gtol``, ``time_budget``).
    """
    return get(method)(**options).run(problem, x0=x0, callbacks=callbacks, seed=seed,
                                      resume=resume)


__all__ = [
    "Callback",
    "Checkpoint",
    "Evaluation",
    "History",
    "ParameterChoice",
    "Problem",
    "ProgressBar",
    "Regularizer",
    "Result",
    "RunState",
    "Solver",
    "Step",
    "StoppingRule",
    "UnknownSolverError",
    "UnsupportedProblemError",
    "available",
    "discrepancy_principle",
    "get",
    "l_curve",
    "load_checkpoint",
    "plot_l_curve",
    "problem_weight",
    "register",
    "solve",
]
