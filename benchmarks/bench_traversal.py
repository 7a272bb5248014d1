"""Time the Amanatides–Woo traversal of the paper's camera rig through the pool-fire grid.

Run: ``python benchmarks/bench_traversal.py [--pixels 32] [--cells 60] [--repeats 5]``.
Prints the best wall time over the repeats, the segment statistics and the fraction of
voxels crossed by at least one ray.
"""

import argparse
import time

import numpy as np

from invflame.geometry import VoxelGrid, paper_rig, traverse


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pixels", type=int, default=32, help="pixels per image side")
    parser.add_argument("--cells", type=int, default=60, help="voxels per grid axis")
    parser.add_argument("--repeats", type=int, default=5, help="timed repetitions (best kept)")
    args = parser.parse_args()

    grid = VoxelGrid.poolfire(args.cells)
    rig = paper_rig(grid, n_pixels=args.pixels)
    origins, directions = rig.rays()
    times = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        seg = traverse(grid, origins, directions)
        times.append(time.perf_counter() - start)
    crossed = np.zeros(grid.n_voxels, dtype=bool)
    crossed[seg.voxel[seg.mask]] = True
    sensor = rig.cameras[0].sensor_size[0]
    print(f"grid {grid.shape}, rig {rig.n_cameras} x {args.pixels}^2 = {seg.n_rays} rays")
    print(f"sensor {sensor:.4f} m square, fov {rig.cameras[0].fov[0]:.2f} deg")
    print(f"traversal: best {1e3 * min(times):.1f} ms, median {1e3 * np.median(times):.1f} ms")
    print(
        f"segments: total {seg.n_segments}, per ray max {seg.count.max()}, "
        f"mean {seg.count.mean():.2f}, min {seg.count.min()}; rays hitting {seg.hit.mean():.1%}"
    )
    print(f"voxels crossed by at least one ray: {crossed.mean():.1%}")


if __name__ == "__main__":
    main()
