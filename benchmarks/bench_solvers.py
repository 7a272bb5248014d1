"""Time per iteration of every registered solver on the paper's voxel problem.

Paper configuration: 60³ voxels over the pool-fire box, four cameras of 32×32 pixels, 650–725
cm⁻¹ at 0.04 cm⁻¹, 8 cm⁻¹ FTIR resolution, float32; the packaged OpenFOAM pool fire as ground
truth, the paper's initialization (truth + 20 % noise), TV for ``pdhg`` and Tikhonov for the
others (Gauss–Newton needs a quadratic regularizer), λ = 1e-3 per ray (as in
:mod:`invflame.experiments.runner`). Each solver runs ``--iterations`` iterations after one
warm-up iteration (compilation) and prints the mean wall
time per iteration and the parameter memory, next to the paper's 430–432 ms and 3 MB per epoch
of its voxel runs (GPU, Adam; Tricard, Chen & Deng 2026, Table 1).

    python benchmarks/bench_solvers.py [--n-cells 60] [--iterations 3] [--solvers adam gd]
"""

import argparse

import solvers
from invflame.experiments.initialization import noisy_truth
from invflame.phantoms import poolfire
from invflame.representations import VoxelRepresentation
from invflame.scene import Scene

OPTIONS = {"adam": {"lr": 0.01}, "gauss-newton": {"inner_iter": 10}, "pdhg": {"inner_iter": 10}}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-cells", type=int, default=60)
    parser.add_argument("--n-pixels", type=int, default=32)
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--solvers", nargs="+", default=solvers.available())
    args = parser.parse_args()

    scene = Scene.paper(n_cells=args.n_cells, n_pixels=args.n_pixels)
    truth = poolfire(scene.grid)
    data = scene.simulate(truth.values)
    rep = VoxelRepresentation(scene.grid, scene.operator)
    x0 = rep.initial_parameters(noisy_truth(truth.values, 0.2, seed=0))
    print(f"voxel problem: grid {scene.grid.shape}, {scene.n_rays} rays, "
          f"{scene.wavenumber.size} -> {scene.out_wavenumber.size} wavenumbers, "
          f"{scene.segments.n_segments} segments; parameters {x0.nbytes / 1e6:.2f} MB "
          "[paper: 3.0 MB]")
    for name in args.solvers:
        regularizer = "tv" if name == "pdhg" else "tikhonov"
        problem = rep.problem(data, regularizer=regularizer, lam=1e-3 * scene.n_rays, x0=x0)
        options = OPTIONS.get(name, {})
        warm = solvers.solve(problem, name, max_iter=1, **options)
        result = solvers.solve(problem, name, x0=warm.x, max_iter=args.iterations, **options)
        times = result.history["time"]  # row 0 is the starting point's evaluation
        per_iteration = (times[-1] - times[0]) / max(result.iterations, 1)
        print(f"{name:>14} ({regularizer:>8}): {1e3 * per_iteration:8.0f} ms per iteration "
              f"over {result.iterations} iterations; loss {result.history['loss'][0]:.4g} -> "
              f"{result.loss:.4g}   [paper, Adam on GPU: 430-432 ms per epoch]")


if __name__ == "__main__":
    main()
