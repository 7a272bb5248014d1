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
formed per iteration in weight space, which makes no sense for a network queried at every ray
sample (``kind="neural-field"``).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.linalg import LinearOperator, lsqr

from solvers.base import Solver, Step, UnsupportedProblemError
from solvers.problem import sum_of_squares
from solvers.registry import register


def _stacked_jacobian(problem, evaluation, free=None):
    """The Jacobian of the stacked residual (restricted to the ``free`` parameters when given,
    as a flat boolean mask) and the stacked residual, at the evaluation's point."""
    jf = evaluation.forward_jacobian
    blocks = [(jf, 1.0)]
    residuals = [(jf.value - problem.data).ravel()]
    reg = problem.regularizer
    if reg is not None and problem.lam > 0:
        g = reg.functional
        weight = np.sqrt(problem.lam * g.scale)
        jk = evaluation.regularizer_jacobian
        offset = 0.0 if g.offset is None else g.offset
        blocks.append((jk, weight))
        residuals.append((weight * (jk.value - offset)).ravel())
    sizes = [r.size for r in residuals]
    cuts = np.cumsum(sizes)[:-1]
    dims = problem.dims
    mask = 1.0 if free is None else free

    def matvec(v):
        v = (mask * v).reshape(dims)
        return np.concatenate([w * j.jvp(None, v).ravel() for j, w in blocks])

    def rmatvec(y):
        parts = np.split(y, cuts)
        return mask * sum(w * j.vjp(None, p.reshape(j.dimsd)).ravel()
                          for (j, w), p in zip(blocks, parts, strict=True))

    n = int(np.prod(dims))
    op = LinearOperator((sum(sizes), n), matvec=matvec, rmatvec=rmatvec, dtype=np.float64)
    return op, np.concatenate(residuals).astype(np.float64)


@register("gauss-newton")
class GaussNewton(Solver):
    """Levenberg–Marquardt-damped Gauss–Newton with inner LSQR; see the module docstring.

    Options
    -------
    damping : float
        Initial damping :math:`\\mu_0 > 0` (loss units per squared parameter unit;
        default 1e-3); a tiny value gives nearly undamped Gauss–Newton steps.
    inner_iter : int
        Maximum LSQR iterations per solve (default 100).
    inner_tol : float
        LSQR ``atol`` and ``btol`` (default 1e-10).
    max_retries : int
        Damped solves per iteration before giving up (default 10).
    """

    defaults = {"damping": 1e-3, "inner_iter": 100, "inner_tol": 1e-10, "max_retries": 10}
    supports = frozenset({"generic", "voxel", "neural-centres"})
    kind_advice = {"neural-field": (
        "Gauss-Newton on a neural field queried at every ray sample builds a huge dense "
        "Jacobian in weight space: use the voxel-centre neural reparameterization "
        "(kind='neural-centres'), a first-order solver such as 'adam', or 'lbfgs' on the "
        "deterministic objective (a problem without a stochastic value_and_grad).")}
    stochastic_ok = False

    def check_options(self):
        o = self.options
        if not (o["damping"] > 0 and int(o["inner_iter"]) >= 1 and o["inner_tol"] >= 0
                and int(o["max_retries"]) >= 1):
            raise ValueError(f"gauss-newton options out of range: need damping > 0, "
                             f"inner_iter >= 1, inner_tol >= 0, max_retries >= 1; got {o}")

    def check_problem(self, problem):
        reg = problem.regularizer
        if reg is not None and problem.lam > 0 and not reg.quadratic:
            raise UnsupportedProblemError(
                f"gauss-newton needs a least-squares objective, but the regularizer's outer "
                f"functional is {type(reg.functional).__name__}, not SquaredL2: use 'pdhg' for "
                "total variation, or a first-order solver ('adam', 'gd', 'lbfgs')"
            )

    def init_state(self, run):
        return {"damping": float(self.options["damping"]), "nu": 2.0}

    def step(self, run) -> Step:
        o = self.options
        problem = run.problem
        current = run.linearized()
        x0 = run.x
        free = None
        if problem.bounded:  # parameters held at a bound by the gradient stay fixed this step
            grad = current.grad
            free = (problem.projected_gradient(x0, grad) == grad).ravel()
        op, residual = _stacked_jacobian(problem, current, free)
        mu, nu = run.state["damping"], run.state["nu"]
        for retry in range(int(o["max_retries"])):
            sol = lsqr(op, -residual, damp=np.sqrt(mu), atol=o["inner_tol"],
                       btol=o["inner_tol"], iter_lim=int(o["inner_iter"]))
            step = (sol[0] if free is None else free * sol[0]).reshape(problem.dims)
            unprojected = x0 + step.astype(problem.dtype)
            x = problem.project(unprojected)
            delta = (x - x0).ravel().astype(np.float64)
            predicted = current.loss - sum_of_squares(op.matvec(delta) + residual)
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
