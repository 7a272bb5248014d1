"""Epoch time and memory of the neural field against the voxel grid, in one process.

Paper configuration (default): 60³ grid, 4 cameras of 32×32 pixels (4096 measured rays,
``--rays-per-pixel`` sub-rays each, 9 by default as in :meth:`Scene.paper`), 650–725 cm⁻¹ at
0.04 cm⁻¹ (1876 wavenumbers), 8 cm⁻¹ FTIR resolution, Tikhonov regularizer, float32. One
epoch is one pass over all rays, forward and backward:

* voxel grid: one evaluation of the full objective and its gradient (voxel forward map and
  its VJP over all rays, regularizer over all voxels);
* neural field: ``ceil(n_rays / batch_rays)`` stochastic iterations (coarse and fine
  renderings of a ray batch in chunks of ``chunk_rays`` pixels, regularizer on a batch of
  voxel centres, gradient by backpropagation through the networks and the emission kernel's
  VJP);
* neural centres (``--centres``): one evaluation of the full objective and its gradient
  (network at all voxel centres, once for the data and the regularizer; voxel forward map,
  its VJP; the network's VJP).

Compilation runs first (one untimed epoch of each) and is not timed; the epochs are then timed
in turn, ``--repeats`` rounds of one epoch of each (:func:`timing.best_times`), and the best of
each kept, so that a change in the machine's load reaches every representation alike. Times are
wall clock and CPU time of the process (all threads; steadier than wall time on a shared
machine); compare them only as ratios within one run. The breakdown times the stages of the
neural field's first batch one after the other (sampling with the coarse network, fine network,
emission kernel on both sample sets, kernel VJP, networks' backward, regularizer), the second
time they run: the first call took twice as long (1.10 against 0.55 s for the batch at 32 + 32
samples per ray). Peak resident memory is read after the neural field's first epoch, before the
voxel grid's first one. The paper reports 479–493 ms per epoch and 65–66 MB on a GPU for its
neural field (Tricard, Chen & Deng 2026, Table 1). The C allocator is set as the ``invflame``
command sets it (glibc's defaults with ``--default-allocator``; ``benchmarks/allocator.py``).
With ``--torch-device cuda`` the neural field's tensors live on the GPU
(``benchmarks/accelerator.py``), the stages are timed after the GPU finished them, and the
accelerators' peak memory is printed beside the resident one.

    python benchmarks/bench_neural.py [--rays-per-pixel 9] [--batches N] [--centres]
        [--default-allocator] [--torch-device cuda]
"""

import argparse
import itertools
import resource
import time
from functools import partial

import accelerator
import numpy as np
import torch
from allocator import add_argument, apply
from timing import best_times

from invflame.phantoms import synthetic_plume
from invflame.representations.neural import NeuralCentresRepresentation, NeuralFieldRepresentation
from invflame.representations.voxel import VoxelRepresentation
from invflame.scene import Scene

PAPER_MS = "479–493 ms"
PAPER_MB = "65–66 MB"


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, in MB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class Clock:
    """Wall and CPU seconds (s) of code blocks, summed per label."""

    def __init__(self):
        self.seconds = {}

    def __call__(self, label, fn, *args):
        """Run ``fn(*args)`` and add its wall and CPU time to ``label``; return its value."""
        wall, cpu = time.perf_counter(), time.process_time()
        out = fn(*args)
        accelerator.synchronize()
        spent = np.array([time.perf_counter() - wall, time.process_time() - cpu])
        self.seconds[label] = self.seconds.get(label, 0.0) + spent
        return out


def synchronized(fn):
    """``fn`` that returns once the work it queued on torch's device is done."""
    def call():
        fn()
        accelerator.synchronize()
    return call


def voxel_epoch(scene, data, truth):
    """An epoch of the voxel grid: the objective and its gradient over all rays."""
    rep = VoxelRepresentation(scene.grid, scene.operator)
    problem = rep.problem(data, "tikhonov", x0=rep.initial_parameters(truth))
    return synchronized(lambda: problem.evaluate(problem.x0).grad)


