"""Time the voxel objective and gradient as one compiled program against the operators' methods.

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
"""

import argparse

import numpy as np
from timing import CLOCKS

from invflame.experiments.machine import describe_machine, in_words
from invflame.phantoms import synthetic_plume
from invflame.representations.voxel import VoxelRepresentation
from invflame.scene import Scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays-per-pixel", type=int, default=1, help="sub-rays per pixel")
    parser.add_argument("--repeats", type=int, default=10, help="timed calls of each path")
    parser.add_argument("--clock", choices=list(CLOCKS), default="wall")
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


if __name__ == "__main__":
    main()
