"""The solver race's runs: one solver on a copy of a problem whose forward operator counts its
evaluations (F, its Jacobian's products JVP and VJP), traced per iteration in CPU and wall time
and stopped once its budget is spent (:func:`race`)."""

from __future__ import annotations

import time

from timing import CLOCKS

import operators
import solvers

COUNTS = ("forward", "jvp", "vjp")
GRACE = 1.5  # a run still inside an iteration at GRACE x its budget is cut off there


class OutOfTime(RuntimeError):
    """A counted evaluation asked for after the run's deadline."""


class CountingOperator(operators.Operator):
    """An operator whose evaluations are counted: values F(x), JVPs and VJPs, also those made
    through the Jacobians it returns.

    Parameters
    ----------
    op : operators.Operator
        The operator counted (same shapes, dtype and units).

    Attributes
    ----------
    counts : dict
        ``forward``, ``jvp`` and ``vjp``: evaluations so far.
    clock, deadline : callable, float or None
        A clock (:data:`CLOCKS`) and a time of it; an evaluation asked for later raises
        :class:`OutOfTime` and sets ``expired``.
    """

    def __init__(self, op: operators.Operator):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=op.name)
        self.op = op
        self.counts = dict.fromkeys(COUNTS, 0)
        self.clock, self.deadline = time.perf_counter, None
        self.expired = False

    def _count(self, kind: str) -> None:
        if self.deadline is not None and self.clock() > self.deadline:
            self.expired = True
            raise OutOfTime(f"cut off inside an iteration at {GRACE:g} x the budget")
        self.counts[kind] += 1

    def _forward(self, x):
        self._count("forward")
        return self.op(x)

    def _jvp(self, x, v):
        self._count("jvp")
        return self.op.jvp(x, v)

    def _vjp(self, x, w):
        self._count("vjp")
        return self.op.vjp(x, w)

    def linearize(self, x) -> operators.Jacobian:
        """The inner operator's Jacobian at ``x``, its products counted."""
        self._count("forward")
        jacobian = self.op.linearize(x)

        def jvp(v):
            self._count("jvp")
            return jacobian(v)

        def vjp(w):
            self._count("vjp")
            return jacobian.adjoint(w)

        return operators.Jacobian(self, x, jacobian.value, jvp=jvp, vjp=vjp)


class Trace(solvers.Callback):
    """One row per iteration (and the start): CPU and wall time since the trace began (before
    the run's first evaluation) without this callback's own time, evaluation counts, objective
    and MSE_T; asks the run to stop once ``budget`` seconds of ``clock`` are spent.

    Parameters
    ----------
    counter : CountingOperator
        The problem's counted forward operator.
    mse_t : callable
        Parameters → normalized MSE of the temperature against the truth.
    clock : {"cpu", "wall"}
        The clock of the budget (:data:`CLOCKS`).
    budget : float or None
        Seconds of ``clock``; None for no budget.
    """

    def __init__(self, counter: CountingOperator, mse_t, clock: str, budget: float | None):
        self.counter, self.mse_t, self.clock, self.budget = counter, mse_t, clock, budget
        self.rows: list[dict] = []
        self.overhead = dict.fromkeys(CLOCKS, 0.0)
        self.began = {key: read() for key, read in CLOCKS.items()}

    def elapsed(self, key: str) -> float:
        """Seconds of clock ``key`` spent by the run, this callback's own time excluded."""
        return CLOCKS[key]() - self.began[key] - self.overhead[key]

    def on_start(self, run):
        self._record(run)

    def __call__(self, run):
        self._record(run)
        return self.budget is not None and self.rows[-1][self.clock] >= self.budget

    def _record(self, run) -> None:
        now = {key: read() for key, read in CLOCKS.items()}
        self.rows.append({"iteration": run.iteration,
                          **{key: now[key] - self.began[key] - self.overhead[key]
                             for key in CLOCKS},
                          **self.counter.counts, "loss": run.current.loss,
                          "mse_t": self.mse_t(run.x)})
        for key, read in CLOCKS.items():
            self.overhead[key] += read() - now[key]


def counted(problem: solvers.Problem) -> tuple[solvers.Problem, CountingOperator]:
    """A copy of ``problem`` whose forward operator counts its evaluations."""
    counter = CountingOperator(problem.forward)
    return solvers.Problem(counter, problem.data, regularizer=problem.regularizer,
                           lam=problem.lam, lower=problem.lower, upper=problem.upper,
                           x0=problem.x0, name=problem.name,
                           metadata=problem.metadata), counter


def race(problem, mse_t, name: str, options: dict, max_iter: int, clock: str,
         budget: float | None) -> dict:
    """One solver run on a counted copy of ``problem``; its trace, or why it was skipped."""
    solver = solvers.get(name)(max_iter=max_iter, **options)
    race_problem, counter = counted(problem)
    try:
        solver.check(race_problem)
    except solvers.UnsupportedProblemError as refusal:
        return {"skipped": str(refusal)}
    trace = Trace(counter, mse_t, clock, budget)
    if budget is not None:
        counter.clock = CLOCKS[clock]
        counter.deadline = counter.clock() + GRACE * budget
    try:
        stop = solver.run(race_problem, callbacks=[trace]).stop_reason
    except Exception as error:  # jaxopt's host callback wraps OutOfTime in an error of its own
        stop = (f"cut off: inside an iteration at {GRACE:g} x the budget" if counter.expired
                else f"failed: {type(error).__name__}: {str(error).strip().splitlines()[-1]}")
    if stop.startswith("callback"):
        stop = f"budget: {budget:g} s of {clock} time spent"
    return {"solver": name, "options": options, "stop": stop, "rows": trace.rows,
            "seconds": {key: trace.elapsed(key) for key in CLOCKS}}