def neural_epoch(rep, data, n_batches: int):
    """``n_batches`` stochastic iterations of the neural field (to be scaled to an epoch by
    ``rep.iterations_per_epoch / n_batches``); consecutive iterations throughout, so each call
    trains on other batches."""
    problem = rep.problem(data, "tikhonov", x0=rep.initial_parameters())
    iterations = itertools.count()

    def batches():
        for _ in range(n_batches):
            k = next(iterations)
            problem.value_and_grad(problem.x0, k, np.random.default_rng(k))

    return synchronized(batches)


def neural_stages(rep, data) -> dict:
    """Wall and CPU seconds of the stages of one training batch, run one after the other."""
    renderer, clock = rep.renderer, Clock()
    objective = rep.problem(data, "tikhonov").value_and_grad
    theta = torch.tensor(rep.initial_parameters(), requires_grad=True)
    theta_c, theta_f = rep.split(theta)
    pixels = torch.as_tensor(rep.epoch_batches(0)[0])
    offsets, quantiles = renderer.random_draws(np.random.default_rng(0))
    for pixel_part, ray_part in renderer.chunks(pixels.numel()):
        rays = renderer.sub_rays(pixels[pixel_part])
        t_coarse, coarse, coarse_lengths, t_fine, fine_lengths = clock(
            "sampling (coarse network, importance)", renderer.samples, rays,
            partial(rep.coarse.evaluate, theta_c), offsets[ray_part], quantiles[ray_part])
        points = renderer.points(rays, t_fine)
        fine = clock("fine network", rep.fine.evaluate, theta_f, points)
        fields = [renderer.kernel_fields(coarse, renderer.points(rays, t_coarse)),
                  renderer.kernel_fields(fine, points)]
        leaves = [f.detach().requires_grad_() for f in fields]
        spectra = clock("emission kernel (coarse + fine)", renderer.measure, rays,
                        (leaves[0], coarse_lengths), (leaves[1], fine_lengths))
        target = objective.target[pixels[pixel_part]]
        misfit = sum(torch.sum((s * objective.weights[pixels[pixel_part]] - target) ** 2)
                     for s in spectra)
        cotangents = clock("kernel VJP", torch.autograd.grad, misfit, leaves)
        clock("networks' backward", torch.autograd.backward, fields, cotangents)
    centres = torch.as_tensor(np.random.default_rng(0).choice(
        objective.centre_regularizer.n_centres, rep.batch_centres, replace=False))
    u = partial(rep.fine.evaluate, theta_f, normalized=True)
    clock("regularizer (forward, backward)",
          lambda: objective.centre_regularizer(u, centres).backward())
    return clock.seconds


def centres_epoch(scene, data):
    """An epoch of the neural-centres representation: its objective and gradient over all
    rays."""
    rep = NeuralCentresRepresentation(scene)
    problem = rep.problem(data, "tikhonov", x0=rep.initial_parameters())
    return synchronized(lambda: problem.evaluate(problem.x0).grad)


def seconds(t) -> str:
    return f"{t[0]:7.2f} s wall {t[1]:7.2f} s CPU"


