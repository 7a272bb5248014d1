r"""Adam (Kingma & Ba, "Adam: a method for stochastic optimization", ICLR 2015), projected.

.. math::
    m_k = \beta_1 m_{k-1} + (1-\beta_1) g_k, \quad v_k = \beta_2 v_{k-1} + (1-\beta_2) g_k^2,

    \theta_k = P\big(\theta_{k-1} - \eta\, \hat m_k / (\sqrt{\hat v_k} + \epsilon)\big),
    \quad \hat m_k = m_k / (1-\beta_1^k), \ \hat v_k = v_k / (1-\beta_2^k),

with :math:`g_k` the (possibly stochastic) gradient at :math:`\theta_{k-1}` and :math:`P` the
projection onto the bounds. The moments are saved in checkpoints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solvers.base import Solver, Step
from solvers.options import SolverOptions, option
from solvers.registry import register


@dataclass(frozen=True)
class AdamOptions(SolverOptions):
    r"""Options of ``adam`` (:class:`Adam`).

    Attributes
    ----------
    lr : float
        Learning rate :math:`\eta`, parameter units per step (default 1e-3); > 0.
    betas : tuple of 2 float
        Moment decay rates :math:`(\beta_1, \beta_2)`, dimensionless (default (0.9, 0.999));
        each in [0, 1).
    eps : float
        :math:`\epsilon` added to :math:`\sqrt{\hat v}`, gradient units (default 1e-8); >= 0.
    """

    lr: float = option(1e-3, "> 0", lambda v: v > 0)
    betas: tuple[float, float] = option((0.9, 0.999), "two numbers in [0, 1)",
                                        lambda v: all(0 <= b < 1 for b in v))
    eps: float = option(1e-8, ">= 0", lambda v: v >= 0)


@register("adam")
class Adam(Solver):
    """Adam with projection onto the bounds; see the module docstring and
    :class:`AdamOptions`."""

    Options = AdamOptions

    def init_state(self, run):
        zeros = np.zeros(run.problem.dims, run.problem.dtype)
        return {"m": zeros, "v": zeros.copy()}

    def step(self, run) -> Step:
        o = self.options
        lr, (b1, b2), eps = o.lr, o.betas, o.eps
        k = run.iteration + 1
        g = run.start_evaluation().grad
        m = b1 * run.state["m"] + (1 - b1) * g
        v = b2 * run.state["v"] + (1 - b2) * g * g
        update = (m / (1 - b1**k)) / (np.sqrt(v / (1 - b2**k)) + eps)
        x = run.problem.project(run.x - lr * update).astype(run.problem.dtype, copy=False)
        return Step(x, run.evaluate(x, k + 1), {"m": m, "v": v})
