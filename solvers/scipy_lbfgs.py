r"""L-BFGS-B from SciPy (Byrd, Lu, Nocedal & Zhu, SIAM J. Sci. Comput. 16, 1995) with bounds.

The solver runs SciPy's L-BFGS-B routine ``scipy.optimize._lbfgsb.setulb`` itself. The
routine works by reverse communication: each call returns to the caller with a task, either
"evaluate the objective and gradient at ``x``" or "``x`` is a new accepted iterate", and
everything the routine knows (the iterate, the memory of correction pairs, the line search
under way) lives in arrays the caller owns. The loop here answers the routine's tasks as
:func:`scipy.optimize.minimize` (``method="L-BFGS-B"``) does, with the same translation of the
options (``factr = ftol / eps``, a bound code per parameter), so its iterates are bit for bit
those of ``minimize`` on the same problem and options. Each accepted iterate is logged, passed
to the callbacks and checked against the stopping rules; SciPy's own tests (``ftol``,
``pgtol``) may also end the run. ``minimize``'s limit of 15000 evaluations (``maxfun``) is not
applied: the stopping rules (``max_iter``, ``time_budget``) bound the run.

**Resume is exact**: the routine's arrays at each accepted iterate are the solver's state,
saved in each checkpoint, so a resumed run continues bit for bit as the uninterrupted run
would. They hold :math:`(2m + 7)\,n + 11 m^2 + 8m + 30` float64 and :math:`3n + 52` integer
numbers for :math:`n` parameters and :math:`m` = ``maxcor`` (12 MB for the quick voxel grid's
2 × 30³ at ``maxcor = 10``, 98.5 MB for the paper's 2 × 60³), in memory twice (the routine's
arrays and the last iterate's copy) and in each checkpoint. The routine is private SciPy API,
used because SciPy exposes no state of L-BFGS-B: ``minimize`` starts each call with an empty
memory. Its signature (:data:`SIGNATURE`) is that of SciPy 1.15, where L-BFGS-B became C
code, and later; a SciPy with another one is refused with a :class:`RuntimeError` naming what
to install.

A checkpoint without the routine's state (written before this solver saved it) or written
under another SciPy version still resumes, inexactly, with a :class:`RuntimeWarning`: the
L-BFGS memory restarts at the saved iterate (the history, iteration count and elapsed time
continue), so the run then differs from an uninterrupted one.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy

from solvers.base import Solver, Step
from solvers.evaluation_cache import EvaluationCache
from solvers.options import SolverOptions, option
from solvers.registry import register

SIGNATURE = "setulb(m,x,l,u,nbd,f,g,factr,pgtol,wa,iwa,task,lsave,isave,dsave,maxls,ln_task)"
"""The signature of ``scipy.optimize._lbfgsb.setulb`` that :class:`ScipyLBFGSB` calls."""
_FG, _NEW_X = 3, 1
"""Tasks the routine returns with: evaluate at ``x``; ``x`` is a new accepted iterate."""
_INTEGERS = frozenset({"iwa", "task", "ln_task", "lsave", "isave"})
"""The routine's integer arrays (the others are float64)."""
_VERSION = "scipy"
"""State entry: the SciPy version whose routine wrote the arrays."""


@dataclass(frozen=True)
class ScipyLBFGSBOptions(SolverOptions):
    """Options of ``lbfgs`` (:class:`ScipyLBFGSB`), passed to SciPy's L-BFGS-B.

    Attributes
    ----------
    maxcor : int
        Number of correction pairs kept (default 10); >= 1.
    ftol : float
        SciPy's relative reduction tolerance of the objective, dimensionless (default 2.2e-9);
        >= 0.
    pgtol : float
        SciPy's tolerance on the largest projected gradient component, loss units per
        parameter unit (default 1e-5); >= 0.
    maxls : int
        Maximum line-search steps per iteration (default 20); >= 1.
    """

    maxcor: int = option(10, ">= 1", lambda v: v >= 1)
    ftol: float = option(2.2e-9, ">= 0", lambda v: v >= 0)
    pgtol: float = option(1e-5, ">= 0", lambda v: v >= 0)
    maxls: int = option(20, ">= 1", lambda v: v >= 1)


