"""Checkpoints and resume: an interrupted run, resumed, equals an uninterrupted one."""

import io

import numpy as np
import pylops
import pytest

import operators as op
import solvers
from solvers.checkpoint import save_checkpoint

from . import kill_worker

OPTIONS = {"gd": {}, "adam": {"lr": 0.05}, "gauss-newton": {}, "lbfgs": {},
           "pdhg": {"inner_iter": 10}, "jaxopt-lbfgs": {},
           "preconditioned-lbfgs": {}}


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


@pytest.mark.parametrize("name", solvers.available())
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


def test_a_checkpoint_without_its_gradient_resumes_by_evaluating_it(nonlinear_problem,
                                                                     tmp_path):
    """A checkpoint may hold no gradient (``save_checkpoint(..., grad=None, ...)``): the
    resumed run evaluates it again and goes on as the uninterrupted run."""
    solver = solvers.get("adam")(max_iter=6, lr=0.05)
    full = solver.run(nonlinear_problem, seed=5)
    path = tmp_path / "run.npz"
    with pytest.raises(Interrupt):
        solver.run(nonlinear_problem, seed=5, callbacks=[solvers.Checkpoint(path, every=1),
                                                         interrupt_at(3)])
    saved = solvers.load_checkpoint(path)
    assert saved.grad is not None
    save_checkpoint(path, saved.meta, saved.x, None, saved.state)
    assert solvers.load_checkpoint(path).grad is None
    resumed = solver.run(nonlinear_problem, resume=path)
    np.testing.assert_array_equal(resumed.x, full.x)
    np.testing.assert_array_equal(resumed.history["loss"], full.history["loss"])


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


def test_resume_refuses_another_solver_or_other_options(nonlinear_problem, tmp_path):
    path = tmp_path / "adam.npz"
    solvers.solve(nonlinear_problem, "adam", lr=0.05, max_iter=2,
                  callbacks=[solvers.Checkpoint(path)])
    with pytest.raises(ValueError, match="written by solver 'adam'"):
        solvers.solve(nonlinear_problem, "gd", resume=path)
    assert solvers.load_checkpoint(path).meta["options"] == {"lr": 0.05, "betas": [0.9, 0.999],
                                                            "eps": 1e-8}
    with pytest.raises(ValueError, match="written with other options of solver 'adam' \\(betas: "
                       r"\[0.9, 0.999\] in the checkpoint, \[0.5, 0.999\] now; lr: 0.05 in the "
                       r"checkpoint, 0.1 now\); resume with the same options"):
        solvers.solve(nonlinear_problem, "adam", lr=0.1, betas=(0.5, 0.999), resume=path)
    # the same options, spelled as another type that converts to the same value
    resumed = solvers.solve(nonlinear_problem, "adam", lr=0.05, betas=[0.9, 0.999], max_iter=3,
                            resume=path)
    assert resumed.iterations == 3
    with pytest.raises(FileNotFoundError, match="no checkpoint"):
        solvers.solve(nonlinear_problem, "adam", resume=tmp_path / "missing.npz")


@pytest.mark.parametrize("seconds, saves", [(0.0, [2, 4, 6, 7]), (3600.0, [7])])
def test_checkpoints_wait_their_seconds_between_saves(nonlinear_problem, tmp_path, monkeypatch,
                                                      seconds, saves):
    """Every 2nd iteration saves unless ``seconds`` have not passed since the last save; the
    end of the run (iteration 7) always saves."""
    saved = []
    monkeypatch.setattr(solvers.base.RunState, "save",
                        lambda run, path: saved.append(run.iteration))
    solvers.solve(nonlinear_problem, "gd", max_iter=7,
                  callbacks=[solvers.Checkpoint(tmp_path / "run.npz", every=2, seconds=seconds)])
    assert saved == saves
    with pytest.raises(ValueError, match="seconds must be a number >= 0"):
        solvers.Checkpoint(tmp_path / "run.npz", seconds=-1.0)


def test_stopping_rules_and_callbacks(nonlinear_problem):
    p = nonlinear_problem
    assert solvers.solve(p, "gd", rtol_loss=1e-3).stop_reason.startswith("rtol_loss")
    assert solvers.solve(p, "gd", rtol_x=1e-3).stop_reason.startswith("rtol_x")
    assert solvers.solve(p, "gd", gtol=1e-4).stop_reason.startswith("gtol")
    assert solvers.solve(p, "gd", gtol=1e-4).converged
    assert not solvers.solve(p, "gd", max_iter=2).converged
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
    assert not timed.converged and not stopped.converged
    stopped.stop_reason = "scipy L-BFGS-B: ABNORMAL: "  # a failed line search, 0 iterations
    assert not stopped.converged
    stream = io.StringIO()
    bar = solvers.ProgressBar(file=stream, mininterval=0)
    result = solvers.solve(p, "adam", lr=0.05, max_iter=7, callbacks=[bar])
    assert "7/7" in stream.getvalue() and "loss=" in stream.getvalue()
    assert len(result.history) == 8 and result.history["iteration"][-1] == 7


