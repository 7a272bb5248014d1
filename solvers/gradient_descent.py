r"""Projected gradient descent with a backtracking (Armijo) line search.

Each iteration tries :math:`\theta(\alpha) = P(\theta - \alpha \nabla L(\theta))`, with
:math:`P` the projection onto the bounds, and halves :math:`\alpha` until the Armijo condition
along the projection arc holds (Bertsekas, *Nonlinear Programming*, 1999, §2.3):

.. math:: L(\theta(\alpha)) \le L(\theta) + c_1 \langle \nabla L(\theta),
          \theta(\alpha) - \theta \rangle.

The accepted step times ``grow`` is the next iteration's first trial. With a stochastic
objective the trials of one iteration share that iteration's sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solvers.base import Solver, Step
from solvers.options import SolverOptions, option
from solvers.registry import register


@dataclass(frozen=True)
class GradientDescentOptions(SolverOptions):
    r"""Options of ``gd`` (:class:`GradientDescent`).

    Attributes
    ----------
    step : float
        First trial step :math:`\alpha_0`, parameter units per gradient unit (default 1); > 0.
    shrink : float
        Backtracking factor, dimensionless (default 0.5); in (0, 1).
    grow : float
        Factor applied to the accepted step for the next first trial (default 2); >= 1.
    c1 : float
        Armijo constant, dimensionless (default 1e-4); in (0, 1).
    max_backtracks : int
        Trials per iteration before giving up (default 30); >= 1.
    """

    step: float = option(1.0, "> 0", lambda v: v > 0)
    shrink: float = option(0.5, "in (0, 1)", lambda v: 0 < v < 1)
    grow: float = option(2.0, ">= 1", lambda v: v >= 1)
    c1: float = option(1e-4, "in (0, 1)", lambda v: 0 < v < 1)
    max_backtracks: int = option(30, ">= 1", lambda v: v >= 1)


@register("gd")
class GradientDescent(Solver):
    """Gradient descent with Armijo backtracking; see the module docstring and
    :class:`GradientDescentOptions`."""

    Options = GradientDescentOptions

    def init_state(self, run):
        return {"step": self.options.step}

    def step(self, run) -> Step:
        o = self.options
        current = run.start_evaluation()
        grad = current.grad
        alpha = run.state["step"]
        for _ in range(o.max_backtracks):
            x = run.problem.project(run.x - alpha * grad)
            trial = run.evaluate(x)
            decrease = float(np.vdot(grad, x - run.x))
            if trial.loss <= current.loss + o.c1 * decrease:
                return Step(x, trial, {"step": alpha * o.grow}, {"step": alpha})
            alpha *= o.shrink
        return Step(run.x, current, {"step": alpha}, {"step": alpha},
                    stop=f"line search failed: no decrease after {o.max_backtracks} trials "
                         f"(last step {alpha:.3e})")
