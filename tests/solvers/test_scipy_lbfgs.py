"""SciPy's L-BFGS-B (``lbfgs``): the iterates of ``scipy.optimize.minimize``, and a resume from
its checkpoints that continues bit for bit (or, from a checkpoint without the routine's state,
with its memory restarted and a warning)."""

import re

import numpy as np
import pytest
from scipy.optimize import Bounds, minimize

import operators as op
import solvers
from solvers.checkpoint import save_checkpoint
from solvers.scipy_lbfgs import SIGNATURE

from . import kill_worker


class Rosenbrock(op.Operator):
    r"""F(x) = (10 (x[1:] - x[:-1]²), x[:-1]): with data (0, 1), :math:`\|F(x) - d\|^2` is the
    chained Rosenbrock function :math:`\sum_i 100 (x_{i+1} - x_i^2)^2 + (1 - x_i)^2`."""

    def __init__(self, n):
        super().__init__(n, 2 * (n - 1), name="rosenbrock")

    def _forward(self, x):
        return np.concatenate([10 * (x[1:] - x[:-1] ** 2), x[:-1]])

    def _jvp(self, x, v):
        return np.concatenate([10 * (v[1:] - 2 * x[:-1] * v[:-1]), v[:-1]])

    def _vjp(self, x, w):
        curve, line = np.split(w, 2)
        out = np.zeros_like(x)
        out[1:] += 10 * curve
        out[:-1] += line - 20 * x[:-1] * curve
        return out


def rosenbrock_problem() -> solvers.Problem:
    """Six parameters with every kind of bound: none, lower, both, upper (two active at the
    minimizer, which would lie at all ones without them)."""
    lower = [-np.inf, -1.0, 0.5, -np.inf, -2.0, -1.5]
    upper = [np.inf, np.inf, 2.0, 0.8, 0.9, np.inf]
    return solvers.Problem(Rosenbrock(6), np.r_[np.zeros(5), np.ones(5)], lam=0.0, lower=lower,
                           upper=upper, x0=[-1.2, 1.0, 1.0, 0.0, 0.3, -1.0], name="rosenbrock")


def _recorder(iterates):
    """A callback appending a copy of each iterate to ``iterates``."""
    def record(run):
        iterates.append(np.array(run.x))
    return record


CASES = {
    "bounded tanh": (lambda: kill_worker.make_problem("lbfgs"), {}),
    "rosenbrock": (rosenbrock_problem, {"maxcor": 3, "ftol": 1e-13, "pgtol": 1e-9, "maxls": 8}),
}


@pytest.mark.parametrize("case", CASES)
def test_the_iterates_are_those_of_scipy_minimize(case):
    """On the same objective with the same options, the run's iterates, losses and end are
    ``scipy.optimize.minimize(method="L-BFGS-B")``'s bit for bit."""
    make, options = CASES[case]
    problem = make()
    ours = []
    result = solvers.get("lbfgs")(max_iter=500, **options).run(problem,
                                                                callbacks=[_recorder(ours)])

    def objective(flat):
        evaluation = problem.evaluate(flat.reshape(problem.dims))
        return evaluation.loss, np.asarray(evaluation.grad, np.float64).ravel()

    theirs, losses = [], []

    def callback(intermediate_result):
        theirs.append(intermediate_result.x.copy())
        losses.append(intermediate_result.fun)

    lower = np.broadcast_to(-np.inf if problem.lower is None else problem.lower, problem.dims)
    upper = np.broadcast_to(np.inf if problem.upper is None else problem.upper, problem.dims)
    reference = minimize(objective, problem.x0.ravel(), jac=True, method="L-BFGS-B",
                         bounds=Bounds(lower.ravel(), upper.ravel()), callback=callback,
                         options={"maxiter": 500, "maxcor": options.get("maxcor", 10),
                                  "ftol": options.get("ftol", 2.2e-9),
                                  "gtol": options.get("pgtol", 1e-5),
                                  "maxls": options.get("maxls", 20)})

    assert result.iterations == reference.nit == len(theirs) > 5
    np.testing.assert_array_equal(np.reshape(ours, (len(ours), -1)), theirs)
    np.testing.assert_array_equal(result.history["loss"][1:], losses)
    np.testing.assert_array_equal(result.x.ravel(), reference.x)
    assert result.stop_reason == f"scipy L-BFGS-B: {reference.message}"


