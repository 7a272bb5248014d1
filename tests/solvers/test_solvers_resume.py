"""Checkpoints and resume: an interrupted run, resumed, equals an uninterrupted one."""

import io

import numpy as np
import pylops
import pytest

import operators as op
import solvers

OPTIONS = {"gd": {}, "adam": {"lr": 0.05}, "gauss-newton": {}, "lbfgs": {},
           "pdhg": {"inner_iter": 10}, "jaxopt-lbfgs": {}}
EXACT = [name for name in solvers.available() if solvers.get(name).exact_resume]


class Interrupt(Exception):
    pass


def interrupt_at(iteration):
    def callback(run):
        if run.iteration == iteration:
            raise Interrupt(f"stopped at {iteration}")
    return callback


@pytest.fixture
def problem_for(nonlinear_problem, numpy_forward):
    """The nonlinear test problem (with total variation for pdhg, to carry dual state)."""
    def make(name):
        if name != "pdhg":
            return nonlinear_problem
        diff = op.aslinearoperator(pylops.FirstDerivative(10, kind="forward", edge=False))
        return solvers.Problem(numpy_forward, nonlinear_problem.data, regularizer=(op.L1(), diff),
                               lam=0.1, lower=-0.6, x0=np.zeros(10))
    return make


@pytest.mark.parametrize("name", EXACT)
def test_interrupted_and_resumed_run_equals_uninterrupted_run(problem_for, tmp_path, name):
    problem = problem_for(name)
    solver = solvers.get(name)(max_iter=8, **OPTIONS[name])
    full = solver.run(problem, seed=5)
    assert full.iterations > 3, full

    path = tmp_path / "run.npz"
    with pytest.raises(Interrupt):
        solver.run(problem, seed=5, callbacks=[solvers.Checkpoint(path, every=2),
                                               interrupt_at(3)])
    assert solvers.load_checkpoint(path).meta["iteration"] == 3  # saved when interrupted
    assert list(tmp_path.iterdir()) == [path]  # written atomically, no temporary left
    resumed = solver.run(problem, resume=path)

    assert resumed.iterations == full.iterations and resumed.seed == 5
    assert resumed.stop_reason == full.stop_reason
    np.testing.assert_array_equal(resumed.x, full.x)
    for column in ("iteration", "loss", "misfit", "regularizer", "grad_norm"):
        np.testing.assert_array_equal(resumed.history[column], full.history[column])


@pytest.mark.parametrize("name", ["adam", "gd"])
def test_stochastic_run_resumes_exactly(stochastic_problem, tmp_path, name):
    sp = stochastic_problem
    full = solvers.solve(sp, name, max_iter=9, seed=3, **OPTIONS[name])
    path = tmp_path / "stochastic.npz"
    solvers.solve(sp, name, max_iter=4, seed=3, callbacks=[solvers.Checkpoint(path, every=1)],
                  **OPTIONS[name])
    resumed = solvers.solve(sp, name, max_iter=9, resume=path, **OPTIONS[name])
    np.testing.assert_array_equal(resumed.x, full.x)
    np.testing.assert_array_equal(resumed.history["loss"], full.history["loss"])
    other_seed = solvers.solve(sp, name, max_iter=9, seed=4, **OPTIONS[name])
    assert not np.array_equal(other_seed.x, full.x)


def test_scipy_lbfgs_resume_continues_the_run(nonlinear_problem, tmp_path):
    assert not solvers.get("lbfgs").exact_resume  # SciPy restarts its memory on resume
    path = tmp_path / "lbfgs.npz"
    first = solvers.solve(nonlinear_problem, "lbfgs", max_iter=4,
                          callbacks=[solvers.Checkpoint(path)])
    resumed = solvers.solve(nonlinear_problem, "lbfgs", max_iter=40, resume=path)
    assert first.iterations == 4 and resumed.iterations > 4
    np.testing.assert_array_equal(resumed.history["loss"][:5], first.history["loss"])
    np.testing.assert_array_equal(resumed.history["iteration"],
                                  np.arange(resumed.iterations + 1))
    assert resumed.loss < 1e-3 * first.history["loss"][0]


def test_resume_refuses_another_solver_or_other_options(nonlinear_problem, tmp_path):
    path = tmp_path / "adam.npz"
    solvers.solve(nonlinear_problem, "adam", lr=0.05, max_iter=2,
                  callbacks=[solvers.Checkpoint(path)])
    with pytest.raises(ValueError, match="written by solver 'adam'"):
        solvers.solve(nonlinear_problem, "gd", resume=path)
    with pytest.raises(ValueError, match="other options.*'lr': \\(0.05, 0.1\\)"):
        solvers.solve(nonlinear_problem, "adam", lr=0.1, resume=path)
    with pytest.raises(FileNotFoundError, match="no checkpoint"):
        solvers.solve(nonlinear_problem, "adam", resume=tmp_path / "missing.npz")


def test_stopping_rules_and_callbacks(nonlinear_problem):
    p = nonlinear_problem
    assert solvers.solve(p, "gd", rtol_loss=1e-3).stop_reason.startswith("rtol_loss")
    assert solvers.solve(p, "gd", rtol_x=1e-3).stop_reason.startswith("rtol_x")
    assert solvers.solve(p, "gd", gtol=1e-4).stop_reason.startswith("gtol")
    # over a window: stops once the loss changed less than rtol over the last 5 iterations
    windowed = solvers.solve(p, "gd", rtol_loss=1e-3, loss_window=5, max_iter=500)
    assert windowed.stop_reason.startswith("rtol_loss") and "over 5 iterations" in \
        windowed.stop_reason
    loss = windowed.history["loss"]
    assert abs(loss[-1] - loss[-6]) <= 1e-3 * abs(loss[-6])
    assert all(abs(loss[k] - loss[k - 5]) > 1e-3 * abs(loss[k - 5])
               for k in range(5, len(loss) - 1))
    with pytest.raises(ValueError, match="loss_window must be a positive integer"):
        solvers.solve(p, "gd", loss_window=0)
    timed = solvers.solve(p, "gd", time_budget=0.0)
    assert timed.stop_reason.startswith("time_budget") and timed.iterations == 0
    stopped = solvers.solve(p, "gd", callbacks=[lambda run: run.iteration == 3])
    assert stopped.iterations == 3 and stopped.stop_reason.startswith("callback")
    stream = io.StringIO()
    bar = solvers.ProgressBar(file=stream, mininterval=0)
    result = solvers.solve(p, "adam", lr=0.05, max_iter=7, callbacks=[bar])
    assert "7/7" in stream.getvalue() and "loss=" in stream.getvalue()
    assert len(result.history) == 8 and result.history["iteration"][-1] == 7
