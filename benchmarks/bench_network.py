"""The field network at the voxel centres: its products by pass size, and the stacked Jacobian
of Gauss–Newton and PDHG on the network-at-centres problem.

Paper configuration: 60³ grid (216 000 voxel centres), the default network (10 frequencies,
4 hidden layers of 64 units), float32. For each number of points per pass of the MLP
(:data:`invflame.representations.neural.network.POINTS_PER_PASS`; "all" is one pass), wall
seconds, best of ``--repeats`` after one untimed call, of

* forward: the fields at all centres, no gradient;
* JVP: the forward-mode product with a weight tangent (:func:`torch.func.jvp`);
* VJP: the pullback of a field cotangent from a kept linearization;
* linearize: the forward with the graph kept for the pullback.

With ``--stack`` it then builds :meth:`invflame.scene.Scene.paper` (one ray per pixel) and
times the stacked Jacobian of the Tikhonov network-at-centres problem
(:func:`solvers.gauss_newton.stacked_jacobian`: the data map's and the regularizer's
Jacobians, both ending in the network's Jacobian) applied as a stack, which applies the
network's Jacobian once per product, and block by block, which applies it once per block.

    python benchmarks/bench_network.py [--repeats 3] [--stack] [--default-allocator]
"""

import argparse

import numpy as np
import torch
from allocator import add_argument, apply
from timing import best_time

from invflame.geometry import VoxelGrid
from invflame.representations.neural import network as network_module
from invflame.representations.neural.network import FieldNetwork, centre_points

PASSES = (2**11, 2**12, 2**13, 2**14, 2**16, None)


def products(net: FieldNetwork, points: torch.Tensor, repeats: int) -> dict[str, float]:
    """Best wall seconds of the network's forward, JVP, VJP and linearization at ``points``."""
    theta = torch.as_tensor(net.parameter_vector())
    tangent = torch.randn_like(theta, generator=torch.Generator().manual_seed(0))

    def fields(t):
        return net.evaluate(t, points)

    value, pull = torch.func.vjp(fields, theta)
    cotangent = torch.randn_like(value)

    def forward():
        with torch.no_grad():
            return fields(theta)

    return {"forward": best_time(forward, repeats),
            "JVP": best_time(lambda: torch.func.jvp(fields, (theta,), (tangent,)), repeats),
            "VJP": best_time(lambda: pull(cotangent), repeats),
            "linearize": best_time(lambda: torch.func.vjp(fields, theta), repeats)}


def stack_products(repeats: int) -> None:
    """Print the Gauss–Newton stack's products on the network-at-centres problem, as a stack
    and block by block."""
    from invflame.phantoms import synthetic_plume
    from invflame.representations.neural import NeuralCentresRepresentation
    from invflame.scene import Scene
    from solvers.gauss_newton import stacked_jacobian

    scene = Scene.paper(rays_per_pixel=1)
    rep = NeuralCentresRepresentation(scene)
    data = scene.simulate(synthetic_plume(scene.grid).values)
    problem = rep.problem(data, "tikhonov", lam=1e-3, x0=rep.initial_parameters())
    stack, _ = stacked_jacobian(problem, problem.evaluate(problem.x0))
    blocks = stack.combination.parts
    rng = np.random.default_rng(0)
    v = rng.standard_normal(stack.dims).astype(stack.dtype)
    y = rng.standard_normal(stack.dimsd).astype(stack.dtype)
    ys = stack.combination.split(y)
    rows = {
        "product, as a stack": best_time(lambda: stack @ v, repeats),
        "product, block by block": best_time(lambda: [b @ v for b in blocks], repeats),
        "adjoint, as a stack": best_time(lambda: stack.adjoint(y), repeats),
        "adjoint, block by block": best_time(
            lambda: sum(b.adjoint(w) for b, w in zip(blocks, ys, strict=True)), repeats),
    }
    print(f"Gauss–Newton stacked Jacobian, network at the centres, Tikhonov "
          f"({scene.grid.shape} grid, {scene.n_rays} rays, {len(blocks)} blocks), "
          f"wall s, best of {repeats}:")
    for label, seconds in rows.items():
        print(f"  {label:<26} {seconds:7.3f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="timed calls, best taken")
    parser.add_argument("--stack", action="store_true",
                        help="also time the Gauss–Newton stacked Jacobian at the paper's size")
    add_argument(parser)
    args = parser.parse_args()
    allocator = apply(args.default_allocator)

    grid = VoxelGrid.poolfire(60)
    net = FieldNetwork(grid)
    points = centre_points(grid)
    n_points = points.numel() // 3
    print(f"network at the {n_points} centres of a {grid.shape} grid, {net.n_parameters} "
          f"weights, float32, {torch.get_num_threads()} torch threads, {allocator}; wall s, "
          f"best of {args.repeats}")
    print(f"  {'points per pass':>16} {'forward':>8} {'JVP':>8} {'VJP':>8} {'linearize':>10}")
    default = network_module.POINTS_PER_PASS
    for size in PASSES:
        network_module.POINTS_PER_PASS = n_points if size is None else size
        t = products(net, points, args.repeats)
        label = "all" if size is None else f"{size}" + (" (default)" if size == default else "")
        print(f"  {label:>16} {t['forward']:8.3f} {t['JVP']:8.3f} {t['VJP']:8.3f} "
              f"{t['linearize']:10.3f}")
    network_module.POINTS_PER_PASS = default
    if args.stack:
        stack_products(args.repeats)


if __name__ == "__main__":
    main()