@pytest.mark.parametrize(("iteration", "mode"), [(1, "after-save"), (8, "before-save"),
                                                 (15, "mid-write")])
def test_a_run_killed_after_k_iterations_resumes_bit_for_bit(tmp_path, iteration, mode):
    """A process running ``lbfgs`` dies by SIGKILL at ``iteration`` (``kill_worker.py``); the
    run resumed from the checkpoint left behind takes the uninterrupted run's iterates and
    ends as it does, bit for bit."""
    solver, problem = kill_worker.make_solver("lbfgs"), kill_worker.make_problem("lbfgs")
    iterates = []
    full = solver.run(problem, seed=kill_worker.SEED, callbacks=[_recorder(iterates)])
    assert full.iterations > 16, full.stop_reason
    path = tmp_path / "run.npz"
    kill_worker.killed_run("lbfgs", path, iteration, mode)
    checkpoint = solvers.load_checkpoint(path)
    saved = checkpoint.meta["iteration"]
    assert saved == {"after-save": 1, "before-save": 6, "mid-write": 14}[mode]
    assert solvers.get("lbfgs").resumes_exactly(checkpoint.state)

    continued = []
    resumed = solver.run(problem, resume=path, callbacks=[_recorder(continued)])
    np.testing.assert_array_equal(continued, iterates[saved:])
    np.testing.assert_array_equal(resumed.x, full.x)
    assert resumed.iterations == full.iterations
    assert resumed.stop_reason == full.stop_reason
    for column in ("iteration", "loss", "misfit", "regularizer", "grad_norm"):
        np.testing.assert_array_equal(resumed.history[column], full.history[column])


def _checkpoint_after(path, iterations):
    """Run ``kill_worker``'s ``lbfgs`` for ``iterations`` with a checkpoint at ``path``."""
    solver = solvers.get("lbfgs")(max_iter=iterations, gtol=kill_worker.GTOL,
                                  **kill_worker.OPTIONS["lbfgs"])
    solver.run(kill_worker.make_problem("lbfgs"), seed=kill_worker.SEED,
               callbacks=[solvers.Checkpoint(path)])
    return solvers.load_checkpoint(path)


@pytest.mark.parametrize(("state", "why"), [
    (lambda state: {}, r"holds no L-BFGS-B state \(written before solver 'lbfgs' saved it\)"),
    (lambda state: {**state, "scipy": np.asarray("1.15.0")},
     r"was written under SciPy 1\.15\.0, whose L-BFGS-B state this SciPy .* does not take"),
], ids=["without the state", "another SciPy"])
def test_a_checkpoint_without_a_usable_state_resumes_with_the_memory_restarted(tmp_path, state,
                                                                                why):
    """The run goes on from the saved iterate as a new run from there would (the L-BFGS memory
    empty), continuing the history and iteration count, and says so; it differs from the
    uninterrupted run."""
    path = tmp_path / "run.npz"
    saved = _checkpoint_after(path, 5)
    save_checkpoint(path, saved.meta, saved.x, saved.grad, state(saved.state))
    assert not solvers.get("lbfgs").resumes_exactly(solvers.load_checkpoint(path).state)
    solver, problem = kill_worker.make_solver("lbfgs"), kill_worker.make_problem("lbfgs")
    continued, restarted, uninterrupted = [], [], []
    with pytest.warns(RuntimeWarning, match=f"the checkpoint {why}: the run continues from "
                      "iteration 5 with its L-BFGS memory restarted, so it differs from an "
                      "uninterrupted run"):
        resumed = solver.run(problem, resume=path, callbacks=[_recorder(continued)])
    fresh = solver.run(problem, x0=saved.x, callbacks=[_recorder(restarted)])
    full = solver.run(problem, callbacks=[_recorder(uninterrupted)])

    np.testing.assert_array_equal(continued, restarted)
    assert resumed.iterations == 5 + fresh.iterations
    np.testing.assert_array_equal(resumed.history["loss"][:6], full.history["loss"][:6])
    np.testing.assert_array_equal(resumed.history["iteration"],
                                  np.arange(resumed.iterations + 1))
    assert not np.array_equal(continued[0], uninterrupted[5])


