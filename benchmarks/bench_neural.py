"""Epoch time and parameter memory of the neural representations at the paper's size.

Paper configuration: 60³ grid (regularizer sampling, voxel centres), 4 cameras of 32×32
pixels (4096 rays), 650–725 cm⁻¹ at 0.04 cm⁻¹ (1876 wavenumbers), 8 cm⁻¹ FTIR resolution,
Tikhonov regularizer, float32. One epoch is one pass over all rays, forward and backward:

* neural field: ``n_rays / batch_rays`` stochastic iterations (coarse and fine renderings of
  a ray batch, regularizer on a batch of voxel centres, gradient by backpropagation through
  the networks and the emission kernel's VJP);
* neural centres: one evaluation of the full objective and its gradient (network at all
  voxel centres, voxel forward map, its VJP, the network's VJP).

Compilation runs first (one warm-up iteration) and is not timed. The paper reports
479–493 ms per epoch and 65–66 MB on a GPU for its neural field (Tricard, Chen & Deng 2026,
Table 1). Here "parameter memory" is the size of the weights; the peak resident memory of
the process is printed for context (CPU).

    python benchmarks/bench_neural.py [--batches 2] [--n-coarse 64] [--n-fine 64]
"""

import argparse
import resource
import time

import numpy as np

from invflame.phantoms import synthetic_plume
from invflame.representations.neural import NeuralCentresRepresentation, NeuralFieldRepresentation
from invflame.scene import Scene

PAPER_MS = "479–493 ms"
PAPER_MB = "65–66 MB"


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bench_neural_field(scene, data, args):
    rep = NeuralFieldRepresentation(scene, n_coarse=args.n_coarse, n_fine=args.n_fine,
                                    batch_rays=args.batch_rays,
                                    batch_centres=args.batch_centres)
    theta = rep.initial_parameters()
    problem = rep.problem(data, "tikhonov", x0=theta)
    n_batches = -(-scene.n_rays // rep.renderer.batch_rays)
    timed = n_batches if args.batches is None else min(args.batches, n_batches)
    start = time.perf_counter()
    problem.value_and_grad(theta, 0, np.random.default_rng(0))
    compile_s = time.perf_counter() - start
    start = time.perf_counter()
    for k in range(timed):
        problem.value_and_grad(theta, k + 1, np.random.default_rng(k + 1))
    per_batch = (time.perf_counter() - start) / timed
    print(f"neural field: {rep.n_parameters} weights (coarse + fine), samples per ray "
          f"{args.n_coarse} coarse + {args.n_fine} fine, {rep.renderer.batch_rays} rays per "
          f"batch, {rep.batch_centres} centres per batch")
    print(f"  epoch ({n_batches} batches, {timed} timed): "
          f"{1e3 * per_batch * n_batches:.0f} ms   [paper, GPU: {PAPER_MS}]   "
          f"(first batch with compilation {compile_s:.1f} s)")
    print(f"  parameter memory: {rep.parameter_bytes(theta) / 1e6:.3f} MB   "
          f"[paper, GPU memory: {PAPER_MB}]")


def bench_neural_centres(scene, data, args):
    rep = NeuralCentresRepresentation(scene)
    theta = rep.initial_parameters()
    problem = rep.problem(data, "tikhonov", x0=theta)
    start = time.perf_counter()
    _ = problem.evaluate(theta).grad
    compile_s = time.perf_counter() - start
    times = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        _ = problem.evaluate(theta).grad
        times.append(time.perf_counter() - start)
    print(f"neural centres: {rep.n_parameters} weights, network at {rep.grid.n_voxels} voxel "
          f"centres, voxel forward map")
    print(f"  epoch (full objective + gradient, best of {args.repeats}): "
          f"{1e3 * min(times):.0f} ms   (first with compilation {compile_s:.1f} s)")
    print(f"  parameter memory: {rep.parameter_bytes(theta) / 1e6:.3f} MB")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n-coarse", type=int, default=64, help="coarse samples per ray")
    parser.add_argument("--n-fine", type=int, default=64, help="importance samples per ray")
    parser.add_argument("--batch-rays", type=int, default=1024, help="rays per iteration")
    parser.add_argument("--batch-centres", type=int, default=4096,
                        help="voxel centres per iteration for the regularizer")
    parser.add_argument("--batches", type=int, default=None,
                        help="time only this many batches and scale to an epoch "
                             "(default: the whole epoch)")
    parser.add_argument("--repeats", type=int, default=1,
                        help="timed epochs of the neural-centres representation")
    args = parser.parse_args()

    scene = Scene.paper()
    data = scene.simulate(synthetic_plume(scene.grid).values)
    print(f"scene: {scene.grid.shape} grid, {scene.n_rays} rays, {scene.wavenumber.size} "
          f"wavenumbers -> {scene.out_wavenumber.size} outputs, {scene.dtype}")
    bench_neural_field(scene, data, args)
    bench_neural_centres(scene, data, args)
    print(f"peak resident memory of this process: {peak_rss_mb():.0f} MB")


if __name__ == "__main__":
    main()
