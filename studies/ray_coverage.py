"""Print the ray coverage of the study's rig for 1, 4, 9, 16 sub-rays per pixel.

Usage: python studies/ray_coverage.py

For the paper's rig (60³ voxels, four cameras of 32² px) and the quick preset's (30³, 16² px):
the fraction of all voxels, of the voxels inside every camera's field of view, and of the pool
fire's voxels above 500 K that at least one ray crosses. A pixel's footprint at the flame is
about 2.9 voxels wide in both, so one ray through each pixel centre leaves voxels in between
unseen.
"""

from invflame.geometry import VoxelGrid, paper_rig, ray_coverage, traverse
from invflame.phantoms import poolfire

if __name__ == "__main__":
    print("| grid | pixels | rays/pixel | voxels | common view | T > 500 K |")
    print("|---|---|---:|---:|---:|---:|")
    for n, pixels in ((60, 32), (30, 16)):
        grid = VoxelGrid.poolfire(n)
        rig = paper_rig(grid, n_pixels=pixels)
        temperature = poolfire(grid).values[0]
        for k in (1, 4, 9, 16):
            c = ray_coverage(traverse(grid, *rig.rays(k)), rig, temperature)
            print(f"| {n}³ | 4 × {pixels}² | {k} | {c['voxels']:.2%} | {c['common_view']:.2%} |"
                  f" {c['hot']:.2%} |", flush=True)
