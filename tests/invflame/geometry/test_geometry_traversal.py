"""Amanatides–Woo traversal against chords, brute-force sampling and special rays."""

import numpy as np
import pytest

from invflame.geometry import VoxelGrid, paper_rig, ray_box_intersection, traverse

# an off-origin box with unequal cells on each axis
GRID = VoxelGrid((-0.3, 0.2, -1.0), (0.7, 0.8, -0.2), (7, 5, 6))


def random_rays(rng, n, inside_fraction=0.3):
    """Rays aimed near the box from outside, and some starting inside it."""
    n_in = int(n * inside_fraction)
    centre, ext = GRID.centre, GRID.extent
    outside = centre + ext * rng.normal(size=(n - n_in, 3)) * 1.5
    targets = centre + ext * (rng.random((n - n_in, 3)) - 0.5) * 1.2
    inside = GRID.lower + ext * rng.random((n_in, 3))
    origins = np.concatenate([outside, inside])
    directions = np.concatenate([targets - outside, rng.normal(size=(n_in, 3))])
    return origins, directions


def brute_force_lengths(grid, origin, direction, t_near, t_far, n_samples=40000):
    """Per-voxel length by midpoint sampling of the chord."""
    dt = (t_far - t_near) / n_samples
    t = t_near + dt * (np.arange(n_samples) + 0.5)
    p = origin + t[:, None] * direction
    idx = np.clip(
        np.floor((p - grid.lower) / grid.spacing).astype(int), 0, np.array(grid.shape) - 1
    )
    flat = np.ravel_multi_index(idx.T, grid.shape)
    return np.bincount(flat, minlength=grid.n_voxels) * dt, dt


def per_voxel(seg, r):
    n = seg.count[r]
    return np.bincount(seg.voxel[r, :n], weights=seg.length[r, :n], minlength=GRID.n_voxels)


def test_lengths_sum_to_chord_and_padding():
    rng = np.random.default_rng(0)
    o, d = random_rays(rng, 500)
    seg = traverse(GRID, o, d)
    assert seg.hit.sum() > 300
    np.testing.assert_allclose(seg.length.sum(axis=1), seg.t_far - seg.t_near, rtol=0, atol=1e-9)
    assert np.all(seg.length[seg.mask] > 0)
    assert np.all(seg.length[~seg.mask] == 0) and np.all(seg.voxel[~seg.mask] == 0)
    assert seg.voxel.dtype == np.int64 and seg.length.dtype == np.float64
    assert seg.max_segments == seg.count.max() <= sum(GRID.shape)
    np.testing.assert_allclose(np.linalg.norm(seg.directions, axis=1), 1.0)
    # the chord agrees with an independent entry/exit computation
    t_near, t_far, hit = ray_box_intersection(GRID, o, d)
    np.testing.assert_array_equal(hit, seg.hit)
    np.testing.assert_allclose(t_far - t_near, seg.t_far - seg.t_near)


def test_segments_are_face_adjacent_and_ordered_outwards():
    rng = np.random.default_rng(1)
    o, d = random_rays(rng, 200)
    seg = traverse(GRID, o, d)
    for r in np.flatnonzero(seg.count > 1):
        idx = np.array(np.unravel_index(seg.voxel[r, : seg.count[r]], GRID.shape)).T
        jumps = np.abs(np.diff(idx, axis=0))
        assert np.all(jumps.max(axis=1) == 1)  # each step moves to a neighbour
        # moving along the ray: the index moves with the direction's sign
        assert np.all(np.diff(idx, axis=0) * np.sign(seg.directions[r]) >= 0)
    # midpoints lie in the voxels they are labelled with
    mid = seg.midpoints()[seg.mask]
    real = seg.length[seg.mask] > 1e-9
    lab = np.array(np.unravel_index(seg.voxel[seg.mask], GRID.shape)).T
    lo = GRID.lower + lab * GRID.spacing
    assert np.all((mid[real] >= lo[real] - 1e-12) & (mid[real] <= lo[real] + GRID.spacing + 1e-12))


def test_agrees_with_brute_force_sampling():
    rng = np.random.default_rng(2)
    o, d = random_rays(rng, 40)
    seg = traverse(GRID, o, d)
    assert seg.hit.sum() >= 25
    for r in np.flatnonzero(seg.hit):
        ref, dt = brute_force_lengths(
            GRID, seg.origins[r], seg.directions[r], seg.t_near[r], seg.t_far[r]
        )
        got = per_voxel(seg, r)
        # each voxel boundary shifts at most one sample of width dt
        np.testing.assert_allclose(got, ref, rtol=0, atol=2 * dt + 1e-12)
        assert set(np.flatnonzero(ref > dt)) <= set(np.flatnonzero(got > 0))


