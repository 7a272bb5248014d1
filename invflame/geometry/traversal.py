r"""Ray–voxel traversal (Amanatides & Woo) and the per-ray segment lists it produces.

The traversal follows J. Amanatides and A. Woo, "A fast voxel traversal algorithm for ray
tracing", Eurographics 1987: starting in the voxel where the ray enters the box, keep for
each axis the ray distance ``t_max[a]`` to the next grid plane across that axis and step
into the neighbour across the nearest one. Here every ``t_max`` is recomputed from the
plane position (``(plane - o) / d``) instead of accumulated, so rounding does not drift, and
the rays are processed together, one step at a time (vectorized over rays).

Conventions
-----------
* Directions are normalized, so ray distances ``t`` are lengths in m.
* Segments are listed from the camera outwards; ``length`` of segment ``k`` is the chord
  of the ray in voxel ``voxel[k]``, and the lengths of a ray sum to ``t_far - t_near``.
* Where a ray leaves a voxel through an edge or a corner (two or three planes at the same
  ``t``) it steps across all of them at once; segments of zero length are dropped. Near
  ties in floating point can still leave segments of a few 1e-16 m.
* Rays that start inside the box have ``t_near = 0``. Rays that miss the box (or only touch
  it in a point or behind the origin) have ``count = 0`` and ``t_near = t_far = 0``; see
  :attr:`RaySegments.hit`. A ray lying in a boundary face of the box counts as inside it
  and is assigned the boundary voxels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse

from invflame.geometry.grid import VoxelGrid


def _check_rays(origins, directions) -> tuple[np.ndarray, np.ndarray]:
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    if o.ndim != 2 or o.shape[1] != 3 or d.shape != o.shape:
        raise ValueError(
            f"origins and directions must both have shape (n_rays, 3); got {o.shape} and {d.shape}"
        )
    if not (np.all(np.isfinite(o)) and np.all(np.isfinite(d))):
        raise ValueError("origins and directions must be finite")
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    if np.any(norm == 0):
        raise ValueError(f"directions of rays {np.flatnonzero(norm[:, 0] == 0)} are zero vectors")
    return o, d / norm


def ray_box_intersection(
    grid: VoxelGrid, origins, directions
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Entry and exit distances of rays through the grid's box (slab method).

    Parameters
    ----------
    grid : VoxelGrid
        The box ``[lower, upper]``.
    origins : array_like, shape (n_rays, 3)
        Ray origins in m.
    directions : array_like, shape (n_rays, 3)
        Ray directions (normalized here; any non-zero length).

    Returns
    -------
    t_near, t_far : ndarray, shape (n_rays,)
        Distances in m from the origin to where the ray enters and leaves the box,
        clipped to ``t ≥ 0``; both 0 for rays that miss.
    hit : ndarray of bool, shape (n_rays,)
        ``t_far > t_near``: the ray crosses the box with a positive chord.
    """
    o, d = _check_rays(origins, directions)
    return _slabs(grid, o, d)


def _slabs(grid: VoxelGrid, o: np.ndarray, d: np.ndarray):
    moving = d != 0
    safe = np.where(moving, d, 1.0)
    t0 = np.where(moving, (grid.lower - o) / safe, -np.inf)
    t1 = np.where(moving, (grid.upper - o) / safe, np.inf)
    # a ray parallel to a slab and outside it never enters
    outside = ~moving & ((o < grid.lower) | (o > grid.upper))
    t_near = np.maximum(np.max(np.minimum(t0, t1), axis=1), 0.0)
    t_far = np.min(np.maximum(t0, t1), axis=1)
    hit = (t_far > t_near) & ~np.any(outside, axis=1)
    return np.where(hit, t_near, 0.0), np.where(hit, t_far, 0.0), hit


