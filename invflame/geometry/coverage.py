"""Ray coverage: which voxels the measurement rays cross at all.

A voxel crossed by no ray is not seen by the data; only the regularizer or the start decide
its value there. With one ray per pixel through the pixel centre and pixel footprints at the
flame larger than a voxel, many voxels fall between rays: sample each pixel by several
sub-rays (``rays_per_pixel``) until the coverage is complete.
"""

from __future__ import annotations

import numpy as np

from invflame.geometry.grid import VoxelGrid
from invflame.geometry.rig import CameraRig
from invflame.geometry.traversal import RaySegments

MIN_CHORD = 1e-9
"""Shortest path length in m that counts as crossing a voxel (drops round-off slivers)."""


def crossed_voxels(segments: RaySegments) -> np.ndarray:
    """Boolean ``(nx, ny, nz)``: the voxel holds a segment of at least one ray."""
    seen = np.zeros(segments.grid.n_voxels, dtype=bool)
    seen[segments.voxel[segments.mask & (segments.length > MIN_CHORD)]] = True
    return seen.reshape(segments.grid.shape)


def common_view(rig: CameraRig, grid: VoxelGrid) -> np.ndarray:
    """Boolean ``(nx, ny, nz)``: the voxel centre lies in front of every camera and projects
    inside every camera's image."""
    centres = grid.centres().reshape(-1, 3)
    inside = np.ones(centres.shape[0], dtype=bool)
    for camera in rig.cameras:
        u, v, depth = camera.project(centres)
        nu, nv = camera.n_pixels
        with np.errstate(invalid="ignore"):
            inside &= (depth > 0) & (u >= 0) & (u <= nu) & (v >= 0) & (v <= nv)
    return inside.reshape(grid.shape)


def ray_coverage(segments: RaySegments, rig: CameraRig, temperature=None,
                 threshold: float = 500.0) -> dict[str, float | None]:
    """Fractions of voxels crossed by at least one ray.

    Parameters
    ----------
    segments : RaySegments
        The traced rays (all sub-rays of all pixels).
    rig : CameraRig
        The cameras, for the common field of view.
    temperature : array_like, shape (nx, ny, nz), optional
        A temperature field in K (e.g. the ground truth) to report the coverage of its hot
        voxels.
    threshold : float, optional
        Temperature in K above which a voxel is hot (default 500).

    Returns
    -------
    dict
        ``"voxels"``: fraction of all voxels crossed; ``"common_view"``: of the voxels inside
        every camera's field of view; ``"hot"``: of the voxels above ``threshold`` (None
        without ``temperature`` or when no voxel is that hot). Values in [0, 1].
    """
    grid = segments.grid
    seen = crossed_voxels(segments)
    view = common_view(rig, grid)
    out = {"voxels": float(seen.mean()),
           "common_view": float(seen[view].mean()) if view.any() else None,
           "hot": None}
    if temperature is not None:
        temperature = np.asarray(temperature)
        if temperature.shape != grid.shape:
            raise ValueError(f"temperature must have the grid's shape {grid.shape}, got "
                             f"{temperature.shape}")
        hot = temperature > threshold
        out["hot"] = float(seen[hot].mean()) if hot.any() else None
    return out
