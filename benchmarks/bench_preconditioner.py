"""Objective against iterations: SciPy's L-BFGS-B beside L-BFGS preconditioned by the voxel
grid's screened Laplacian, on one honest voxel problem.

Run: ``python benchmarks/bench_preconditioner.py [--truth poolfire] [--method VG/Tikh.]
[--lam 30] [--iterations 100]``.

Builds the problem of ``invflame study --preset quick`` for one voxel method (its data, its
calibrated start, its λ unless ``--lam`` is given) and solves it from the same start with
``lbfgs`` (SciPy), ``preconditioned-lbfgs`` without its preconditioner (projected L-BFGS) and
with it (:class:`operators.ScreenedPoissonSolve` of
:meth:`~invflame.representations.voxel.VoxelRepresentation.problem`), each for
``--iterations`` iterations and no other stopping rule. Prints per solver the objective after
10, 25, 50 and all iterations, the evaluations of the objective, the wall time, the iteration
at which it first reaches SciPy's final objective, and MSE_T of the fields against the truth
(with the start's): how fast a solver minimizes, and what the minimum is worth.
"""

import argparse
import time

import numpy as np

import solvers
from invflame.experiments import reproduce
from invflame.experiments.method_problem import method_problem

SOLVERS = {"lbfgs (SciPy)": ("lbfgs", {}),
           "projected L-BFGS": ("preconditioned-lbfgs", {"precondition": False}),
           "preconditioned L-BFGS": ("preconditioned-lbfgs", {})}


class Counted:
    """Counts the objective's evaluations of a problem."""

    def __init__(self, problem):
        self.calls = 0
        self._evaluate = problem.evaluate
        problem.evaluate = self

    def __call__(self, *args, **kwargs):
        self.calls += 1
        return self._evaluate(*args, **kwargs)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="bench_preconditioner")
    parser.add_argument("--truth", default="poolfire")
    parser.add_argument("--method", default="VG/Tikh.",
                        choices=[m for m in reproduce.METHODS if m.startswith("VG")])
    parser.add_argument("--lam", type=float, default=None)
    parser.add_argument("--iterations", type=int, default=100)
    args = parser.parse_args()
    setup = method_problem(args.method, args.truth)
    lam = setup.cfg["regularizer"]["lambda"] if args.lam is None else args.lam
    print(f"{args.method} on {args.truth}, λ {lam:g}, {args.iterations} iterations; start "
          f"MSE_T {setup.scores(setup.x0)['mse']['T']:.5f}")
    print("| solver | objective: 10 it | 25 it | 50 it | last | evaluations | seconds | "
          "reaches SciPy's last at | MSE_T |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    target = None
    for label, (name, options) in SOLVERS.items():
        problem = setup.problem(lam)
        counter = Counted(problem)
        began = time.perf_counter()
        result = solvers.solve(problem, name, max_iter=args.iterations, **options)
        seconds = time.perf_counter() - began
        loss = np.asarray(result.history["loss"])
        target = loss[-1] if target is None else target
        reached = np.flatnonzero(loss <= target)
        at = [f"{loss[min(i, loss.size - 1)]:.4g}" for i in (10, 25, 50)]
        print(f"| {label} | {' | '.join(at)} | {loss[-1]:.4g} | {counter.calls} | "
              f"{seconds:.0f} | {reached[0] if reached.size else '–'} | "
              f"{setup.scores(result.x)['mse']['T']:.5f} |", flush=True)