def test_rays_that_miss():
    o = np.array(
        [
            [-1.0, 0.5, -0.5],  # control: parallel to x through the box
            [-1.0, 0.9, -0.5],  # parallel to x, above the box
            [2.0, 0.5, -0.5],  # pointing away from the box
            [0.2, 0.5, -0.6],  # control: starts inside the box
            [-1.0, 0.2, -1.0],  # lies on the box's edge: counted as inside
        ]
    )
    d = np.array([[1, 0, 0], [1, 0, 0], [1, 0, 0], [0, 0, 1], [1, 0, 0]], dtype=float)
    seg = traverse(GRID, o, d)
    np.testing.assert_array_equal(seg.hit, [True, False, False, True, True])
    np.testing.assert_array_equal(seg.count[[1, 2]], 0)
    np.testing.assert_array_equal(seg.t_near[[1, 2]], 0)
    np.testing.assert_array_equal(seg.t_far[[1, 2]], 0)
    assert np.all(seg.length[[1, 2]] == 0)


def test_rays_touching_only_a_corner_or_an_edge_miss():
    grid = VoxelGrid.cube(4)
    o = np.array([[-1.5, 0.5, 0.5], [-1.5, 0.5, 0.0]])
    d = np.array([[1.0, -1.0, -1.0], [1.0, -1.0, 0.0]])
    seg = traverse(grid, o, d)
    np.testing.assert_array_equal(seg.count, [0, 0])
    np.testing.assert_array_equal(seg.hit, [False, False])


def test_box_behind_the_origin_is_missed():
    seg = traverse(GRID, [[0.2, 0.5, 1.0]], [[0.0, 0.0, 1.0]])
    assert seg.count[0] == 0 and not seg.hit[0]


def test_axis_aligned_rays_through_cell_centres():
    x, y, z = GRID.axes()
    h = GRID.spacing
    o = np.array([[-5.0, y[2], z[3]], [x[4], 9.0, z[1]], [x[0], y[4], 3.0]])
    d = np.array([[1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, -0.5]])
    seg = traverse(GRID, o, d)
    np.testing.assert_array_equal(seg.count, GRID.shape)
    np.testing.assert_array_equal(seg.voxel[0, :7], GRID.flat_index(np.arange(7), 2, 3))
    np.testing.assert_array_equal(seg.voxel[1, :5], GRID.flat_index(4, np.arange(4, -1, -1), 1))
    np.testing.assert_array_equal(seg.voxel[2, :6], GRID.flat_index(0, 4, np.arange(5, -1, -1)))
    for r in range(3):
        np.testing.assert_allclose(seg.length[r, : seg.count[r]], h[r])
    np.testing.assert_allclose(seg.t_near, [4.7, 9.0 - 0.8, 3.2])


def test_rays_along_grid_planes_and_edges():
    h = GRID.spacing
    plane_y = GRID.lower[1] + 2 * h[1]
    plane_z = GRID.lower[2] + 3 * h[2]
    x_mid = GRID.axes()[0][5]
    o = np.array(
        [
            [-1.0, plane_y, plane_z],  # along x on an interior edge
            [x_mid, plane_y, -2.0],  # along z in the plane y = plane_y
            [-1.0, GRID.upper[1], GRID.lower[2]],  # along x on the box's outer edge
        ]
    )
    d = np.array([[1.0, 0, 0], [0, 0, 1.0], [1.0, 0, 0]])
    seg = traverse(GRID, o, d)
    np.testing.assert_array_equal(seg.count, [7, 6, 7])
    # a ray in a grid plane takes the voxels on the plane's upper side
    np.testing.assert_array_equal(seg.voxel[0, :7], GRID.flat_index(np.arange(7), 2, 3))
    np.testing.assert_array_equal(seg.voxel[1, :6], GRID.flat_index(5, 2, np.arange(6)))
    # on the outer boundary it takes the boundary voxels
    np.testing.assert_array_equal(seg.voxel[2, :7], GRID.flat_index(np.arange(7), 4, 0))
    np.testing.assert_allclose(seg.length.sum(axis=1), GRID.extent[[0, 2, 0]])


