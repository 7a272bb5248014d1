"""Runs of every registered solver on a tiny problem, and a process that dies by SIGKILL in one.

``python kill_worker.py NAME CHECKPOINT ITERATION MODE`` runs solver ``NAME`` as
:func:`run` does and sends itself SIGKILL at iteration ``ITERATION``:

``after-save``
    right after the checkpoint of that iteration is written (saved every iteration);
``before-save``
    before its checkpoint (saved every second iteration), so the work since the last one is
    lost;
``mid-write``
    halfway through writing that iteration's checkpoint, leaving a torn temporary file beside
    the previous checkpoint.

The tests import this module for :func:`killed_run`, which runs it so, and for
:func:`make_problem` and :func:`make_solver`, so that the killed run and the runs they compare
it with share one definition.
"""

from __future__ import annotations

import importlib.util
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pylops

import operators as op
import solvers

MODES = ("after-save", "before-save", "mid-write")
SEED = 11
OPTIONS = {"gd": {}, "adam": {"lr": 0.05}, "gauss-newton": {"damping": 1.0},
           "lbfgs": {"pgtol": 0.0, "ftol": 0.0}, "pdhg": {"inner_iter": 10},
           "jaxopt-lbfgs": {}, "preconditioned-lbfgs": {}}
"""Each solver's options; SciPy's tolerances at 0, so that its L-BFGS-B runs until the loss
no longer falls in float64."""
MAX_ITER = {"lbfgs": 200}
"""Iteration limits other than 12: SciPy's L-BFGS-B runs until its own test ends it (after 18
iterations)."""
GTOL = 1e-8
"""Projected-gradient norm (loss units per parameter unit) that ends a run early."""


def _fixtures():
    spec = importlib.util.spec_from_file_location("solver_fixtures",
                                                  Path(__file__).with_name("conftest.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def make_problem(name: str) -> solvers.Problem:
    """Bounded nonlinear least squares, F(x) = tanh(Ax) + 0.1 Ax with 10 parameters; with a
    first-difference total variation for ``pdhg`` (dual state to carry), a first-difference
    Tikhonov term otherwise."""
    rng = np.random.default_rng(0)
    forward = _fixtures().NumpyTanh(rng.standard_normal((30, 10)) / 3)
    data = forward(0.5 * rng.standard_normal(10))
    diff = op.aslinearoperator(pylops.FirstDerivative(10, kind="forward", edge=False))
    outer = op.L1() if name == "pdhg" else op.SquaredL2()
    return solvers.Problem(forward, data, regularizer=(outer, diff), lam=1e-2, lower=-0.6,
                           x0=np.zeros(10), name="bounded tanh")


def make_solver(name: str) -> solvers.Solver:
    """Solver ``name`` with its options of :data:`OPTIONS` and the stopping rules."""
    return solvers.get(name)(max_iter=MAX_ITER.get(name, 12), gtol=GTOL, **OPTIONS[name])


def run(name: str, callbacks=()) -> solvers.Result:
    """The uninterrupted run of solver ``name`` (seed :data:`SEED`)."""
    return make_solver(name).run(make_problem(name), seed=SEED, callbacks=callbacks)


def killed_run(name: str, path: Path, iteration: int, mode: str) -> None:
    """Run this script for solver ``name`` with checkpoints at ``path`` until it kills itself
    with SIGKILL at ``iteration`` in ``mode``; asserts that it died so, leaving a torn temporary
    file beside the checkpoint exactly when killed mid-write."""
    done = subprocess.run([sys.executable, __file__, name, str(path), str(iteration), mode],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert done.returncode == -signal.SIGKILL, done.stderr
    torn = [p.name for p in path.parent.iterdir() if p.name.endswith(".tmp")]
    assert len(torn) == (mode == "mid-write"), torn


def _die():
    os.kill(os.getpid(), signal.SIGKILL)


def main(name: str, path: str, iteration: int, mode: str) -> None:
    """Run solver ``name`` with checkpoints at ``path`` and die at ``iteration`` (see above)."""

    def kill(run_state):
        if run_state.iteration == iteration:
            _die()

    if mode == "after-save":
        callbacks = [solvers.Checkpoint(path, every=1), kill]
    elif mode == "before-save":
        callbacks = [kill, solvers.Checkpoint(path, every=2)]
    else:
        import solvers.checkpoint as checkpoint

        save = checkpoint.save_checkpoint

        def torn_save(target, meta, *arrays):
            if meta["iteration"] != iteration:
                return save(target, meta, *arrays)

            def write(stream):
                stream.write(b"PK\x03\x04 half of a checkpoint")
                stream.flush()
                _die()

            return checkpoint.write_atomic(target, write)

        checkpoint.save_checkpoint = torn_save
        callbacks = [solvers.Checkpoint(path, every=1)]
    run(name, callbacks)
    sys.exit(f"solver {name} finished without reaching iteration {iteration}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4])
