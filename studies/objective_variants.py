r"""What a voxel fit scores when its objective changes: a likelihood with the model error, a
pull toward the start, another start, another solver.

Usage: python studies/objective_variants.py [--truth poolfire] [--method VG/Tikh.]
       [--lambdas 30] [--solver lbfgs] [--iterations 100] [--model-error N]
       [--anchor VOXELS] [--compact MU] [--start RUN] [--cells N]

On the honest quick problem of one voxel method (:func:`invflame.experiments.method_problem`:
the study's data, calibrated start and λ scale), solves for each λ from the start with the
study's plateau rule and prints χ²/M of the likelihood fitted, the objective, MSE_T, the gain
over the start, the hot-volume ratio, the iterations and why the solver stopped. Variants:

``--model-error N``
    The likelihood :math:`\sigma^2 = \mathrm{NESR}^2 + r(\nu)^2 d^2`: a relative model
    error :math:`r(\nu)` per wavenumber, the root of
    :math:`\sum (F_\text{fine} - F)^2 / \sum F^2` over ``N`` prior plumes rendered as the
    data are and by the reconstruction model from their average on its grid
    (:attr:`invflame.experiments.model_error.ModelError.relative_variance`); :math:`d` the
    measured radiance (0 where negative).
``--anchor VOXELS``
    The Tikhonov term plus a pull to the start, :math:`\mathrm{mean}(\lVert Du\rVert^2 +
    \lVert u - u_0\rVert^2 / \ell^2)` with :math:`\ell` = VOXELS grid spacings.
``--compact MU``
    The Tikhonov term plus a cost of the progress, :math:`\mathrm{mean}(\lVert Du\rVert^2)
    + \mu\,\mathrm{mean}(s)` over the parameters (:math:`s \ge 0`: an L1 norm that keeps
    air at :math:`s = 0` and the flame compact).
``--start RUN``
    Start from the reconstruction of a run folder (gains stay against the study's start).
``--cells N``
    Reconstruct on N voxels per axis (``truth.grid``; its own band-tomography start), scored
    with the truth averaged onto the preset's grid (30 per axis for ``quick``).
"""

import argparse
import dataclasses
from pathlib import Path

import numpy as np

import operators as op
import solvers
from invflame.experiments import reproduce
from invflame.experiments.method_problem import method_problem
from invflame.experiments.model_error import estimate_model_error
from invflame.field import Field
from invflame.representations.curvature import by_field, group_curvature
from operators.functionals import namespace


def anchored(problem: solvers.Problem, spacing, voxels: float) -> solvers.Problem:
    """``problem`` with its Tikhonov term joined by a pull to its start, and the screened
    Laplacian of both as its preconditioner."""
    dims = problem.dims
    pull = 1.0 / (voxels * float(np.min(spacing)))
    gradient = op.Gradient(dims, tuple(spacing), problem.dtype)
    stacked = op.vstack([gradient, pull * op.Identity(dims, dtype=problem.dtype)])
    offset = np.concatenate([np.zeros(int(np.prod(gradient.dimsd))),
                             pull * np.ravel(problem.x0)]).astype(problem.dtype)
    regularizer = op.Composite(op.SquaredL2(scale=1.0 / np.prod(dims),
                                            offset=offset.reshape(stacked.dimsd)), stacked)
    scale = problem.lam / np.prod(dims)
    return solvers.Problem(
        problem.forward, problem.data, regularizer=regularizer, lam=problem.lam,
        lower=problem.lower, upper=problem.upper, x0=problem.x0,
        name=f"{problem.name} + pull to the start",
        preconditioner=lambda: op.ScreenedPoissonSolve(
            dims, tuple(spacing), scale,
            group_curvature(problem.forward, problem.x0, by_field(dims)) + scale * pull**2))


class SquaresThenSum(op.Functional):
    r""":math:`c\,(\sum_{i < n} x_i^2 + \mu \sum_{i \ge n} x_i)` of a flat vector."""

    def __init__(self, scale: float, n_squares: int, weight: float):
        super().__init__(scale)
        self.n_squares, self.weight = int(n_squares), float(weight)

    def terms(self, x):
        x = namespace(x).ravel(x)
        return namespace(x).concatenate([x[:self.n_squares] ** 2,
                                         self.weight * x[self.n_squares:]])

    def grad(self, x):
        xp = namespace(x)
        flat = xp.ravel(x)
        slope = xp.full(flat.shape[0] - self.n_squares, self.weight, flat.dtype)
        return (self.scale * xp.concatenate([2.0 * flat[:self.n_squares], slope])).reshape(
            x.shape)