def test_diagonal_through_voxel_corners_steps_across_all_planes():
    grid = VoxelGrid.cube(9, size=0.9)
    n = grid.shape[0]
    o = np.array(
        [grid.lower - 0.1, grid.upper + 0.05, [grid.lower[0] - 0.1, -0.43, grid.lower[2] - 0.1]]
    )
    d = np.array([[1.0, 1.0, 1.0], [-1.0, -1.0, -1.0], [1.0, 0.0, 1.0]])
    seg = traverse(grid, o, d)
    np.testing.assert_array_equal(seg.count, [n, n, n])  # no zero-length corner segments
    i = np.arange(n)
    np.testing.assert_array_equal(seg.voxel[0], grid.flat_index(i, i, i))
    np.testing.assert_array_equal(seg.voxel[1], grid.flat_index(i[::-1], i[::-1], i[::-1]))
    iy = int(np.floor((-0.43 - grid.lower[1]) / grid.spacing[1]))
    np.testing.assert_array_equal(seg.voxel[2], grid.flat_index(i, iy, i))
    np.testing.assert_allclose(seg.length[0], np.sqrt(3) * 0.1)
    np.testing.assert_allclose(seg.length[2], np.sqrt(2) * 0.1)


def test_rays_starting_inside():
    start = GRID.centres()[3, 1, 2]
    seg = traverse(GRID, [start, start], [[1.0, 0.0, 0.0], [-0.3, 0.4, 0.2]])
    assert np.all(seg.t_near == 0)
    np.testing.assert_array_equal(seg.voxel[:, 0], GRID.flat_index(3, 1, 2))
    np.testing.assert_allclose(seg.length[0, 0], GRID.spacing[0] / 2)
    np.testing.assert_allclose(seg.t_far[0], GRID.upper[0] - start[0])
    assert seg.count[0] == 4
    # starting exactly on a grid plane, moving down across it
    on_plane = np.array([GRID.lower[0] + 2 * GRID.spacing[0], 0.5, -0.5])
    seg = traverse(GRID, [on_plane], [[-1.0, 0.0, 0.0]])
    assert seg.count[0] == 2
    ix = np.unravel_index(seg.voxel[0], GRID.shape)[0]
    np.testing.assert_array_equal(ix, [1, 0])


def test_take_sort_and_csr():
    rng = np.random.default_rng(3)
    o, d = random_rays(rng, 120)
    seg = traverse(GRID, o, d)
    srt, order = seg.sorted_by_count()
    assert np.all(np.diff(srt.count) >= 0)
    np.testing.assert_array_equal(srt.count, seg.count[order])
    inverse = np.argsort(order)
    np.testing.assert_array_equal(srt.t_far[inverse], seg.t_far)
    short = seg.take(order[:40])
    assert short.max_segments == short.count.max() < seg.max_segments
    np.testing.assert_array_equal(short.voxel, seg.voxel[order[:40], : short.max_segments])
    a = seg.to_csr()
    assert a.shape == (120, GRID.n_voxels)
    np.testing.assert_allclose(a @ np.ones(GRID.n_voxels), seg.t_far - seg.t_near, atol=1e-12)
    kappa = rng.random(GRID.n_voxels)
    np.testing.assert_allclose(a @ kappa, (seg.length * kappa[seg.voxel]).sum(axis=1))


@pytest.mark.parametrize(
    "origins, directions, match",
    [
        (np.zeros((2, 3)), np.zeros((3, 3)), "shape"),
        (np.zeros((2, 3)), np.array([[1.0, 0, 0], [0, 0, 0]]), "zero"),
        (np.zeros((1, 3)), np.array([[np.nan, 0, 0]]), "finite"),
    ],
)
def test_bad_rays(origins, directions, match):
    with pytest.raises(ValueError, match=match):
        traverse(GRID, origins, directions)


def test_paper_rig_sees_the_box():
    grid = VoxelGrid.poolfire(60)
    rig = paper_rig(grid)
    seg = traverse(grid, *rig.rays())
    assert seg.hit.all()  # every pixel looks through the box
    crossed = np.zeros(grid.n_voxels, dtype=bool)
    crossed[seg.voxel[seg.mask]] = True
    fraction = crossed.mean()
    # 4 x 32 x 32 rays sample the 60^3 grid sparsely: about 55 % of voxels are crossed
    assert 0.5 < fraction < 0.6
    # every voxel centre projects inside every camera's image
    centres = grid.centres().reshape(-1, 3)
    for cam in rig.cameras:
        u, v, _ = cam.project(centres)
        assert np.all((u > 0) & (u < 32) & (v > 0) & (v < 32))