class _Routine(NamedTuple):
    """SciPy's L-BFGS-B routine with the dtype of its integer arrays and its messages."""

    setulb: object
    integer: type
    status: dict
    reasons: dict

    def message(self, task: np.ndarray) -> str:
        """SciPy's words for a final ``task``, as ``minimize`` reports them."""
        return f"{self.status.get(int(task[0]), task[0])}: {self.reasons.get(int(task[1]), '')}"


def _routine() -> _Routine:
    """SciPy's L-BFGS-B routine, checked to have :data:`SIGNATURE`.

    Raises
    ------
    RuntimeError
        If the installed SciPy has no such routine or one with another signature, saying
        which SciPy has it.
    """
    try:
        from scipy.optimize import _lbfgsb, _lbfgsb_py

        setulb = _lbfgsb.setulb
        messages = _lbfgsb_py.status_messages, _lbfgsb_py.task_messages
        found = (setulb.__doc__ or "").split("\n", 1)[0]
    except (ImportError, AttributeError) as err:
        found = f"nothing of that name ({err})"
    if found != SIGNATURE:
        raise RuntimeError(
            f"solver 'lbfgs' calls SciPy's L-BFGS-B routine scipy.optimize._lbfgsb.setulb as "
            f"{SIGNATURE}, but SciPy {scipy.__version__} has {found}; install a SciPy whose "
            "routine has that signature (pip install 'scipy>=1.15'), or use the solver "
            "'preconditioned-lbfgs'")
    integer = np.int64 if getattr(_lbfgsb_py, "HAS_ILP64", False) else np.int32
    return _Routine(setulb, integer, *messages)


def _layout(n: int, m: int) -> dict[str, tuple[int, ...]]:
    """The shape of each of the routine's arrays for ``n`` parameters and ``m`` pairs."""
    return {"x": (n,), "f": (), "g": (n,), "wa": (2 * m * n + 5 * n + 11 * m * m + 8 * m,),
            "iwa": (3 * n,), "task": (2,), "ln_task": (2,), "lsave": (4,), "isave": (44,),
            "dsave": (29,)}


def _dtype(name: str, integer: type) -> type:
    return integer if name in _INTEGERS else np.float64


