r"""Primal–dual hybrid gradient for a nonsmooth regularizer and a nonlinear forward map.

This is the linearized scheme, not the nonlinear PDHG of Valkonen (2014): each outer
iteration linearizes :math:`F` and :math:`K` at :math:`\theta_k` (Jacobians :math:`J`, :math:`L`)
and runs Chambolle–Pock iterations (Chambolle & Pock, J. Math. Imaging Vis. 40, 2011, with
:math:`\vartheta = 1`) on the convex model

.. math:: \min_{\theta \in C}\ \|J(\theta - \theta_k) + F(\theta_k) - d\|^2
          + \lambda\, g(L(\theta - \theta_k) + K(\theta_k)),

both terms dualized with the stacked operator :math:`A = (J; L)` and the box :math:`C` of the
bounds handled by projection in the primal step:

.. math::
    \theta^{+} = P_C(\theta - \tau A^\mathsf{T} y), \quad
    \bar\theta = \theta^{+} + \vartheta(\theta^{+} - \theta), \quad
    y^{+} = \mathrm{prox}_{\sigma h^*}(y + \sigma A \bar\theta),

with :math:`\tau = \sigma = 0.99 / \|A\|` (:func:`operators.operator_norm`, 5 % margin).
:math:`A` is built with the operator algebra (:func:`operators.vstack` of the two Jacobians),
and the dual variable :math:`y = (p, q)` is an output of that stack. The dual variables are
kept from one outer iteration to the next. If :math:`F` and :math:`K` are linear the model is
exact and the run is plain Chambolle–Pock; otherwise a step that increases the true objective
is halved until it does not (at most ``max_backtracks`` times).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import operators
from operators import Composite
from solvers.base import Solver, Step, UnsupportedProblemError
from solvers.options import SolverOptions, option
from solvers.registry import register


def stacked_operator(evaluation, use_regularizer: bool):
    """The stacked Jacobian :math:`A = (J; L)` (or :math:`(J)` alone) at an evaluation's point.

    Parameters
    ----------
    evaluation : solvers.Evaluation
        Carrying ``forward_jacobian`` and, when ``use_regularizer``, ``regularizer_jacobian``.
    use_regularizer : bool
        Whether the regularizer's Jacobian is a block.

    Returns
    -------
    operators.LinearOperator
        From the parameters to the stacked dual space; ``.combination`` is the
        :class:`operators.combinators.VStack` whose ``split``/``join`` convert its outputs to
        blocks.
    """
    blocks = [evaluation.forward_jacobian]
    if use_regularizer:
        blocks.append(evaluation.regularizer_jacobian)
    return operators.vstack(blocks, name="PDHGOperator")


@dataclass(frozen=True)
class PDHGOptions(SolverOptions):
    r"""Options of ``pdhg`` (:class:`PDHG`).

    Attributes
    ----------
    inner_iter : int
        Chambolle–Pock iterations per outer iteration (default 50); >= 1.
    tau, sigma : float or None
        Primal step (parameter units per gradient unit) and dual step (default None: both
        :math:`0.99/\|A\|`); both None or both > 0 (need :math:`\tau\sigma\|A\|^2 < 1`).
    norm_iter : int
        Power iterations for :math:`\|A\|` (default 20); >= 1. Recomputed every outer
        iteration when :math:`F` or :math:`K` is nonlinear, once otherwise.
    max_backtracks : int
        Step halvings on the true objective per outer iteration (default 10); >= 0.
    """

    inner_iter: int = option(50, ">= 1", lambda v: v >= 1)
    tau: float | None = option(None, "None or > 0", lambda v: v is None or v > 0)
    sigma: float | None = option(None, "None or > 0", lambda v: v is None or v > 0)
    norm_iter: int = option(20, ">= 1", lambda v: v >= 1)
    max_backtracks: int = option(10, ">= 0", lambda v: v >= 0)

    def check(self):
        """``tau`` and ``sigma`` are given together or not at all."""
        if (self.tau is None) != (self.sigma is None):
            raise self.error("sigma" if self.sigma is None else "tau",
                             None if self.sigma is None else self.tau,
                             "given together with the other: set both tau and sigma, or "
                             "neither")


@register("pdhg")
class PDHG(Solver):
    """Linearized primal–dual (Chambolle–Pock) iterations; see the module docstring and
    :class:`PDHGOptions`."""

    Options = PDHGOptions
    stochastic_ok = False
    applies_jacobians = True

    def check_problem(self, problem):
        reg = problem.regularizer
        if reg is not None and isinstance(reg.functional, Composite):
            raise UnsupportedProblemError(
                "pdhg needs the regularizer's outer functional to have a proximal map; give "
                "it as a pair (g, K) with g e.g. operators.L1, not a Composite g(K(x))"
            )

    def _uses_regularizer(self, problem) -> bool:
        return problem.regularizer is not None and problem.lam > 0

    def _linear(self, problem) -> bool:
        return problem.forward.linear and (not self._uses_regularizer(problem)
                                           or problem.regularizer.op.linear)

    def init_state(self, run):
        problem = run.problem
        state = {"p": np.zeros(problem.forward.dimsd, problem.dtype), "norm": np.nan}
        if self._uses_regularizer(problem):
            state["q"] = np.zeros(problem.regularizer.op.dimsd, problem.dtype)
        return state

    def step(self, run) -> Step:
        o = self.options
        problem = run.problem
        current = run.linearized()
        use_reg = self._uses_regularizer(problem)
        stack = stacked_operator(current, use_reg)
        jf = current.forward_jacobian
        jk = current.regularizer_jacobian if use_reg else None
        norm = run.state["norm"]
        if not (self._linear(problem) and np.isfinite(norm)):
            norm = 1.05 * operators.operator_norm(stack, o.norm_iter, seed=run.rng())
        tau = o.tau or 0.99 / max(norm, np.finfo(float).tiny)
        sigma = o.sigma or 0.99 / max(norm, np.finfo(float).tiny)

        x0 = run.x
        b = problem.data - jf.value                    # data model: J (x - x0) - b
        c = jk.value if use_reg else None              # regularizer model: L (x - x0) + c
        g, lam = (problem.regularizer.functional, problem.lam) if use_reg else (None, 0.0)
        p, q = run.state["p"], run.state.get("q")
        blocks = stack.combination
        x = x0
        for _ in range(o.inner_iter):
            y = blocks.join([p, q] if use_reg else [p])
            x_new = problem.project(x - tau * stack.adjoint(y))
            x_bar = 2.0 * x_new - x
            a = blocks.split(stack(x_bar - x0))
            # prox of sigma h1* for h1(u) = ||u - b||^2 (Moreau)
            v = p + sigma * a[0]
            p = (v - sigma * b) / (1.0 + sigma / 2.0)
            if use_reg:
                # prox of sigma h2* for h2(u) = lam g(u + c): lam prox_{(sigma/lam) g*}(.)
                q = lam * g.prox_dual((q + sigma * (a[1] + c)) / lam, sigma / lam)
            x = x_new

        state = {"p": p.astype(problem.dtype), "norm": norm}
        if use_reg:
            state["q"] = q.astype(problem.dtype)
        target = x
        trial = run.evaluate(target)
        alpha = 1.0
        if not self._linear(problem):
            for _ in range(o.max_backtracks):
                if trial.loss <= current.loss:
                    break
                alpha /= 2
                x = x0 + alpha * (target - x0)
                trial = run.evaluate(x)
        return Step(x.astype(problem.dtype, copy=False), trial, state,
                    {"step": alpha, "tau": tau, "sigma": sigma})
