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

import numpy as np

from solvers.base import Solver, Step
from solvers.registry import register


@register("gd")
class GradientDescent(Solver):
    """Gradient descent with Armijo backtracking; see the module docstring.

    Options
    -------
    step : float
        First trial step :math:`\\alpha_0` (parameter units per gradient unit; default 1).
    shrink : float
        Backtracking factor in (0, 1) (default 0.5).
    grow : float
        Factor >= 1 applied to the accepted step for the next first trial (default 2).
    c1 : float
        Armijo constant in (0, 1) (default 1e-4).
    max_backtracks : int
        Trials per iteration before giving up (default 30).
    """

    defaults = {"step": 1.0, "shrink": 0.5, "grow": 2.0, "c1": 1e-4, "max_backtracks": 30}

    def check_options(self):
        o = self.options
        if not (o["step"] > 0 and 0 < o["shrink"] < 1 and o["grow"] >= 1 and 0 < o["c1"] < 1
                and int(o["max_backtracks"]) >= 1):
            raise ValueError(f"gd options out of range: need step > 0, 0 < shrink < 1, "
                             f"grow >= 1, 0 < c1 < 1, max_backtracks >= 1; got {o}")

    def init_state(self, run):
        return {"step": float(self.options["step"])}

    def step(self, run) -> Step:
        o = self.options
        current = run.start_evaluation()
        grad = current.grad
        alpha = run.state["step"]
        for _ in range(int(o["max_backtracks"])):
            x = run.problem.project(run.x - alpha * grad)
            trial = run.evaluate(x)
            decrease = float(np.vdot(grad, x - run.x))
            if trial.loss <= current.loss + o["c1"] * decrease:
                return Step(x, trial, {"step": alpha * o["grow"]}, {"step": alpha})
            alpha *= o["shrink"]
        return Step(run.x, current, {"step": alpha}, {"step": alpha},
                    stop=f"line search failed: no decrease after {o['max_backtracks']} trials "
                         f"(last step {alpha:.3e})")
