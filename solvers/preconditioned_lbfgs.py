r"""L-BFGS with a preconditioner and box bounds, by two-metric projection.

Each iteration splits the parameters into those held at a bound by the gradient (at the lower
bound with a positive component, at the upper with a negative one) and the free ones, and moves
only the free ones along

.. math:: d = -Z H Z \nabla L, \qquad H = \text{L-BFGS}(s_i, y_i;\ H_0 = \gamma M),

with :math:`Z` the mask of the free parameters, :math:`(s_i, y_i)` the last ``maxcor`` steps
and gradient changes (a pair kept when :math:`s^\mathsf{T} y > 0`), :math:`M` the problem's
``preconditioner`` (the identity without one) and :math:`\gamma = s^\mathsf{T} y /
y^\mathsf{T} M y` of the newest pair (Nocedal & Wright, *Numerical Optimization*, 2006,
Algorithm 7.4, with :math:`H_0 = \gamma M`). :math:`ZHZ` is positive definite on the free
parameters, so :math:`d` descends; a projected backtracking line search along
:math:`P(\theta + \alpha d)` takes the first :math:`\alpha = 1, 1/2, \dots` that satisfies
Armijo's condition (Bertsekas, *Nonlinear Programming*, 1999, §2.3; two-metric projection:
Gafni & Bertsekas, SIAM J. Control Optim. 22, 1984). Without a pair (the first iteration, or
after a failed search, which clears the memory) the step is :math:`-ZMZ\nabla L` scaled to the
largest change ``first_step``.

A preconditioner that matches the curvature the objective owes to its regularizer (for a voxel
grid under Tikhonov, :class:`operators.ScreenedPoissonSolve`) lets the solver remove smooth and
rough errors alike at the same pace, where plain L-BFGS spends many iterations smoothing.

The memory is the solver's state, so a resumed run continues exactly; it holds
:math:`2\,\texttt{maxcor}\,n` float64 numbers for :math:`n` parameters (9 MB for the quick
voxel grid's 2 × 30³, 69 MB for the paper's 2 × 60³), in memory and in each checkpoint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solvers.base import Solver, Step
from solvers.options import SolverOptions, option
from solvers.registry import register


@dataclass(frozen=True)
class PreconditionedLBFGSOptions(SolverOptions):
    """Options of ``preconditioned-lbfgs`` (:class:`PreconditionedLBFGS`).

    Attributes
    ----------
    maxcor : int
        Step and gradient-change pairs kept (default 10); >= 1.
    first_step : float
        Largest parameter change of the step without a pair, in parameter units (default 0.1);
        > 0.
    c1 : float
        Armijo constant, dimensionless (default 1e-4); in (0, 1).
    max_backtracks : int
        Halvings of the step per iteration before the memory is cleared (default 20); >= 1.
    precondition : bool
        Use the problem's preconditioner (default True); False: :math:`M = I`, plain
        projected L-BFGS.
    """

    maxcor: int = option(10, ">= 1", lambda v: v >= 1)
    first_step: float = option(0.1, "> 0", lambda v: v > 0)
    c1: float = option(1e-4, "in (0, 1)", lambda v: 0 < v < 1)
    max_backtracks: int = option(20, ">= 1", lambda v: v >= 1)
    precondition: bool = option(True)


@register("preconditioned-lbfgs")
class PreconditionedLBFGS(Solver):
    """L-BFGS with the problem's preconditioner and two-metric projection onto the bounds; see
    the module docstring and :class:`PreconditionedLBFGSOptions`."""

    Options = PreconditionedLBFGSOptions
    stochastic_ok = False

    def init_state(self, run):
        m, n = self.options.maxcor, int(np.prod(run.problem.dims))
        return {"s": np.zeros((m, n)), "y": np.zeros((m, n)), "pairs": 0}

    def step(self, run) -> Step:
        problem, o = run.problem, self.options
        current = run.start_evaluation()
        x = np.asarray(run.x, np.float64)
        grad = np.asarray(current.grad, np.float64)
        free = (problem.projected_gradient(run.x, current.grad) == current.grad).astype(
            np.float64).ravel()
        state = run.state
        for attempt in range(2):
            direction, scale = self._direction(problem, free, grad, state)
            alpha = scale
            for tries in range(1, o.max_backtracks + 1):
                trial_x = problem.project((x + alpha * direction).astype(problem.dtype))
                trial = run.evaluate(trial_x)
                moved = np.asarray(trial_x, np.float64) - x
                if trial.loss <= current.loss + o.c1 * float(grad.ravel() @ moved.ravel()):
                    info = {"step": alpha, "backtracks": tries - 1, "restarts": attempt}
                    new_grad = np.asarray(trial.grad, np.float64)
                    return Step(trial_x, trial, _remembered(state, moved, new_grad - grad),
                                info)
                alpha /= 2
            if state["pairs"] == 0:
                break
            state = {**state, "pairs": 0}  # a failed search clears the memory once
        return Step(run.x, current, state,
                    {"step": alpha, "backtracks": tries, "restarts": attempt},
                    stop=f"line search failed: no decrease after {o.max_backtracks} halvings "
                         "along the preconditioned gradient")

    def _direction(self, problem, free, grad, state) -> tuple[np.ndarray, float]:
        """The search direction (``problem.dims``, float64) and its first trial step, for
        ``free`` the flat 0/1 mask of the parameters free to move."""
        precondition = _preconditioner(problem if self.options.precondition else None)
        pairs = state["pairs"]
        q = free * grad.ravel()
        s, y = state["s"][:pairs], state["y"][:pairs]
        rho = 1.0 / np.einsum("ij,ij->i", s, y)
        alphas = np.empty(pairs)
        for i in range(pairs - 1, -1, -1):
            alphas[i] = rho[i] * (s[i] @ q)
            q -= alphas[i] * y[i]
        r = free * precondition(free * q)
        if pairs:
            r *= (s[-1] @ y[-1]) / (y[-1] @ precondition(y[-1]))
        for i in range(pairs):
            r += s[i] * (alphas[i] - rho[i] * (y[i] @ r))
        direction = -(free * r).reshape(problem.dims)
        if pairs:
            return direction, 1.0
        largest = float(np.max(np.abs(direction)))
        return direction, (self.options.first_step / largest if largest > 0 else 1.0)


def _preconditioner(problem):
    """The preconditioner of ``problem`` as a function of flat float64 vectors (the identity
    without a problem or its preconditioner)."""
    m = None if problem is None else problem.preconditioner
    if m is None:
        return lambda v: v
    return lambda v: np.asarray(m.matvec(v), np.float64)


def _remembered(state: dict, s: np.ndarray, y: np.ndarray) -> dict:
    r"""The state with the pair ``(s, y)`` added as the newest (the oldest dropped when full);
    unchanged when :math:`s^\mathsf{T} y \le 0` (no curvature to learn from)."""
    s, y = s.ravel(), y.ravel()
    if not s @ y > 0:
        return state
    pairs = state["pairs"]
    keep = state["s"].shape[0]
    if pairs < keep:
        new_s, new_y = state["s"].copy(), state["y"].copy()
        new_s[pairs], new_y[pairs] = s, y
        return {"s": new_s, "y": new_y, "pairs": pairs + 1}
    return {"s": np.concatenate([state["s"][1:], s[None]]),
            "y": np.concatenate([state["y"][1:], y[None]]), "pairs": keep}