@dataclass(frozen=True, eq=False)
class RaySegments:
    """Voxels crossed by each ray and the path length in each, in a padded layout.

    Attributes
    ----------
    grid : VoxelGrid
        Grid the rays were traced through.
    origins : ndarray, shape (n_rays, 3)
        Ray origins in m.
    directions : ndarray, shape (n_rays, 3)
        Unit ray directions.
    voxel : ndarray of int64, shape (n_rays, max_segments)
        C-order flat voxel indices, nearest the origin first; padding is 0.
    length : ndarray of float64, shape (n_rays, max_segments)
        Path length in each voxel in m; padding is 0.
    count : ndarray of int64, shape (n_rays,)
        Number of real segments per ray (the rest of the row is padding).
    t_near, t_far : ndarray of float64, shape (n_rays,)
        Ray distances in m where the ray enters and leaves the box (0 and 0 for misses).
    """

    grid: VoxelGrid
    origins: np.ndarray
    directions: np.ndarray
    voxel: np.ndarray
    length: np.ndarray
    count: np.ndarray
    t_near: np.ndarray
    t_far: np.ndarray

    @property
    def n_rays(self) -> int:
        """Number of rays."""
        return self.count.shape[0]

    @property
    def max_segments(self) -> int:
        """Width of the padded arrays (largest ``count``)."""
        return self.voxel.shape[1]

    @property
    def n_segments(self) -> int:
        """Total number of real segments over all rays."""
        return int(self.count.sum())

    @property
    def hit(self) -> np.ndarray:
        """Boolean (n_rays,): the ray crosses the box with a positive chord."""
        return self.t_far > self.t_near

    @property
    def mask(self) -> np.ndarray:
        """Boolean (n_rays, max_segments): real segments (``False`` on padding)."""
        return np.arange(self.max_segments) < self.count[:, None]

    def midpoints(self) -> np.ndarray:
        """Midpoint of each segment in m, shape (n_rays, max_segments, 3); padding repeats
        the exit point ``origin + t_far · direction``."""
        t_end = self.t_near[:, None] + np.cumsum(self.length, axis=1)
        t_mid = t_end - 0.5 * self.length
        return self.origins[:, None, :] + t_mid[..., None] * self.directions[:, None, :]

    def take(self, rays) -> RaySegments:
        """The segments of a subset of rays (integer indices or boolean mask), with the
        padding trimmed to the subset's longest ray."""
        rays = np.arange(self.n_rays)[rays]
        count = self.count[rays]
        width = int(count.max()) if count.size else 0
        return RaySegments(
            self.grid,
            self.origins[rays],
            self.directions[rays],
            self.voxel[rays, :width],
            self.length[rays, :width],
            count,
            self.t_near[rays],
            self.t_far[rays],
        )

    def sorted_by_count(self) -> tuple[RaySegments, np.ndarray]:
        """Rays reordered by increasing segment count (stable), and the permutation used.

        Batches of consecutive rays of the result then have similar counts, so little of
        their padded arrays is padding. ``values_sorted[inverse]`` with
        ``inverse = np.argsort(order)`` restores the original ray order.
        """
        order = np.argsort(self.count, kind="stable")
        return self.take(order), order

    def to_csr(self) -> scipy.sparse.csr_array:
        """Path-length matrix ``A`` (n_rays, n_voxels) in m: ``A[r, j]`` is the length of
        ray ``r`` in voxel ``j``; ``A @ kappa.ravel()`` is the optical depth of each ray."""
        mask = self.mask
        indptr = np.concatenate([[0], np.cumsum(self.count)])
        return scipy.sparse.csr_array(
            (self.length[mask], self.voxel[mask], indptr),
            shape=(self.n_rays, self.grid.n_voxels),
        )


def traverse(grid: VoxelGrid, origins, directions) -> RaySegments:
    """Trace rays through a voxel grid (Amanatides–Woo), vectorized over rays.

    Parameters
    ----------
    grid : VoxelGrid
        Grid to traverse.
    origins : array_like, shape (n_rays, 3)
        Ray origins in m (inside or outside the box).
    directions : array_like, shape (n_rays, 3)
        Ray directions; normalized here, components may be exactly 0.

    Returns
    -------
    RaySegments
        Padded per-ray voxel indices and lengths (m), see the module notes for the
        conventions on misses, ties and zero-length segments.
    """
    o, d = _check_rays(origins, directions)
    n_rays = o.shape[0]
    t_near, t_far, hit = _slabs(grid, o, d)
    shape = np.asarray(grid.shape)
    h = grid.spacing
    step = np.sign(d).astype(np.int64)
    moving = step != 0
    safe = np.where(moving, d, 1.0)

    # starting voxel; on a grid plane, pick the voxel the ray moves into
    f = (o + t_near[:, None] * d - grid.lower) / h
    idx = np.floor(f).astype(np.int64)
    idx -= (f == idx) & (step < 0)
    idx = np.clip(idx, 0, shape - 1)

    max_steps = int(shape.sum()) + 3
    voxel = np.zeros((n_rays, max_steps), dtype=np.int64)
    length = np.zeros((n_rays, max_steps), dtype=np.float64)
    count = np.zeros(n_rays, dtype=np.int64)

    active = np.flatnonzero(hit)
    o_a, idx_a, step_a, moving_a, safe_a = (a[active] for a in (o, idx, step, moving, safe))
    t_cur, t_end_a = t_near[active], t_far[active]
    strides = np.array([shape[1] * shape[2], shape[2], 1])
    for _ in range(max_steps):
        if active.size == 0:
            break
        plane = grid.lower + h * (idx_a + (step_a > 0))
        t_max = np.where(moving_a, (plane - o_a) / safe_a, np.inf)
        t_next = np.min(t_max, axis=1)
        t_exit = np.clip(t_next, t_cur, t_end_a)
        seg = t_exit - t_cur
        real = seg > 0
        rows, cols = active[real], count[active[real]]
        voxel[rows, cols] = idx_a[real] @ strides
        length[rows, cols] = seg[real]
        count[rows] += 1
        t_cur = t_exit
        idx_a = idx_a + step_a * (t_max == t_next[:, None])
        keep = (t_cur < t_end_a) & np.all((idx_a >= 0) & (idx_a < shape), axis=1)
        active, o_a, idx_a, step_a, moving_a, safe_a, t_cur, t_end_a = (
            a[keep] for a in (active, o_a, idx_a, step_a, moving_a, safe_a, t_cur, t_end_a)
        )
    if active.size:
        raise RuntimeError(f"traversal did not finish within {max_steps} steps")

    width = int(count.max()) if n_rays else 0
    return RaySegments(grid, o, d, voxel[:, :width], length[:, :width], count, t_near, t_far)