def milliseconds(t) -> str:
    return f"{1e3 * t[0]:7.1f} ms wall {1e3 * t[1]:7.1f} ms CPU"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rays-per-pixel", type=int, default=9, help="sub-rays per pixel")
    parser.add_argument("--n-coarse", type=int, default=64, help="coarse samples per ray")
    parser.add_argument("--n-fine", type=int, default=64, help="importance samples per ray")
    parser.add_argument("--batch-rays", type=int, default=1024, help="pixels per iteration")
    parser.add_argument("--chunk-rays", type=int, default=None,
                        help="pixels per rendering call (default: the renderer's)")
    parser.add_argument("--batch-centres", type=int, default=4096,
                        help="voxel centres per iteration for the regularizer")
    parser.add_argument("--batches", type=int, default=None,
                        help="time only this many batches and scale to an epoch "
                             "(default: the whole epoch)")
    parser.add_argument("--repeats", type=int, default=1,
                        help="rounds of one timed epoch of each representation, best taken")
    parser.add_argument("--centres", action="store_true",
                        help="also time the neural-centres representation")
    add_argument(parser)
    accelerator.add_argument(parser)
    args = parser.parse_args()
    allocator = apply(args.default_allocator)
    devices = accelerator.apply(args.torch_device)

    scene = Scene.paper(rays_per_pixel=args.rays_per_pixel)
    truth = synthetic_plume(scene.grid).values
    data = scene.simulate(truth)
    print(f"scene: {scene.grid.shape} grid, {scene.n_rays} rays x {scene.rays_per_pixel} "
          f"sub-rays, {scene.wavenumber.size} wavenumbers -> {scene.out_wavenumber.size} "
          f"outputs, {scene.dtype}; {torch.get_num_threads()} torch threads; {allocator}; "
          f"{devices}")
    rep = NeuralFieldRepresentation(scene, n_coarse=args.n_coarse, n_fine=args.n_fine,
                                    batch_rays=args.batch_rays, chunk_rays=args.chunk_rays,
                                    batch_centres=args.batch_centres)
    renderer = rep.renderer
    n_batches = rep.iterations_per_epoch
    timed_batches = n_batches if args.batches is None else min(args.batches, n_batches)
    epochs = {"neural field": neural_epoch(rep, data, timed_batches)}
    epochs["neural field"]()  # compiles; the peak memory of a neural field's process
    neural_peak, neural_device_peak = peak_rss_mb(), accelerator.device_peaks()
    neural_stages(rep, data)  # a first call takes up to twice as long: not timed
    stages = neural_stages(rep, data)
    epochs["voxel grid"] = voxel_epoch(scene, data, truth)
    if args.centres:
        epochs["neural centres"] = centres_epoch(scene, data)
    times = best_times(epochs, args.repeats, "wall and cpu")
    neural = times["neural field"] * n_batches / timed_batches
    voxel = times["voxel grid"]
    segments = int(np.count_nonzero(scene.segments.length))
    samples = scene.segments.n_rays * (2 * renderer.n_coarse + renderer.n_fine)
    print(f"voxel grid: {segments / scene.segments.n_rays:.1f} segments per sub-ray")
    print(f"  epoch (objective + gradient, best of {args.repeats} in turn): {seconds(voxel)}")
    print(f"neural field: {rep.n_parameters} weights (coarse + fine), "
          f"{renderer.n_coarse} coarse + {renderer.n_fine} fine samples per sub-ray "
          f"({renderer.n_coarse} + {renderer.n_coarse + renderer.n_fine} kernel segments), "
          f"{renderer.batch_rays} pixels per batch in calls of {renderer.chunk_rays}, "
          f"{rep.batch_centres} centres per batch")
    print(f"  epoch ({n_batches} batches, {timed_batches} timed, best of {args.repeats} in turn): "
          f"{seconds(neural)}   "
          f"[paper, GPU: {PAPER_MS}]")
    print(f"  neural / voxel epoch: {neural[0] / voxel[0]:.2f} wall, "
          f"{neural[1] / voxel[1]:.2f} CPU; kernel segments per epoch "
          f"{samples / segments:.2f}x the voxel map's")
    print(f"  peak resident memory after the first neural epoch: {neural_peak:.0f} MB")
    if neural_device_peak:
        print(f"  peak accelerator memory after the first neural epoch: {neural_device_peak}")
    print(f"  parameter memory: {rep.parameter_bytes(rep.initial_parameters()) / 1e6:.3f} MB"
          f"   [paper, GPU memory: {PAPER_MB}]")
    total = sum(stages.values())
    print(f"  stages of one batch (in sequence, {milliseconds(total)}):")
    for label, t in stages.items():
        print(f"    {label:<40} {milliseconds(t)}   {100 * t[1] / total[1]:4.0f} % CPU")
    if args.centres:
        centres = times["neural centres"]
        print(f"neural centres: epoch (objective + gradient, best of {args.repeats} in turn): "
              f"{seconds(centres)}")
        print(f"  neural centres / voxel epoch: {centres[0] / voxel[0]:.2f} wall, "
              f"{centres[1] / voxel[1]:.2f} CPU")
    print(f"peak resident memory of this process: {peak_rss_mb():.0f} MB")
    if peaks := accelerator.device_peaks():
        print(f"peak accelerator memory of this process: {peaks}")


if __name__ == "__main__":
    main()