def compact(problem: solvers.Problem, spacing, weight: float) -> solvers.Problem:
    """``problem`` with its Tikhonov term joined by ``weight`` times the mean progress (the
    first field), its preconditioner kept."""
    dims = problem.dims
    gradient = op.Gradient(dims, tuple(spacing), problem.dtype)
    progress = np.zeros(dims, problem.dtype)
    progress[0] = 1.0
    stacked = op.vstack([gradient, op.Diagonal(progress)])
    functional = SquaresThenSum(1.0 / np.prod(dims), int(np.prod(gradient.dimsd)), weight)
    return solvers.Problem(
        problem.forward, problem.data, regularizer=op.Composite(functional, stacked),
        lam=problem.lam, lower=problem.lower, upper=problem.upper, x0=problem.x0,
        name=f"{problem.name} + mean progress",
        preconditioner=lambda: problem.preconditioner)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="objective_variants")
    parser.add_argument("--truth", default="poolfire")
    parser.add_argument("--method", default="VG/Tikh.", choices=("VG/NR", "VG/Tikh.", "VG/TV"))
    parser.add_argument("--lambdas", type=float, nargs="+", default=[30.0])
    parser.add_argument("--solver", default="lbfgs")
    parser.add_argument("--iterations", type=int, default=100)
    parser.add_argument("--model-error", type=int, default=0, metavar="N")
    parser.add_argument("--anchor", type=float, default=None, metavar="VOXELS")
    parser.add_argument("--compact", type=float, default=None, metavar="MU")
    parser.add_argument("--start", type=Path, default=None, metavar="RUN")
    parser.add_argument("--cells", type=int, default=None, metavar="N")
    args = parser.parse_args()
    setup = method_problem(args.method, args.truth, settings=None if args.cells is None else
                           {("truth", "grid"): args.cells})
    scored = (None if args.cells is None else
              (reproduce.method_config("quick", args.method, 0, "honest", args.truth)[
                  "truth"]["grid"],) * 3)
    if (args.anchor, args.compact) != (None, None) and setup.cfg["regularizer"][
            "kind"] != "tikhonov":
        parser.error("--anchor and --compact join a Tikhonov term: give --method VG/Tikh.")
    measurement = setup.measurement
    if args.model_error:
        r2 = estimate_model_error(setup.cfg, setup.scene, measurement, args.model_error,
                                  seed=setup.cfg["seed"]).relative_variance
        print(f"relative model error r: median {np.sqrt(np.median(r2)):.4f}, range "
              f"{np.sqrt(r2.min()):.4f}-{np.sqrt(r2.max()):.4f}")
        sigma = np.sqrt(np.broadcast_to(measurement.sigma, measurement.data.shape) ** 2
                        + r2 * np.maximum(measurement.data, 0.0) ** 2)
        measurement = dataclasses.replace(measurement, sigma=sigma)
    x0 = (None if args.start is None else setup.representation.initial_parameters(
        Field.load(args.start / "reconstruction.npz").values))
    start_mse = setup.scores(setup.x0, scored)["mse"]["T"]
    print(f"{args.method} on {args.truth}, {args.solver}; its start's MSE_T "
          f"{start_mse:.5f}")
    print("| λ | χ²/M | objective | MSE_T | gain | hot vol. | iterations | stopped by |")
    print("|---:|---:|---:|---:|---:|---:|---:|---|")
    m = measurement.n_measurements
    for lam in args.lambdas:
        problem = setup.problem(lam, measurement, x0)
        if args.anchor is not None:
            problem = anchored(problem, setup.scene.grid.spacing, args.anchor)
        if args.compact is not None:
            problem = compact(problem, setup.scene.grid.spacing, args.compact)
        result = solvers.solve(problem, args.solver, max_iter=args.iterations,
                               **setup.cfg["solver"]["options"])
        scores = setup.scores(result.x, scored)
        misfit = problem.evaluate(result.x).misfit
        print(f"| {lam:g} | {misfit / m:.4g} | {result.loss:.4g} | {scores['mse']['T']:.5f} | "
              f"{start_mse / scores['mse']['T']:.2f} | {scores['hot_volume_ratio']:.2f} | "
              f"{result.iterations} | {result.stop_reason.split(':')[0]} |", flush=True)
