"""Spectra and band images of a rig of cameras of any pixel counts."""

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest

from invflame.geometry import CameraRig, PinholeCamera, VoxelGrid, paper_rig
from invflame.plotting.spectra import pixel_of_ray, plot_spectrum_and_images


def unequal_rig() -> CameraRig:
    """Two cameras: 3 columns × 2 rows, then 2 × 4."""
    cameras = paper_rig(VoxelGrid.poolfire(4), n_pixels=3).cameras[:2]
    return CameraRig([PinholeCamera(c.position, c.look_at, c.up, c.focal_length, c.sensor_size,
                                    pixels)
                      for c, pixels in zip(cameras, ((3, 2), (2, 4)), strict=True)])


def test_a_ray_s_camera_row_and_column():
    rig = unequal_rig()
    assert rig.image_shapes == ((2, 3), (4, 2))
    assert [pixel_of_ray(rig, ray) for ray in (0, 2, 3, 5, 6, 7, 13)] == [
        (0, 0, 0), (0, 0, 2), (0, 1, 0), (0, 1, 2), (1, 0, 0), (1, 0, 1), (1, 3, 1)]
    with pytest.raises(ValueError, match="ray 14 is outside the rig's 14 rays"):
        pixel_of_ray(rig, 14)


def test_every_camera_is_shown_in_its_own_shape_with_the_brightest_pixel_marked(tmp_path):
    rig = unequal_rig()
    measured = np.ones((14, 4))
    measured[12] = 5.0  # camera 2, row 4, column 1
    fig = plot_spectrum_and_images(np.linspace(660.0, 690.0, 4), measured, 0.9 * measured,
                                   rig, "VG/TV", path=tmp_path / "s.png")
    assert matplotlib.image.imread(tmp_path / "s.png").size > 0
    shown = [ax for ax in fig.axes if ax.images]
    assert [ax.images[0].get_array().shape for ax in shown] == [(2, 3), (4, 2)] * 2
    assert fig.axes[0].get_title() == "brightest pixel: camera 2, row 4, column 1 (ray 12)"
    marked = [ax for ax in shown if ax.lines]
    assert marked == [shown[1], shown[3]]  # on camera 2, measured and simulated
    np.testing.assert_array_equal(marked[0].lines[0].get_xydata(), [[0.0, 3.0]])
    plt.close(fig)


def test_spectra_of_another_rig_are_refused():
    with pytest.raises(ValueError, match=r"one row per pixel of the rig: 14 pixels over "
                                         r"cameras of \[\(2, 3\), \(4, 2\)\]"):
        plot_spectrum_and_images(np.arange(4.0), np.ones((16, 4)), np.ones((16, 4)),
                                 unequal_rig())
