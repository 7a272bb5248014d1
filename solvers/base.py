"""The solver base class: one run loop for every solver.

A solver subclasses :class:`Solver`, declares its algorithm options as a frozen dataclass
``Options`` (:mod:`solvers.options`) and implements :meth:`Solver.init_state` and
:meth:`Solver.step`. The base class checks the problem, evaluates
the starting point, runs the loop with the stopping rules and callbacks, and saves and resumes
checkpoints through :func:`solvers.checkpoint.save_run` and :func:`solvers.checkpoint.load_run`.
A step must not change ``run.x``, ``run.state`` or ``run.history``: it returns the new
parameters, the objective there, the new state and diagnostics, so that an interruption at any
moment leaves a consistent state behind.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from solvers.callbacks import as_callback
from solvers.checkpoint import load_run, save_run
from solvers.history import History, Result
from solvers.options import SolverOptions
from solvers.problem import Evaluation, Problem
from solvers.stopping import StoppingRule, diverged


class UnsupportedProblemError(ValueError):
    """A solver asked to solve a problem it cannot handle sensibly."""


@dataclass
class Step:
    """What one iteration produced.

    Attributes
    ----------
    x : ndarray
        New parameters.
    evaluation : Evaluation
        Objective at ``x``.
    state : dict
        New solver state (numbers and arrays only).
    info : dict
        Numeric diagnostics recorded in the history (e.g. ``step``, ``damping``).
    stop : str or None
        Reason to stop given by the solver itself (converged, line search failed...).
    """

    x: np.ndarray
    evaluation: Evaluation
    state: dict[str, Any]
    info: dict[str, float] = field(default_factory=dict)
    stop: str | None = None


class RunState:
    """The state of a run, as callbacks see it.

    Attributes
    ----------
    solver : Solver
    problem : Problem
    x : ndarray
        Current parameters (possibly a read-only copy of a point on JAX's device: a step and
        a callback must not change them; :class:`~solvers.history.Result` holds a copy).
    iteration : int
        Iterations done.
    current : Evaluation
        Objective at ``x``.
    state : dict
        Solver state (saved in checkpoints).
    history : History
    seed : int
    scratch : dict
        Per-run objects a solver may cache (never saved).
    """

    def __init__(self, solver, problem, x, current, state, history, seed, iteration=0,
                 elapsed_before=0.0, callbacks=()):
        self.solver = solver
        self.problem = problem
        self.x = x
        self.current = current
        self.state = state
        self.history = history
        self.seed = int(seed)
        self.iteration = int(iteration)
        self.scratch: dict[str, Any] = {}
        self.callbacks = list(callbacks)
        self.elapsed_before = float(elapsed_before)
        self.started = time.perf_counter()

    @property
    def call_seconds(self) -> float:
        """Wall seconds since this call to ``run`` began."""
        return time.perf_counter() - self.started

    @property
    def elapsed(self) -> float:
        """Wall seconds of the whole run, earlier segments included."""
        return self.elapsed_before + self.call_seconds

    def rng(self, stream: int = 0) -> np.random.Generator:
        """A generator for the next iteration, a function of (seed, iteration, stream) only."""
        return np.random.default_rng([self.seed, self.iteration + 1, 1 + stream])

    def evaluate(self, x, sample: int | None = None, jacobians: bool = False) -> Evaluation:
        """Objective at ``x``; ``sample`` picks the stochastic sample (default: next iteration).
        It carries the operators' Jacobians when ``jacobians`` is set or the solver applies
        them (:attr:`Solver.applies_jacobians`), so that an accepted trial point needs no
        second evaluation; otherwise it may come from the compiled objective
        (:attr:`solvers.Problem.compiled`).
        """
        sample = self.iteration + 1 if sample is None else sample
        return self.problem.evaluate(x, iteration=sample, seed=self.seed,
                                     jacobians=jacobians or self.solver.applies_jacobians)

    def start_evaluation(self) -> Evaluation:
        """The objective at ``x`` for the next iteration's sample (``current`` if it fits)."""
        sample = self.iteration + 1
        if self.current.sample is not None and self.current.sample != sample:
            self.current = self.evaluate(self.x, sample)
        return self.current

    def linearized(self) -> Evaluation:
        """``current`` with the Jacobians of the forward and regularizer operators."""
        if self.current.forward_jacobian is None:
            self.current = self.evaluate(self.x, jacobians=True)
        return self.current

    def save(self, path):
        """Write a checkpoint of this run (see :func:`solvers.checkpoint.save_run`)."""
        return save_run(path, self)


