"""Pinhole cameras, image orientation, and the camera rig."""

import numpy as np
import pytest

from invflame.errors import GeometryError
from invflame.geometry import (
    CameraRig,
    PinholeCamera,
    VoxelGrid,
    framing_sensor_size,
    paper_rig,
    ring_rig,
)


@pytest.fixture
def camera():
    # looks along -x at the origin, y up, 5 columns x 3 rows
    return PinholeCamera((2.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0, 1, 0), 0.5, (0.4, 0.3), (5, 3))


def test_rays_are_unit_and_start_at_pinhole(camera):
    o, d = camera.rays()
    assert o.shape == d.shape == (15, 3)
    np.testing.assert_allclose(o, np.tile([2.0, 0.0, 0.0], (15, 1)))
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    # centre pixel (odd counts) looks along the optical axis
    np.testing.assert_allclose(d[1 * 5 + 2], [-1.0, 0.0, 0.0], atol=1e-15)


def test_camera_frame(camera):
    np.testing.assert_allclose(camera.forward, [-1, 0, 0])
    np.testing.assert_allclose(camera.image_up, [0, 1, 0])
    # right = forward x up: looking along -x with y up, +z is to the left, so right is -z
    np.testing.assert_allclose(camera.right, [0, 0, -1])
    assert camera.image_shape == (3, 5) and camera.n_rays == 15


def test_pixel_order_row_major_top_row_first(camera):
    _, d = camera.rays()
    img_up = (d @ camera.image_up).reshape(camera.image_shape)
    img_right = (d @ camera.right).reshape(camera.image_shape)
    assert np.all(np.diff(img_up, axis=0) < 0)  # rows go down the image
    assert np.all(np.diff(img_right, axis=1) > 0)  # columns go right
    np.testing.assert_allclose(img_up[:, 0], img_up[:, 4])


def test_orientation_point_above_centre_projects_to_upper_half():
    grid = VoxelGrid.poolfire(10)
    for cam in paper_rig(grid).cameras:
        nu, nv = cam.n_pixels
        u, v, depth = cam.project(grid.centre + [0.0, 0.3, 0.0])
        assert depth > 0
        assert v < nv / 2 - 1  # upper half: small row index
        assert abs(u - nu / 2) < 1e-9
        u0, v0, _ = cam.project(grid.centre)
        np.testing.assert_allclose([u0, v0], [nu / 2, nv / 2], atol=1e-9)
        # and a point to the camera's right lands in the right half
        u1, _, _ = cam.project(grid.centre + 0.3 * cam.right)
        assert u1 > nu / 2 + 1


def test_project_inverts_rays(camera):
    o, d = camera.rays()
    u, v, depth = camera.project(o + 1.7 * d)
    uu, vv = np.meshgrid(np.arange(5) + 0.5, np.arange(3) + 0.5)
    np.testing.assert_allclose(u, uu.ravel(), atol=1e-12)
    np.testing.assert_allclose(v, vv.ravel(), atol=1e-12)
    assert np.all(depth > 0)
    u, v, depth = camera.project([5.0, 0.0, 0.0])  # behind the camera
    assert np.isnan(u) and np.isnan(v) and depth < 0


