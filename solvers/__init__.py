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

The package loads its modules when a name of theirs is first used, so that a module that needs
no solver (``import solvers.atomic``) starts without JAX. :func:`available`, :func:`get`,
:func:`register` and :func:`solve` import every built-in solver first, so that the registry
knows them all.
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from solvers.history import Result
    from solvers.problem import Problem

_HOMES = {
    "Callback": "callbacks",
    "Checkpoint": "callbacks",
    "Evaluation": "problem",
    "History": "history",
    "ParameterChoice": "parameter_choice",
    "Problem": "problem",
    "ProgressBar": "callbacks",
    "Regularizer": "problem",
    "Result": "history",
    "RunState": "base",
    "Solver": "base",
    "Step": "base",
    "StoppingRule": "stopping",
    "UnknownSolverError": "registry",
    "UnsupportedProblemError": "base",
    "discrepancy_principle": "parameter_choice",
    "l_curve": "parameter_choice",
    "load_checkpoint": "checkpoint",
    "problem_weight": "parameter_choice",
}
"""Public name → the module of this package that defines it."""

_REGISTRY_LOOKUPS = ("available", "get", "register")
"""The registry's functions, which see every built-in solver."""


def _registry():
    """:mod:`solvers.registry`, with every built-in solver registered in it."""
    from solvers import (  # noqa: F401
        adam,
        gauss_newton,
        gradient_descent,
        jaxopt_lbfgs,
        pdhg,
        preconditioned_lbfgs,
        registry,
        scipy_lbfgs,
    )

    return registry


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
    return _registry().get(method)(**options).run(problem, x0=x0, callbacks=callbacks,
                                                  seed=seed, resume=resume)


def __getattr__(name: str):
    """Import the module behind a public name, or a submodule, on first use.

    Raises
    ------
    AttributeError
        If ``name`` is neither a public name nor a submodule of this package.
    """
    if name in _REGISTRY_LOOKUPS:
        value = getattr(_registry(), name)
    elif name in _HOMES:
        value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
    elif name in {module.name for module in pkgutil.iter_modules(__path__)}:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The public names, and the modules and names loaded so far."""
    return sorted({*globals(), *__all__})


__all__ = sorted([*_HOMES, *_REGISTRY_LOOKUPS, "solve"])