@pytest.mark.parametrize(("damage", "message"), [
    (lambda state: {**state, "wa": state["wa"][:-1]},
     r"does not fit 10 parameters and maxcor 10 \(wa has shape \(1429,\), expected \(1430,\)\)"),
    (lambda state: {k: v for k, v in state.items() if k != "isave"}, "lacks isave"),
    (lambda state: rosenbrock_state(),
     r"does not fit 10 parameters and maxcor 10 \(x has shape \(6,\), expected \(10,\); g has "
     r"shape \(6,\), expected \(10,\); wa has shape \(1330,\), expected \(1430,\); iwa has "
     r"shape \(18,\), expected \(30,\)\); resume on the problem it was written for"),
], ids=["truncated", "incomplete", "another problem's"])
def test_a_state_that_does_not_fit_the_problem_is_refused(tmp_path, damage, message):
    path = tmp_path / "run.npz"
    saved = _checkpoint_after(path, 3)
    save_checkpoint(path, saved.meta, saved.x, saved.grad, damage(saved.state))
    with pytest.raises(ValueError, match=message):
        kill_worker.make_solver("lbfgs").run(kill_worker.make_problem("lbfgs"), resume=path)


def rosenbrock_state():
    """The routine's state after two iterations on the 6-parameter Rosenbrock problem."""
    saved = []
    solvers.solve(rosenbrock_problem(), "lbfgs", max_iter=2,
                  callbacks=[lambda run: saved.append(run.state)])
    return saved[-1]


def test_a_scipy_with_another_routine_is_refused(nonlinear_problem, monkeypatch):
    from scipy.optimize import _lbfgsb

    def setulb(*args):
        """setulb(m,x,l,u,nbd,f,g,factr,pgtol,wa,iwa,task,iprint,csave,lsave,isave,dsave,maxls,[n])
        """

    monkeypatch.setattr(_lbfgsb, "setulb", setulb)
    with pytest.raises(RuntimeError, match=r"solver 'lbfgs' calls SciPy's L-BFGS-B routine "
                       rf"scipy.optimize._lbfgsb.setulb as {re.escape(SIGNATURE)}, but SciPy .* "
                       r"has setulb\(m,x,l,u,nbd,f,g,factr,pgtol,wa,iwa,task,iprint,csave,.*; "
                       r"install a SciPy whose routine has that signature \(pip install "
                       r"'scipy>=1.15'\)"):
        solvers.solve(nonlinear_problem, "lbfgs", max_iter=2)


def test_the_iterates_callbacks_see_stay_as_they_were(nonlinear_problem):
    """An unbounded float64 problem: each iterate is an array of its own, not the routine's
    working array, so the relative step the stopping rule ``rtol_x`` sees is the real one."""
    seen, copies = [], []

    def callback(run):
        seen.append(run.x)
        copies.append(run.x.copy())

    result = solvers.solve(nonlinear_problem, "lbfgs", max_iter=6, rtol_x=1e-9,
                           callbacks=[callback])
    assert result.iterations == 6, result.stop_reason
    np.testing.assert_array_equal(seen, copies)