def test_from_fov_square_pixels():
    cam = PinholeCamera.from_fov((0, 0, 5), (0, 0, 0), (0, 1, 0), 60.0, (8, 4), focal_length=0.1)
    w, h = cam.sensor_size
    np.testing.assert_allclose(w, 2 * 0.1 * np.tan(np.radians(30)))
    np.testing.assert_allclose(h, w / 2)
    np.testing.assert_allclose(cam.fov[0], 60.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(up=(1, 0, 0)), "parallel"),
        (dict(look_at=(2, 0, 0)), "differ"),
        (dict(focal_length=0.0), "focal_length"),
        (dict(sensor_size=(0.1, -1)), "sensor_size"),
        (dict(n_pixels=(4, 0)), "n_pixels"),
        (dict(up=(0, 0, 0)), "non-zero"),
    ],
)
def test_camera_validation(kwargs, match):
    args = dict(
        position=(2, 0, 0),
        look_at=(0, 0, 0),
        up=(0, 1, 0),
        focal_length=0.5,
        sensor_size=(0.4, 0.3),
        n_pixels=(5, 3),
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        PinholeCamera(**args)


def test_framing_sensor_size_nearest_face():
    grid = VoxelGrid.poolfire(4)
    pos = grid.centre + [1.5, 0, 0]
    w, h = framing_sensor_size(pos, grid.centre, (0, 1, 0), 0.59, grid.corners(), margin=0.0)
    np.testing.assert_allclose([w, h], [0.59, 0.59])
    with pytest.raises(ValueError, match="in front"):
        framing_sensor_size(pos, grid.centre, (0, 1, 0), 0.59, [[3.0, 0.5, 0.0]])


def test_paper_rig_layout():
    grid = VoxelGrid.poolfire(60)
    rig = paper_rig(grid)
    assert rig.n_cameras == 4 and rig.n_rays == 4 * 32 * 32
    positions = np.array([c.position for c in rig.cameras])
    np.testing.assert_allclose(
        positions - grid.centre,
        [[1.5, 0, 0], [-1.5, 0, 0], [0, 0, 1.5], [0, 0, -1.5]],
    )
    for cam in rig.cameras:
        assert cam.focal_length == 0.59 and cam.image_shape == (32, 32)
        np.testing.assert_allclose(cam.sensor_size, (0.6018, 0.6018))
        np.testing.assert_allclose(cam.image_up, [0, 1, 0])
        # the whole box is in view and fills it up to the 2 % margin
        u, v, _ = cam.project(grid.corners())
        assert u.min() > 0 and v.min() > 0 and u.max() < 32 and v.max() < 32
        np.testing.assert_allclose([u.min(), u.max()], [16 - 16 / 1.02, 16 + 16 / 1.02])


def test_ring_rig_places_cameras_at_the_azimuths_framing_the_box():
    grid = VoxelGrid.poolfire(10)
    rig = ring_rig(grid, (0, 45, 90, 135), n_pixels=8)
    offsets = np.array([c.position for c in rig.cameras]) - grid.centre
    half = 1.5 / np.sqrt(2)
    np.testing.assert_allclose(offsets, [[1.5, 0, 0], [half, 0, half], [0, 0, 1.5],
                                         [-half, 0, half]], atol=1e-12)
    sizes = {c.sensor_size for c in rig.cameras}
    assert len(sizes) == 1  # one sensor for all
    # the diagonal cameras see the box's nearest vertical edge: a wider sensor than the paper's
    assert sizes.pop()[0] > paper_rig(grid).cameras[0].sensor_size[0]
    for cam in rig.cameras:
        u, v, _ = cam.project(grid.corners())
        assert u.min() >= 0 and v.min() >= 0 and u.max() <= 8 and v.max() <= 8
    with pytest.raises(ValueError, match="azimuths must be a non-empty"):
        ring_rig(grid, [])
    with pytest.raises(GeometryError, match="inside the grid"):
        ring_rig(grid, (0, 90), distance=0.3)


def test_rig_rays_and_images():
    grid = VoxelGrid.poolfire(8)
    rig = paper_rig(grid, n_pixels=4)
    o, d = rig.rays()
    assert o.shape == d.shape == (64, 3)
    np.testing.assert_array_equal(rig.ray_offsets, [0, 16, 32, 48, 64])
    np.testing.assert_allclose(d[16:32], rig.cameras[1].rays()[1])
    values = np.arange(64 * 2).reshape(64, 2)
    images = rig.to_images(values)
    assert images.shape == (4, 4, 4, 2)
    np.testing.assert_array_equal(images[2, 1, 3], values[32 + 1 * 4 + 3])
    with pytest.raises(ValueError, match="leading axis"):
        rig.to_images(values[:10])


def test_rig_with_mixed_image_shapes():
    a = PinholeCamera((2, 0, 0), (0, 0, 0), (0, 1, 0), 0.5, (0.4, 0.3), (5, 3))
    b = PinholeCamera((0, 0, 2), (0, 0, 0), (0, 1, 0), 0.5, (0.4, 0.4), (2, 2))
    rig = CameraRig((a, b))
    assert rig.n_rays == 19 and rig.image_shapes == ((3, 5), (2, 2))
    parts = rig.split_images(np.arange(19))
    assert [p.shape for p in parts] == [(3, 5), (2, 2)]
    np.testing.assert_array_equal(parts[1].ravel(), [15, 16, 17, 18])
    with pytest.raises(ValueError, match="split_images"):
        rig.to_images(np.arange(19))
    with pytest.raises(ValueError, match="PinholeCamera"):
        CameraRig(())


def test_sub_rays_tile_each_pixel_and_are_pixel_major():
    camera = PinholeCamera((0.0, 0.0, -2.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, (0.4, 0.2),
                           (4, 2))
    _, centre = camera.rays()
    _, sub = camera.rays(9)
    assert sub.shape == (8 * 9, 3)
    # the sub-rays of one pixel project inside that pixel, around its centre ray
    u, v, _ = camera.project(camera.position + sub)
    pixel_u, pixel_v = np.floor(u).reshape(8, 9), np.floor(v).reshape(8, 9)
    np.testing.assert_array_equal(pixel_u, np.tile(np.arange(4), 2)[:, None].repeat(9, 1))
    np.testing.assert_array_equal(pixel_v, np.repeat(np.arange(2), 4)[:, None].repeat(9, 1))
    # stratified: offsets 1/6, 1/2, 5/6 of a pixel along each side
    np.testing.assert_allclose(np.sort(np.unique(np.round(u[:9] % 1, 12))), [1 / 6, 0.5, 5 / 6])
    uc, vc, _ = camera.project(camera.position + centre)
    np.testing.assert_allclose(u.reshape(8, 9)[:, 4], uc, atol=1e-12)
    np.testing.assert_allclose(v.reshape(8, 9)[:, 4], vc, atol=1e-12)


@pytest.mark.parametrize("bad", [2, 0, 8, 3.0])
def test_rays_per_pixel_must_be_a_square(bad):
    camera = PinholeCamera((0.0, 0.0, -2.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, (0.4, 0.4),
                           (2, 2))
    with pytest.raises(ValueError, match="perfect square"):
        camera.rays(bad)
