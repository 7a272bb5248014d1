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

import numpy as np
from scipy.optimize import Bounds, minimize

from solvers.base import Solver, Step
from solvers.evaluation_cache import EvaluationCache
from solvers.registry import register


@register("lbfgs")
class ScipyLBFGSB(Solver):
    """SciPy L-BFGS-B; see the module docstring.

    Options
    -------
    maxcor : int
        Number of correction pairs kept (default 10).
    ftol : float
        SciPy's relative reduction tolerance (default 2.2e-9).
    pgtol : float
        SciPy's tolerance on the largest projected gradient component (default 1e-5).
    maxls : int
        Maximum line-search steps per iteration (default 20).
    """

    defaults = {"maxcor": 10, "ftol": 2.2e-9, "pgtol": 1e-5, "maxls": 20}
    stochastic_ok = False
    exact_resume = False

    def check_options(self):
        o = self.options
        if not (int(o["maxcor"]) >= 1 and o["ftol"] >= 0 and o["pgtol"] >= 0
                and int(o["maxls"]) >= 1):
            raise ValueError(f"lbfgs options out of range: need maxcor >= 1, ftol >= 0, "
                             f"pgtol >= 0, maxls >= 1; got {o}")

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
                                   "maxcor": int(o["maxcor"]), "ftol": o["ftol"],
                                   "gtol": o["pgtol"], "maxls": int(o["maxls"])})
        if reason:
            return reason[0]
        return f"scipy L-BFGS-B: {result.message}"
