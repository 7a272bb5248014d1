r"""Matrix-free Gauss–Newton with Levenberg–Marquardt damping.

With a Tikhonov-like regularizer :math:`\Phi = c\|K(\theta) - b\|^2` the objective is a sum of
squares of the stacked residual :math:`R(\theta) = (F(\theta) - d,\ \sqrt{\lambda c}\,
(K(\theta) - b))`. Each iteration linearizes :math:`R` at :math:`\theta_k` (Jacobian
:math:`A`, applied only through jvp/vjp) and solves the damped least-squares problem

.. math:: \min_\delta \|A\delta + R(\theta_k)\|^2 + \mu\|\delta\|^2

with LSQR (Paige & Saunders 1982, :func:`scipy.sparse.linalg.lsqr`, ``damp`` :math:`=\sqrt\mu`).
The trial :math:`P(\theta_k + \delta)` (projected onto the bounds) is accepted when the gain
ratio :math:`\rho` = actual / predicted decrease is positive; :math:`\mu` is then multiplied by
:math:`\max(1/3, 1 - (2\rho - 1)^3)`, else multiplied by :math:`\nu` (doubling each rejection)
and the step retried (Nielsen's update, Madsen, Nielsen & Tingleff, *Methods for non-linear
least squares problems*, 2004). Near a zero-residual solution the damping vanishes and the
convergence is fast (quadratic in the limit).

Only squared-L2 regularizers fit this form; for total variation use ``pdhg``. The Jacobian is
applied many times per iteration, so a problem that is not ``linearizable`` is refused.

The stacked Jacobian is built with the operator algebra,

.. math:: A = \begin{pmatrix} J_F \\ \sqrt{\lambda c}\, J_K \end{pmatrix} D_\text{free},

(:func:`operators.vstack` of the Jacobians, :class:`operators.Diagonal` of the mask of the
parameters not held at a bound), so it is an :class:`operators.LinearOperator` that LSQR takes
as it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.linalg import lsqr

import operators
from solvers.base import Solver, Step, UnsupportedProblemError
from solvers.options import SolverOptions, option
from solvers.problem import sum_of_squares
from solvers.registry import register


def stacked_jacobian(problem, evaluation, free=None):
    r"""The Jacobian of the stacked residual and the stacked residual at the evaluation's point.

    Parameters
    ----------
    problem : solvers.Problem
        With a squared-L2 regularizer or none.
    evaluation : solvers.Evaluation
        Carrying ``forward_jacobian`` (and ``regularizer_jacobian`` when regularized).
    free : ndarray of bool, optional
        Parameters free to move, shape ``problem.dims``; the Jacobian is restricted to them.

    Returns
    -------
    A : operators.LinearOperator
        Parameters ``problem.dims`` to the stacked residual (flat, loss units^½).
    residual : ndarray
        The stacked residual :math:`R(\theta)`, shaped like ``A``'s output, float64.
    """
    jf = evaluation.forward_jacobian
    blocks = [jf]
    residuals = [jf.value - problem.data]
    reg = problem.regularizer
    if reg is not None and problem.lam > 0:
        g = reg.functional
        weight = float(np.sqrt(problem.lam * g.scale))
        jk = evaluation.regularizer_jacobian
        offset = 0.0 if g.offset is None else g.offset
        blocks.append(weight * jk)
        residuals.append(weight * (jk.value - offset))
    stack = operators.vstack(blocks, name="GaussNewtonJacobian")
    residual = stack.combination.join(residuals).astype(np.float64)
    if free is not None:
        stack = stack @ operators.Diagonal(free.astype(problem.dtype), name="free")
    return stack, residual


@dataclass(frozen=True)
class GaussNewtonOptions(SolverOptions):
    r"""Options of ``gauss-newton`` (:class:`GaussNewton`).

    Attributes
    ----------
    damping : float
        Initial damping :math:`\mu_0`, loss units per squared parameter unit (default 1e-3);
        > 0. A tiny value gives nearly undamped Gauss–Newton steps.
    inner_iter : int
        Maximum LSQR iterations per solve (default 100); >= 1.
    inner_tol : float
        LSQR ``atol`` and ``btol``, dimensionless (default 1e-10); >= 0.
    max_retries : int
        Damped solves per iteration before giving up (default 10); >= 1.
    """

    damping: float = option(1e-3, "> 0", lambda v: v > 0)
    inner_iter: int = option(100, ">= 1", lambda v: v >= 1)
    inner_tol: float = option(1e-10, ">= 0", lambda v: v >= 0)
    max_retries: int = option(10, ">= 1", lambda v: v >= 1)


@register("gauss-newton")
class GaussNewton(Solver):
    """Levenberg–Marquardt-damped Gauss–Newton with inner LSQR; see the module docstring and
    :class:`GaussNewtonOptions`."""

    Options = GaussNewtonOptions
    stochastic_ok = False
    applies_jacobians = True

    def check_problem(self, problem):
        reg = problem.regularizer
        if reg is not None and problem.lam > 0 and not reg.quadratic:
            raise UnsupportedProblemError(
                f"gauss-newton needs a least-squares objective, but the regularizer's outer "
                f"functional is {type(reg.functional).__name__}, not SquaredL2: use 'pdhg' for "
                "total variation, or a first-order solver ('adam', 'gd', 'lbfgs')"
            )

    def init_state(self, run):
        return {"damping": float(self.options.damping), "nu": 2.0}

    def step(self, run) -> Step:
        o = self.options
        problem = run.problem
        current = run.linearized()
        x0 = run.x
        free = None
        if problem.bounded:  # parameters held at a bound by the gradient stay fixed this step
            grad = current.grad
            free = problem.projected_gradient(x0, grad) == grad
        op, residual = stacked_jacobian(problem, current, free)
        mu, nu = run.state["damping"], run.state["nu"]
        for retry in range(o.max_retries):
            sol = lsqr(op, -residual.ravel(), damp=np.sqrt(mu), atol=o.inner_tol,
                       btol=o.inner_tol, iter_lim=o.inner_iter)
            step = sol[0].reshape(problem.dims)
            if free is not None:
                step = free * step
            unprojected = x0 + step.astype(problem.dtype)
            x = problem.project(unprojected)
            delta = (x - x0).ravel().astype(np.float64)
            predicted = current.loss - sum_of_squares(op.matvec(delta) + residual.ravel())
            info = {"damping": mu, "inner_iterations": sol[2], "retries": retry}
            if predicted > 0:
                trial = run.evaluate(x)
                rho = (current.loss - trial.loss) / predicted
                if rho > 0:
                    state = {"damping": mu * max(1 / 3, 1 - (2 * rho - 1) ** 3), "nu": 2.0}
                    return Step(x, trial, state, info)
            elif np.array_equal(x, unprojected):
                return Step(x0, current, run.state, info,
                            stop="stationary: the Gauss-Newton model predicts no decrease")
            mu, nu = mu * nu, 2 * nu
        return Step(x0, current, {"damping": mu, "nu": nu}, info,
                    stop=f"no decrease after {o['max_retries']} damped steps "
                         f"(damping {mu:.3e})")
