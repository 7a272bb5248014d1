r"""Adam (Kingma & Ba, "Adam: a method for stochastic optimization", ICLR 2015), projected.

.. math::
    m_k = \beta_1 m_{k-1} + (1-\beta_1) g_k, \quad v_k = \beta_2 v_{k-1} + (1-\beta_2) g_k^2,

    \theta_k = P\big(\theta_{k-1} - \eta\, \hat m_k / (\sqrt{\hat v_k} + \epsilon)\big),
    \quad \hat m_k = m_k / (1-\beta_1^k), \ \hat v_k = v_k / (1-\beta_2^k),

with :math:`g_k` the (possibly stochastic) gradient at :math:`\theta_{k-1}` and :math:`P` the
projection onto the bounds. The moments are saved in checkpoints.

The step runs where the gradient is: on JAX's device, as one compiled program, for a problem
whose objective is compiled (:attr:`solvers.Problem.compiles`; the moments then stay on the
device between iterations and the host receives the new point), in NumPy otherwise. Both run
:func:`adam_update`.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import numpy as np

from operators import precision
from operators.functionals import namespace
from operators.interop import to_jax, to_numpy
from solvers.base import Solver, Step
from solvers.bounds import project
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


def adam_update(x, g, m, v, rates, bounds):
    r"""One projected Adam step, for NumPy and JAX arrays alike (traced by :func:`jax.jit`
    for the device).

    Parameters
    ----------
    x, g, m, v : ndarray or jax.Array
        :math:`\theta_{k-1}`, :math:`g_k`, :math:`m_{k-1}`, :math:`v_{k-1}`, one shape.
    rates : tuple of 8 float
        :math:`(\eta, \beta_1, 1 - \beta_1, \beta_2, 1 - \beta_2, \epsilon, 1 - \beta_1^k,
        1 - \beta_2^k)` (:func:`adam_rates`): each computed in float64 before it meets the
        arrays' dtype, as a traced float32 :math:`1 - \beta_2` would be 4.7e-5 off.
    bounds : pair of array or None
        Lower and upper bounds (:func:`solvers.bounds.project`).

    Returns
    -------
    x, m, v
        :math:`\theta_k`, :math:`m_k`, :math:`v_k`, arrays of ``g``'s kind.
    """
    lr, b1, one_less_b1, b2, one_less_b2, eps, c1, c2 = rates
    m = b1 * m + one_less_b1 * g
    v = b2 * v + one_less_b2 * g * g
    update = (m / c1) / (namespace(g).sqrt(v / c2) + eps)
    return project(x - lr * update, *bounds), m, v


def adam_rates(options: AdamOptions, k: int) -> tuple[float, ...]:
    """The numbers :func:`adam_update` takes for step ``k`` (from 1), as Python floats."""
    b1, b2 = options.betas
    return (options.lr, b1, 1 - b1, b2, 1 - b2, options.eps, 1 - b1**k, 1 - b2**k)


_adam_update_on_device = jax.jit(adam_update)


@register("adam")
class Adam(Solver):
    """Adam with projection onto the bounds; see the module docstring and
    :class:`AdamOptions`."""

    Options = AdamOptions

    def init_state(self, run):
        zeros = np.zeros(run.problem.dims, run.problem.dtype)
        return {"m": zeros, "v": zeros.copy()}

    def step(self, run) -> Step:
        k = run.iteration + 1
        rates = adam_rates(self.options, k)
        problem, current = run.problem, run.start_evaluation()
        m, v = run.state["m"], run.state["v"]
        if not problem.compiles:
            x, m, v = adam_update(run.x, current.grad, m, v, rates,
                                  (problem.lower, problem.upper))
            x = x.astype(problem.dtype, copy=False)
        else:
            with precision(problem.dtype):
                point = current.point if current.point is not None else to_jax(
                    run.x, problem.dtype)
                device_x, m, v = _adam_update_on_device(point, current.native_grad, m, v, rates,
                                                        problem.compiled.bounds)
            x = to_numpy(device_x)
        return Step(x, run.evaluate(x, k + 1), {"m": m, "v": v})
