"""Time the voxel objective and gradient compiled whole against the operators' methods.

Run: ``python benchmarks/bench_objective.py [--rays-per-pixel 1] [--repeats 10] [--clock wall]``.

At the paper configuration (60³ voxels, four cameras of 32×32 pixels, 1876 wavenumbers,
float32), the voxel problem (:meth:`~invflame.representations.voxel.VoxelRepresentation.problem`)
with the Tikhonov and the TV regularizer, at the synthetic plume's fields with T lowered by a
tenth: ``problem.evaluate(x).grad``, the loss and gradient of one epoch, once from the compiled
program (:attr:`solvers.Problem.compiled`, what Adam and L-BFGS use) and once through the
operators' own methods (``jacobians=True``, what Gauss–Newton and PDHG use). After one
untimed call of each (compiling), the two alternate ``--repeats`` times; the best of each,
their ratio and the relative differences of the loss and the gradient are printed, with the
machine.

Then the host's share of an epoch of the paper's voxel solver (Adam, lr 0.01, TV): after 3
untimed iterations (which compile Adam's step on the device), ``--epochs`` Adam iterations
with the objective's value and gradient computed once beforehand and handed back at every
point (the fields' domain check and the point's copy to the device still done), with the
runner's checkpoints (:data:`~invflame.experiments.runner.CHECKPOINT_EVERY`,
:data:`~invflame.experiments.runner.CHECKPOINT_SECONDS`) and, for comparison, a checkpoint
every 10 iterations: what an epoch costs beyond the objective (Adam's step, the bounds, the
history's gradient norm, the check, the copies between host and device, the checkpoints), in
ms per epoch. On a CPU, JAX's device is the CPU: Adam's step counts here whether NumPy or a
compiled program computes it.
"""

import argparse
import tempfile
from pathlib import Path

import numpy as np
from timing import CLOCKS

import solvers
from invflame.experiments.machine import describe_machine, in_words
from invflame.experiments.reproduce import SOLVERS
from invflame.experiments.runner import CHECKPOINT_EVERY, CHECKPOINT_SECONDS
from invflame.phantoms import synthetic_plume
from invflame.representations.voxel import VoxelRepresentation
from invflame.scene import Scene
from operators import precision
from operators.interop import to_jax


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays-per-pixel", type=int, default=1, help="sub-rays per pixel")
    parser.add_argument("--repeats", type=int, default=10, help="timed calls of each path")
    parser.add_argument("--clock", choices=list(CLOCKS), default="wall")
    parser.add_argument("--epochs", type=int, default=100,
                        help="Adam iterations timed for the host's share of an epoch")
    args = parser.parse_args()
    scene = Scene.paper(rays_per_pixel=args.rays_per_pixel)
    truth = synthetic_plume(scene.grid).values
    data = scene.simulate(truth)
    start = truth.copy()
    start[0] = 0.9 * truth[0] + 30.0
    rep = VoxelRepresentation(scene.grid, scene.operator)
    now = CLOCKS[args.clock]
    print(f"scene: {scene.grid.shape} grid, {scene.n_rays} rays x {scene.rays_per_pixel} "
          f"sub-rays, {scene.wavenumber.size} wavenumbers, {scene.dtype}")
    print(f"computing on: {in_words(describe_machine(uses_torch=False))}")
    print(f"objective and gradient, best of {args.repeats} ({args.clock} clock):")
    for regularizer in ("tikhonov", "tv"):
        problem = rep.problem(data, regularizer, x0=rep.initial_parameters(start))
        x = problem.x0
        paths = {"compiled": {}, "operators": {"jacobians": True}}
        compiled, operators = (problem.evaluate(x, **kwargs) for kwargs in paths.values())
        best = {name: np.inf for name in paths}
        for _ in range(args.repeats):
            for name, kwargs in paths.items():
                begin = now()
                gradient = problem.evaluate(x, **kwargs).grad  # NumPy: the work is done
                assert gradient.shape == problem.dims
                best[name] = min(best[name], now() - begin)
        loss = abs(compiled.loss - operators.loss) / operators.loss
        grad = np.linalg.norm(compiled.grad - operators.grad) / np.linalg.norm(operators.grad)
        print(f"  {regularizer:>8}: compiled {1e3 * best['compiled']:7.1f} ms, operators "
              f"{1e3 * best['operators']:7.1f} ms ({best['operators'] / best['compiled']:.2f}x);"
              f" relative differences: loss {loss:.1e}, gradient {grad:.1e}")

    print(f"host work of an Adam epoch, the objective precomputed (mean of {args.epochs}):")
    problem.compiled = Precomputed(problem.compiled, problem.x0, problem.lam)
    host_epoch(problem, 3, 0.0, now)  # untimed: compiles what the step runs on the device
    for label, seconds in (("the runner's checkpoints", CHECKPOINT_SECONDS),
                           ("a checkpoint every 10 epochs", 0.0)):
        host = host_epoch(problem, args.epochs, seconds, now)
        print(f"  {label:>28}: {1e3 * host:6.2f} ms")


class Precomputed:
    """A compiled objective's value and gradient at one point, handed back at every point
    after the operators' domain checks of that point and its copy to JAX's device (the
    gradient stays there, as the compiled objective's does)."""

    def __init__(self, compiled, x, lam: float):
        self.checks, self.dtype = compiled.checks, compiled.dtype
        self.bounds = compiled.bounds
        self.projected_gradient_norm = compiled.projected_gradient_norm
        self.misfit, self.regularizer, _, grad = compiled(x, lam)
        self.grad = grad()

    def __call__(self, x, lam: float):
        for check in self.checks:
            check(x)
        with precision(self.dtype):
            point = to_jax(x, self.dtype)
        return self.misfit, self.regularizer, point, lambda: self.grad


def host_epoch(problem, epochs: int, seconds: float, now) -> float:
    """Seconds per Adam iteration of ``problem`` (its objective :class:`Precomputed`)."""
    solver = solvers.get(SOLVERS["voxel"]["name"])(max_iter=epochs, **SOLVERS["voxel"]["options"])
    with tempfile.TemporaryDirectory() as folder:
        checkpoint = solvers.Checkpoint(Path(folder) / "checkpoint.npz", every=CHECKPOINT_EVERY,
                                        seconds=seconds)
        begin = now()
        solver.run(problem, callbacks=[checkpoint])
        return (now() - begin) / epochs


if __name__ == "__main__":
    main()