@pytest.mark.parametrize(("damage", "reason"), [
    (lambda data: b"", "an empty file"),
    (lambda data: data[: len(data) // 2], "bytes, unreadable"),
    (lambda data: b"not a checkpoint at all" * 10, "bytes, unreadable"),
])
def test_a_damaged_checkpoint_is_named_with_what_to_do(nonlinear_problem, tmp_path, damage,
                                                       reason):
    path = tmp_path / "adam.npz"
    solvers.solve(nonlinear_problem, "adam", lr=0.05, max_iter=2,
                  callbacks=[solvers.Checkpoint(path)])
    path.write_bytes(damage(path.read_bytes()))
    with pytest.raises(solvers.atomic.CorruptFileError,
                       match=f"checkpoint {path} is damaged or incomplete \\(.*{reason}.*\\); "
                             "delete it and start the run again without resuming"):
        solvers.solve(nonlinear_problem, "adam", lr=0.05, resume=path)


def test_checkpoint_writers_use_their_own_temporary_files(tmp_path, monkeypatch):
    import tempfile

    from solvers.checkpoint import save_checkpoint

    made = []
    mkstemp = tempfile.mkstemp

    def recording_mkstemp(*args, **kwargs):
        made.append(mkstemp(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(tempfile, "mkstemp", recording_mkstemp)
    path = tmp_path / "checkpoint.npz"
    for value in (1.0, 2.0):
        save_checkpoint(path, {"iteration": int(value)}, np.full(3, value), None, {})
    names = [name for _, name in made]
    assert len(set(names)) == 2 and all(name != str(path) + ".tmp" for name in names)
    assert list(tmp_path.iterdir()) == [path]
    np.testing.assert_array_equal(solvers.load_checkpoint(path).x, np.full(3, 2.0))


KILL_RNG = np.random.default_rng(20261123)
KILL_MODES = dict(zip(solvers.available(),
                      np.resize(KILL_RNG.permutation(kill_worker.MODES), len(solvers.available())),
                      strict=True))
"""A mode of death for each solver, every mode used (see ``kill_worker.py``)."""


def _kill_iteration(name, iterations, mode):
    """A seeded random iteration to die at, after the first checkpoint and before the end."""
    first = 2 if mode == "before-save" else 1
    rng = np.random.default_rng([20261123, *name.encode()])
    return int(rng.integers(first + (mode == "mid-write"), iterations))


def _killed_and_resumed(tmp_path, name):
    """Solver ``name`` run uninterrupted, and run by ``kill_worker.py`` until it dies at a
    seeded random iteration (in its mode of :data:`KILL_MODES`), then resumed from the
    checkpoint left behind: the full and the resumed run, the iteration of death and the
    checkpoint's iteration."""
    solver, problem = kill_worker.make_solver(name), kill_worker.make_problem(name)
    full = solver.run(problem, seed=kill_worker.SEED)  # kill_worker.run; one solver keeps its jit
    iteration = _kill_iteration(name, full.iterations, KILL_MODES[name])
    path = tmp_path / "run.npz"
    kill_worker.killed_run(name, path, iteration, KILL_MODES[name])
    saved = solvers.load_checkpoint(path).meta["iteration"]
    return full, solver.run(problem, resume=path), iteration, saved


@pytest.mark.parametrize("name", solvers.available())
def test_a_run_killed_at_a_random_point_resumes_bit_for_bit(tmp_path, name):
    """Every solver: a process running it dies by SIGKILL at a random
    iteration (after a checkpoint, before one, or halfway through writing one); the run resumed
    from the checkpoint left behind equals the uninterrupted run bit for bit."""
    full, resumed, iteration, saved = _killed_and_resumed(tmp_path, name)
    # before-save dies at `iteration` before its save: the last even iteration below it
    assert saved == {"after-save": iteration,
                     "before-save": (iteration - 1) - (iteration - 1) % 2,
                     "mid-write": iteration - 1}[KILL_MODES[name]]

    assert resumed.iterations == full.iterations and resumed.seed == kill_worker.SEED
    assert resumed.stop_reason == full.stop_reason
    np.testing.assert_array_equal(resumed.x, full.x)
    for column in ("iteration", "loss", "misfit", "regularizer", "grad_norm"):
        np.testing.assert_array_equal(resumed.history[column], full.history[column])
