"""Time of the error bars of a quick-preset voxel problem against its reconstruction's.

Run: ``python benchmarks/bench_uncertainty.py [--method VG/Tikh.] [--truth poolfire]
[--iterations 40] [--rank 50]``.

Builds the problem of ``invflame study --preset quick`` for one voxel method
(:func:`~invflame.experiments.method_problem.method_problem`: its data, start and λ), solves
it with the method's solver and options for at most ``--iterations`` iterations, then computes
σ per voxel at the result as ``invflame uncertainty`` does (the low-rank Laplace posterior
of :mod:`invflame.experiments.posterior` with ``--rank`` eigenpairs, 10 extra probes and one
power iteration, and its propagation to the fields). Prints the wall and CPU time of both, per
solver iteration and per Hessian product, their ratios, the truncation of the rank, and both
costs projected to the method's iteration limit and to the default rank 100.
"""

import argparse
import time

import numpy as np

import solvers
from invflame.experiments import reproduce
from invflame.experiments.method_problem import method_problem
from invflame.experiments.posterior import laplace_posterior
from invflame.experiments.regularization import solver_options
from invflame.experiments.uncertainty import field_sigma, voxel_jacobian

OVERSAMPLING, POWER_ITERATIONS, DEFAULT_RANK = 10, 1, 100


def clocks() -> np.ndarray:
    """Wall and process CPU time, s."""
    return np.array([time.perf_counter(), time.process_time()])


def products(rank: int) -> int:
    """Hessian products of the randomized eigendecomposition at ``rank``."""
    return (POWER_ITERATIONS + 2) * (rank + OVERSAMPLING)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="bench_uncertainty")
    parser.add_argument("--truth", default="poolfire")
    parser.add_argument("--method", default="VG/Tikh.",
                        choices=[m for m in reproduce.METHODS if m.startswith("VG")])
    parser.add_argument("--iterations", type=int, default=40)
    parser.add_argument("--rank", type=int, default=50)
    args = parser.parse_args()
    setup = method_problem(args.method, args.truth)
    cfg = setup.cfg
    problem = setup.problem()
    print(f"{args.method} on {args.truth}, quick preset: {problem.dims} unknowns "
          f"({int(np.prod(problem.dims))}), {setup.measurement.n_measurements} measured values")

    start = clocks()
    result = solvers.solve(problem, cfg["solver"]["name"], max_iter=args.iterations,
                           seed=cfg["seed"], **solver_options(cfg, setup.measurement))
    solve = clocks() - start
    start = clocks()
    posterior = laplace_posterior(problem, result.x, args.rank, OVERSAMPLING, POWER_ITERATIONS,
                                  progress=True)
    sigma = field_sigma(voxel_jacobian(setup.representation, result.x),
                        posterior.voxel_covariance())
    uncertainty = clocks() - start

    per_iteration = solve / max(result.iterations, 1)
    per_product = uncertainty / products(args.rank)
    limit = cfg["solver"]["iterations"]
    print(f"reconstruction: {result.iterations} iterations ({result.stop_reason}), wall "
          f"{solve[0]:.1f} s, cpu {solve[1]:.1f} s; per iteration wall {per_iteration[0]:.2f} "
          f"s, cpu {per_iteration[1]:.2f} s")
    print(f"uncertainty at rank {args.rank}: {products(args.rank)} Hessian products, wall "
          f"{uncertainty[0]:.1f} s, cpu {uncertainty[1]:.1f} s; per product wall "
          f"{per_product[0]:.2f} s, cpu {per_product[1]:.2f} s; truncation d_k/(1+d_k) "
          f"{posterior.truncation:.3f} (d_k = {posterior.eigenvalues[-1]:.3g}); median sigma_T "
          f"{np.median(sigma[0]):.3g} K")
    print(f"ratios (wall, cpu): uncertainty / reconstruction {uncertainty[0] / solve[0]:.2f}, "
          f"{uncertainty[1] / solve[1]:.2f}; Hessian product / solver iteration "
          f"{per_product[0] / per_iteration[0]:.2f}, {per_product[1] / per_iteration[1]:.2f}")
    full_solve = per_iteration * limit
    full_uncertainty = per_product * products(DEFAULT_RANK)
    print(f"projected: reconstruction at the limit of {limit} iterations wall "
          f"{full_solve[0]:.0f} s; uncertainty at rank {DEFAULT_RANK} wall "
          f"{full_uncertainty[0]:.0f} s; ratio {full_uncertainty[0] / full_solve[0]:.2f}")
