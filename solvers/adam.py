r"""Adam (Kingma & Ba, "Adam: a method for stochastic optimization", ICLR 2015), projected.

.. math::
    m_k = \beta_1 m_{k-1} + (1-\beta_1) g_k, \quad v_k = \beta_2 v_{k-1} + (1-\beta_2) g_k^2,

    \theta_k = P\big(\theta_{k-1} - \eta\, \hat m_k / (\sqrt{\hat v_k} + \epsilon)\big),
    \quad \hat m_k = m_k / (1-\beta_1^k), \ \hat v_k = v_k / (1-\beta_2^k),

with :math:`g_k` the (possibly stochastic) gradient at :math:`\theta_{k-1}` and :math:`P` the
projection onto the bounds. The moments are saved in checkpoints.
"""

from __future__ import annotations

import numpy as np

from solvers.base import Solver, Step
from solvers.registry import register


@register("adam")
class Adam(Solver):
    """Adam with projection onto the bounds; see the module docstring.

    Options
    -------
    lr : float
        Learning rate :math:`\\eta` in parameter units (default 1e-3).
    betas : (float, float)
        Moment decay rates :math:`(\\beta_1, \\beta_2)` in [0, 1) (default (0.9, 0.999)).
    eps : float
        :math:`\\epsilon` (default 1e-8).
    """

    defaults = {"lr": 1e-3, "betas": (0.9, 0.999), "eps": 1e-8}

    def check_options(self):
        o = self.options
        betas = tuple(o["betas"])
        if not (o["lr"] > 0 and len(betas) == 2 and all(0 <= b < 1 for b in betas)
                and o["eps"] >= 0):
            raise ValueError(f"adam options out of range: need lr > 0, betas two numbers in "
                             f"[0, 1), eps >= 0; got {o}")

    def init_state(self, run):
        zeros = np.zeros(run.problem.dims, run.problem.dtype)
        return {"m": zeros, "v": zeros.copy()}

    def step(self, run) -> Step:
        lr, (b1, b2), eps = self.options["lr"], self.options["betas"], self.options["eps"]
        k = run.iteration + 1
        g = run.start_evaluation().grad
        m = b1 * run.state["m"] + (1 - b1) * g
        v = b2 * run.state["v"] + (1 - b2) * g * g
        update = (m / (1 - b1**k)) / (np.sqrt(v / (1 - b2**k)) + eps)
        x = run.problem.project(run.x - lr * update).astype(run.problem.dtype, copy=False)
        return Step(x, run.evaluate(x, k + 1), {"m": m, "v": v})