def _box(problem, integer: type) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The routine's lower and upper bounds (float64, 0 where absent) and bound codes (0: none,
    1: lower only, 2: both, 3: upper only), flat, as ``minimize`` translates them."""
    n = int(np.prod(problem.dims))
    lower, upper = (np.full(n, -np.inf) if b is None else np.asarray(b, np.float64).ravel()
                    for b in (problem.lower, problem.upper))
    has_lower, has_upper = ~np.isinf(lower), ~np.isinf(upper)
    codes = np.where(has_lower, np.where(has_upper, 2, 1), np.where(has_upper, 3, 0))
    return (np.where(has_lower, lower, 0.0), np.where(has_upper, upper, 0.0),
            codes.astype(integer))


@register("lbfgs")
class ScipyLBFGSB(Solver):
    """SciPy L-BFGS-B; see the module docstring and :class:`ScipyLBFGSBOptions`."""

    Options = ScipyLBFGSBOptions
    stochastic_ok = False

    def check_problem(self, problem) -> None:
        """Refuse a SciPy without the routine before any evaluation (a :class:`RuntimeError`,
        see :func:`_routine`)."""
        _routine()

    def init_state(self, run) -> dict:
        """The routine's arrays before its first call, at ``run.x``."""
        integer = _routine().integer
        state = {name: np.zeros(shape, _dtype(name, integer))
                 for name, shape in _layout(run.x.size, self.options.maxcor).items()}
        state["x"][:] = np.asarray(run.x, np.float64).ravel()
        state[_VERSION] = np.asarray(scipy.__version__)
        return state

    @classmethod
    def resumes_exactly(cls, arrays) -> bool:
        """True when ``arrays`` hold the routine's state written under this SciPy."""
        return _VERSION in arrays and str(arrays[_VERSION]) == scipy.__version__

    def state_from_arrays(self, arrays, run) -> dict:
        """The routine's arrays from a checkpoint, checked against the problem's size and
        ``maxcor``; fresh ones at the checkpoint's iterate, with a :class:`RuntimeWarning`,
        when the checkpoint holds none or was written under another SciPy version.

        Raises
        ------
        ValueError
            If some arrays are missing or their shapes do not fit the problem and ``maxcor``.
        """
        layout = _layout(run.x.size, self.options.maxcor)
        missing = sorted((set(layout) | {_VERSION}) - set(arrays))
        if arrays and missing:
            raise ValueError(f"the checkpoint's L-BFGS-B state lacks {', '.join(missing)}; "
                             "start a new run without resuming")
        saved = str(arrays[_VERSION]) if arrays else None
        if not self.resumes_exactly(arrays):
            why = ("holds no L-BFGS-B state (written before solver 'lbfgs' saved it)"
                   if saved is None else
                   f"was written under SciPy {saved}, whose L-BFGS-B state this SciPy "
                   f"{scipy.__version__} does not take")
            warnings.warn(f"the checkpoint {why}: the run continues from iteration "
                          f"{run.iteration} with its L-BFGS memory restarted, so it differs "
                          "from an uninterrupted run", RuntimeWarning, stacklevel=4)
            return self.init_state(run)
        wrong = [f"{name} has shape {arrays[name].shape}, expected {shape}"
                 for name, shape in layout.items() if arrays[name].shape != shape]
        if wrong:
            raise ValueError(
                f"the checkpoint's L-BFGS-B state does not fit {run.x.size} parameters and "
                f"maxcor {self.options.maxcor} ({'; '.join(wrong)}); resume on the problem "
                "it was written for, or start a new run without resuming")
        integer = _routine().integer
        state = {name: np.array(arrays[name], _dtype(name, integer)) for name in layout}
        state[_VERSION] = np.asarray(saved)
        return state

    def loop(self, run) -> str:
        budget = self.stopping.budget_spent(run.iteration, run.call_seconds)
        if budget:
            return budget
        problem, o = run.problem, self.options
        lbfgsb = _routine()
        box = _box(problem, lbfgsb.integer)
        factr = o.ftol / np.finfo(float).eps
        work = {name: np.array(value) for name, value in run.state.items()}  # run.state: a copy
        cache = EvaluationCache()
        cache.put(run.x, run.current)
        while True:
            lbfgsb.setulb(o.maxcor, work["x"], *box, work["f"], work["g"], factr, o.pgtol,
                          work["wa"], work["iwa"], work["task"], work["lsave"], work["isave"],
                          work["dsave"], o.maxls, work["ln_task"])
            task = int(work["task"][0])
            if task not in (_FG, _NEW_X):
                return f"scipy L-BFGS-B: {lbfgsb.message(work['task'])}"
            # a fresh array, not a view of the routine's x; rounding to the problem's dtype may
            # step over a bound
            x = problem.project(np.array(work["x"], problem.dtype).reshape(problem.dims))
            evaluation = cache.get(x)
            if task == _FG:
                evaluation = evaluation or cache.put(x, run.evaluate(x))
                work["f"][...] = evaluation.loss
                work["g"][:] = np.asarray(evaluation.grad, np.float64).ravel()
                continue
            state = {name: value.copy() for name, value in work.items()}
            reason = self.record(run, Step(x, evaluation or run.evaluate(x), state))
            if reason:
                return reason
