r"""L-BFGS-B from SciPy (Byrd, Lu, Nocedal & Zhu, SIAM J. Sci. Comput. 16, 1995) with bounds.

SciPy owns the iteration: the objective and gradient are handed to
:func:`scipy.optimize.minimize` (``method="L-BFGS-B"``) in float64, and each accepted iterate
is logged, passed to the callbacks and checked against the stopping rules through SciPy's
callback. SciPy's own tests (``ftol``, ``pgtol``) may also end the run.

**Resume is not exact**: SciPy does not expose the L-BFGS memory, so a run resumed from a
checkpoint restarts the memory at the saved point (it still continues the history, iteration
count and elapsed time). ``exact_resume`` is False for this solver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, minimize

from solvers.base import Solver, Step
from solvers.evaluation_cache import EvaluationCache
from solvers.options import SolverOptions, option
from solvers.registry import register


@dataclass(frozen=True)
class ScipyLBFGSBOptions(SolverOptions):
    """Options of ``lbfgs`` (:class:`ScipyLBFGSB`), passed to SciPy's L-BFGS-B.

    Attributes
    ----------
    maxcor : int
        Number of correction pairs kept (default 10); >= 1.
    ftol : float
        SciPy's relative reduction tolerance of the objective, dimensionless (default 2.2e-9);
        >= 0.
    pgtol : float
        SciPy's tolerance on the largest projected gradient component, loss units per
        parameter unit (default 1e-5); >= 0.
    maxls : int
        Maximum line-search steps per iteration (default 20); >= 1.
    """

    maxcor: int = option(10, ">= 1", lambda v: v >= 1)
    ftol: float = option(2.2e-9, ">= 0", lambda v: v >= 0)
    pgtol: float = option(1e-5, ">= 0", lambda v: v >= 0)
    maxls: int = option(20, ">= 1", lambda v: v >= 1)


@register("lbfgs")
class ScipyLBFGSB(Solver):
    """SciPy L-BFGS-B; see the module docstring and :class:`ScipyLBFGSBOptions`."""

    Options = ScipyLBFGSBOptions
    stochastic_ok = False
    exact_resume = False

    def loop(self, run) -> str:
        problem = run.problem
        budget = self.stopping.budget_spent(run.iteration, run.call_seconds)
        if budget:
            return budget
        cache = EvaluationCache()
        cache.put(run.x, run.current)

        def as_params(flat):
            # SciPy works in float64; rounding to the problem's dtype may step over a bound
            return problem.project(np.asarray(flat, dtype=problem.dtype).reshape(problem.dims))

        def fun(flat):
            x = as_params(flat)
            ev = cache.get(x) or cache.put(x, run.evaluate(x))
            return ev.loss, np.asarray(ev.grad, np.float64).ravel()

        reason = []

        def callback(intermediate_result):
            x = as_params(intermediate_result.x)
            ev = cache.get(x) or run.evaluate(x)
            stop = self.record(run, Step(x, ev, {}))
            if stop:
                reason.append(stop)
                raise StopIteration

        bounds = None
        if problem.bounded:
            lo = -np.inf if problem.lower is None else problem.lower
            hi = np.inf if problem.upper is None else problem.upper
            bounds = Bounds(np.broadcast_to(lo, problem.dims).ravel(),
                            np.broadcast_to(hi, problem.dims).ravel())
        o = self.options
        result = minimize(fun, run.x.astype(np.float64).ravel(), jac=True, method="L-BFGS-B",
                          bounds=bounds, callback=callback,
                          options={"maxiter": self.stopping.max_iter - run.iteration,
                                   "maxcor": o.maxcor, "ftol": o.ftol, "gtol": o.pgtol,
                                   "maxls": o.maxls})
        if reason:
            return reason[0]
        return f"scipy L-BFGS-B: {result.message}"