class Solver:
    """Base class of all solvers; see the module docstring.

    Parameters
    ----------
    max_iter, rtol_loss, rtol_x, gtol, time_budget, loss_window, misfit_target
        Stopping rules, see :class:`solvers.stopping.StoppingRule`.
    **options
        Algorithm options, the fields of the solver's ``Options`` dataclass.

    Raises
    ------
    solvers.options.OptionError
        For an unknown option, a wrong type or a value out of range, naming the solver, the
        option, the value and what is allowed.
    """

    name = "solver"
    #: The algorithm options: a frozen dataclass checked on construction (see
    #: :mod:`solvers.options`); ``help(solver_class.Options)`` lists them.
    Options: type[SolverOptions] = SolverOptions
    stochastic_ok = True
    #: Whether an iteration applies the problem's Jacobians many times (an inner linear solve,
    #: a linearized operator): such a solver refuses a problem that is not linearizable.
    applies_jacobians = False

    def __init__(self, *, max_iter: int = 100, rtol_loss: float | None = None,
                 rtol_x: float | None = None, gtol: float | None = None,
                 time_budget: float | None = None, loss_window: int = 1,
                 misfit_target: float | None = None, **options):
        self.options = self.Options.from_kwargs(options)
        self.stopping = StoppingRule(max_iter, rtol_loss, rtol_x, gtol, time_budget,
                                     loss_window, misfit_target)

    def __repr__(self) -> str:
        opts = ", ".join(f"{k}={v!r}" for k, v in self.options.items())
        return f"<solver {self.name}: {opts}; {self.stopping}>"

    # -- hooks for subclasses ------------------------------------------------------------------
    def check_problem(self, problem: Problem) -> None:
        """Solver-specific checks beyond kind and stochasticity; raise
        :class:`UnsupportedProblemError`."""

    def init_state(self, run: RunState) -> dict[str, Any]:
        """Solver state at the starting point (numbers and arrays)."""
        return {}

    def step(self, run: RunState) -> Step:
        """One iteration from ``run.x``; must not change ``run.x``, ``run.state``, ``run.history``.
        """
        raise NotImplementedError

    def state_to_arrays(self, run: RunState) -> dict[str, np.ndarray]:
        """Solver state as named arrays for a checkpoint."""
        return {k: np.asarray(v) for k, v in run.state.items()}

    def state_from_arrays(self, arrays: dict[str, np.ndarray], run: RunState) -> dict[str, Any]:
        """Inverse of :meth:`state_to_arrays` (0-d arrays become Python numbers)."""
        return {k: (v.item() if v.ndim == 0 else v) for k, v in arrays.items()}

    @classmethod
    def resumes_exactly(cls, arrays: dict[str, np.ndarray]) -> bool:
        """Whether a run resumed from a checkpoint holding the state ``arrays``
        (:meth:`state_to_arrays`) continues exactly as the uninterrupted run would."""
        return True

    # -- the run -------------------------------------------------------------------------------
    def check(self, problem: Problem) -> None:
        """Raise :class:`UnsupportedProblemError` if this solver should not solve ``problem``."""
        if not isinstance(problem, Problem):
            raise TypeError(f"expected a solvers.Problem, got {type(problem).__name__}")
        if self.applies_jacobians and not problem.linearizable:
            advice = f" {problem.advice}" if problem.advice else ""
            raise UnsupportedProblemError(
                f"solver {self.name!r} applies the Jacobians of the problem many times per "
                f"iteration, but {problem.name} is not linearizable (one Jacobian product costs "
                f"a whole pass over the data).{advice} First-order solvers ('adam', 'gd') and "
                "'lbfgs' take it."
            )
        if problem.stochastic and not self.stochastic_ok:
            raise UnsupportedProblemError(
                f"solver {self.name!r} needs the full deterministic objective but the problem "
                "has a stochastic value_and_grad; use a first-order solver ('adam', 'gd') or "
                "build the problem without value_and_grad"
            )
        self.check_problem(problem)

    def run(self, problem: Problem, x0=None, callbacks=(), seed: int = 0,
            resume=None) -> Result:
        """Minimize the problem's objective.

        Parameters
        ----------
        problem : Problem
        x0 : array_like, optional
            Starting point (default ``problem.x0``); ignored when resuming.
        callbacks : sequence of Callback or callable, optional
            Called after each iteration (see :mod:`solvers.callbacks`).
        seed : int, optional
            Seed of the run's randomness (stochastic samples, random start vectors); a resumed
            run keeps the checkpoint's seed.
        resume : str or Path, optional
            Checkpoint to continue from; the solver and its algorithm options must match the
            checkpoint's (stopping rules may differ, e.g. a larger ``max_iter``).

        Returns
        -------
        Result
        """
        self.check(problem)
        callbacks = [as_callback(c) for c in callbacks]
        run = (self._resumed(problem, resume, callbacks) if resume is not None
               else self._started(problem, x0, seed, callbacks))
        for cb in callbacks:
            cb.on_start(run)
        try:
            reason = self.loop(run)
        finally:
            for cb in callbacks:
                cb.on_end(run)
        return Result(x=np.array(run.x), history=run.history, stop_reason=reason,
                      iterations=run.iteration, solver=self.name,
                      options={**self.options.as_dict(), **self.stopping.as_dict()},
                      problem=problem.name, seed=run.seed, elapsed=run.elapsed,
                      metadata=dict(problem.metadata))

    def loop(self, run: RunState) -> str:
        """Iterate until a stopping rule fires; returns the stop reason.

        A step to non-finite parameters or loss is not taken, and a non-finite gradient at
        the new iterate ends the run there: the run stops with a reason starting
        ``"non-finite"`` and keeps the last iterate whose parameters and loss are finite. A
        step whose loss exceeds the start's a thousandfold (:func:`solvers.stopping.diverged`)
        is not taken either: the run stops with a reason starting ``"diverged"``.
        """
        if not np.isfinite(run.current.loss):
            return (f"non-finite: the loss is {run.current.loss} at iteration {run.iteration}; "
                    "check the starting point and the data")
        while True:
            reason = self.stopping.budget_spent(run.iteration, run.call_seconds)
            if reason:
                return reason
            step = self.step(run)
            reason = self.record(run, step)
            if reason:
                return reason

    def record(self, run: RunState, step: Step) -> str | None:
        """Make ``step`` the current iterate, log it, call callbacks; return a stop reason."""
        bad = _non_finite(step)
        if bad:
            return (f"non-finite: {bad} at iteration {run.iteration + 1}; kept iteration "
                    f"{run.iteration}, the last finite one (lower the step size or learning "
                    "rate, or check the problem)")
        rise = diverged(float(run.history["loss"][0]), float(step.evaluation.loss))
        if rise:
            return (f"diverged: {rise} at iteration {run.iteration + 1}; kept iteration "
                    f"{run.iteration} (lower the step size or learning rate)")
        dx = float(np.linalg.norm(np.asarray(step.x, np.float64) - run.x))
        x_norm = float(np.linalg.norm(run.x))
        step_ratio = dx / x_norm if x_norm > 0 else (np.inf if dx > 0 else 0.0)
        run.x, run.current, run.state = step.x, step.evaluation, step.state
        run.iteration += 1
        grad_norm = _log_row(run, step.info)
        if not np.isfinite(grad_norm):
            return (f"non-finite: the gradient at iteration {run.iteration} (its loss "
                    f"{run.current.loss:.6g} is finite and kept; check the problem's derivatives)")
        for cb in run.callbacks:
            if cb(run):
                return "callback: a callback asked to stop"
        if step.stop:
            return step.stop
        return (self.stopping.converged(run.history["loss"], step_ratio, grad_norm,
                                        run.current.misfit)
                or self.stopping.budget_spent(run.iteration, run.call_seconds))

    def _started(self, problem, x0, seed, callbacks) -> RunState:
        if x0 is None and problem.x0 is None:
            raise ValueError("no starting point: pass x0 to run() or set Problem(x0=...)")
        if int(seed) != seed or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed}")
        x = problem.check_point(problem.x0 if x0 is None else x0, "x0")
        run = RunState(self, problem, x, None, {}, History(), seed, callbacks=callbacks)
        run.current = run.evaluate(x)
        run.state = self.init_state(run)
        _log_row(run, {})
        return run

    def _resumed(self, problem, path, callbacks) -> RunState:
        ck = load_run(path, self, problem)
        meta = ck.meta
        x = problem.check_point(ck.x, "checkpoint x")
        run = RunState(self, problem, x, ck.evaluation(problem.dtype), {},
                       History(meta["history"]), meta["seed"], iteration=meta["iteration"],
                       elapsed_before=meta["elapsed"], callbacks=callbacks)
        if not run.current.has_grad:
            run.current = run.evaluate(x, run.current.sample)
        run.state = self.state_from_arrays(ck.state, run)
        return run


def _non_finite(step: Step) -> str | None:
    """What of a step is NaN or infinite (its parameters or loss), or None."""
    if not np.all(np.isfinite(step.x)):
        return f"{int(np.size(step.x) - np.isfinite(step.x).sum())} non-finite parameters"
    if not np.isfinite(step.evaluation.loss):
        return f"the loss is {step.evaluation.loss}"
    return None


def _log_row(run: RunState, info: dict[str, float]) -> float:
    c = run.current
    grad_norm = run.problem.projected_gradient_norm(run.x, c)
    run.history.append(iteration=run.iteration, loss=c.loss, misfit=c.misfit,
                       regularizer=c.regularizer, grad_norm=grad_norm, time=run.elapsed,
                       **info)
    return grad_norm
