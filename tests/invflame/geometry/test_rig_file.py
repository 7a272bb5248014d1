"""Camera rigs from TOML: the paper preset, round trips, orientations, bad records, bad rigs."""

import numpy as np
import pytest

from invflame.cli import main
from invflame.errors import GeometryError, InputDataError
from invflame.geometry import CameraRig, PinholeCamera, VoxelGrid, paper_rig, traverse
from invflame.geometry.rig_file import (
    check_rig_sees_grid,
    parse_rig,
    read_rig,
    rig_records,
    write_rig,
)

CAMERA = {"position": [2.0, 0.5, 0.0], "look_at": [0.0, 0.5, 0.0], "up": [0.0, 1.0, 0.0],
          "focal_length": 0.5, "sensor_size": [0.4, 0.3], "pixels": [5, 3]}


def same_rays(a: CameraRig, b: CameraRig, rays_per_pixel: int = 1) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(a.rays(rays_per_pixel),
                                                    b.rays(rays_per_pixel), strict=True))


@pytest.mark.parametrize("rays_per_pixel", [1, 9])
def test_paper_preset_gives_exactly_the_paper_rays(rays_per_pixel):
    preset = read_rig("paper")
    assert preset.instrument == {}
    assert same_rays(preset.rig, paper_rig(VoxelGrid.poolfire(60)), rays_per_pixel)


def test_rig_file_round_trips_value_by_value(tmp_path):
    rig = paper_rig(VoxelGrid.cube(6, centre=(0.1, 0.2, -0.3)), n_pixels=3, distance=1.3)
    spec = read_rig(write_rig(rig, tmp_path / "rig.toml",
                              {"resolution": 4.0, "apodization": "triangular"}))
    assert spec.instrument == {"resolution": 4.0, "apodization": "triangular"}
    assert rig_records(spec.rig) == rig_records(rig)
    assert same_rays(spec.rig, rig, 4)


def test_rotation_and_quaternion_give_the_look_at_camera():
    # camera on +x looking at the origin, y up: right = forward x up = -z, down = -y
    look = parse_rig([{**CAMERA, "position": [2.0, 0.0, 0.0], "look_at": [0.0, 0.0, 0.0]}],
                     "test").rig
    rotation = [[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]]  # rows: right, down, fwd
    pose = {k: v for k, v in CAMERA.items() if k not in ("look_at", "up")}
    pose["position"] = [2.0, 0.0, 0.0]
    by_matrix = parse_rig([{**pose, "rotation": rotation}], "test").rig
    # the same rotation as a unit quaternion [w, x, y, z]: 180 degrees about (1, 0, -1)/sqrt 2
    s = np.sqrt(0.5)
    by_quaternion = parse_rig([{**pose, "quaternion": [0.0, s, 0.0, -s]}], "test").rig
    for rig in (by_matrix, by_quaternion):
        np.testing.assert_allclose(rig.rays()[1], look.rays()[1], atol=1e-15)


def test_pixel_pitch_and_principal_point():
    pitch = parse_rig([{**{k: v for k, v in CAMERA.items() if k != "sensor_size"},
                        "pixel_pitch": [0.08, 0.1]}], "test").rig
    assert pitch.cameras[0].sensor_size == pytest.approx((0.4, 0.3))
    # principal point at the centre of pixel (u, v) = (1, 2): that pixel looks along the axis
    shifted = parse_rig([{**CAMERA, "principal_point": [1.5, 2.5]}], "test").rig.cameras[0]
    _, d = shifted.rays()
    np.testing.assert_allclose(d[2 * 5 + 1], shifted.forward, atol=1e-15)
    u, v, _ = shifted.project(shifted.position + shifted.forward)
    assert (u, v) == pytest.approx((1.5, 2.5))


@pytest.mark.parametrize(("change", "message"), [
    ({"focal_length": -1.0}, "camera 1: 'focal_length' must be a positive number in m"),
    ({"position": [1.0, 2.0]}, "camera 1: 'position' must be a list of 3 finite numbers"),
    ({"pixels": [4, 0]}, "camera 1: 'pixels' must be two positive integers"),
    ({"focal_lenght": 0.5}, "camera 1: unknown key 'focal_lenght' \\(did you mean "
                            "'focal_length'\\?\\)"),
    ({"rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}, "camera 1: give exactly one of "
                                                      "'look_at', 'rotation', 'quaternion'"),
    ({"pixel_pitch": [1e-3, 1e-3]}, "camera 1: give exactly one of 'sensor_size', "
                                    "'pixel_pitch'"),
    ({"up": [1.0, 0.0, 0.0], "look_at": [4.0, 0.5, 0.0]}, "camera 1: up .* is parallel"),
    ({"apodization": "boxcar"}, "camera 1: 'apodization' = 'boxcar' is not modelled"),
    ({"resolution": 4.0}, "camera 1: 'resolution' = 4.0 differs from camera 0's 8.0"),
])
def test_malformed_records_name_the_camera_and_key(change, message):
    good = {**CAMERA, "resolution": 8.0}
    with pytest.raises(InputDataError, match=message):
        parse_rig([good, {**good, **change}], "rig.toml")


@pytest.mark.parametrize(("record", "message"), [
    ({k: v for k, v in CAMERA.items() if k != "focal_length"}, "missing key 'focal_length'"),
    ({k: v for k, v in CAMERA.items() if k != "up"}, "'look_at' needs 'up'"),
    ({**{k: v for k, v in CAMERA.items() if k not in ("look_at", "up")},
      "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}, "'rotation' must be a proper rotation"),
    ({**{k: v for k, v in CAMERA.items() if k not in ("look_at", "up")},
      "quaternion": [1.0, 1.0, 0.0, 0.0]}, "'quaternion' \\[w, x, y, z\\] must have unit norm"),
])
def test_missing_and_inconsistent_orientation_keys(record, message):
    with pytest.raises(InputDataError, match="rig.toml: camera 0: " + message):
        parse_rig([record], "rig.toml")


def test_rig_files_that_are_not_rigs(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text("[[cameras]\n")
    with pytest.raises(InputDataError, match=f"{path}: not a TOML rig file"):
        read_rig(path)
    path.write_text("camera = 1\n")
    with pytest.raises(InputDataError, match="unknown top-level key"):
        read_rig(path)
    path.write_text("")
    with pytest.raises(InputDataError, match="no cameras"):
        read_rig(path)
    with pytest.raises(FileNotFoundError, match="rig file not found"):
        read_rig(tmp_path / "missing.toml")


@pytest.mark.parametrize(("camera", "message"), [
    ({**CAMERA, "position": [0.0, 0.5, 0.0], "look_at": [1.0, 0.5, 0.0]},
     "camera 1 at \\[0.0, 0.5, 0.0\\] m is inside the grid"),
    ({**CAMERA, "look_at": [4.0, 0.5, 0.0]}, "camera 1 .* looks away from the grid"),
    ({**CAMERA, "look_at": [0.0, 0.5, 3.0]}, "camera 1 .* sees no voxel"),
])
def test_cameras_that_cannot_measure_the_grid_are_named(camera, message):
    grid = VoxelGrid.poolfire(8)
    rig = CameraRig((paper_rig(grid, n_pixels=2).cameras[0],
                     parse_rig([camera], "test").rig.cameras[0]))
    with pytest.raises(GeometryError, match=message):
        check_rig_sees_grid(rig, grid)


def _chords(grid, origins, directions):
    """Entry and exit distances through the box, by clipping the parametric line."""
    t_in, t_out = np.zeros(len(origins)), np.full(len(origins), np.inf)
    for a in range(3):
        t0 = (grid.lower[a] - origins[:, a]) / directions[:, a]
        t1 = (grid.upper[a] - origins[:, a]) / directions[:, a]
        t_in = np.maximum(t_in, np.minimum(t0, t1))
        t_out = np.minimum(t_out, np.maximum(t0, t1))
    return np.where(t_out > t_in, t_out - t_in, 0.0)


def test_three_cameras_at_oblique_angles_traverse_their_chords():
    grid = VoxelGrid((-0.4, 0.0, -0.3), (0.5, 0.8, 0.4), (7, 9, 6))
    centre = grid.centre
    records = []
    for azimuth, elevation in ((20.0, 25.0), (137.0, -15.0), (251.0, 40.0)):
        a, e = np.radians(azimuth), np.radians(elevation)
        direction = np.array([np.cos(e) * np.cos(a), np.sin(e), np.cos(e) * np.sin(a)])
        records.append({"position": (centre + 1.7 * direction).tolist(),
                        "look_at": (centre + [0.03, -0.02, 0.05]).tolist(),
                        "up": [0.0, 1.0, 0.0], "focal_length": 0.4,
                        "sensor_size": [0.35, 0.3], "pixels": [7, 6]})
    rig = parse_rig(records, "test").rig
    check_rig_sees_grid(rig, grid)
    origins, directions = rig.rays(4)
    segments = traverse(grid, origins, directions)
    chords = _chords(grid, origins, directions)
    assert (chords > 0).sum() > 0.5 * len(chords)  # most rays cross the box
    np.testing.assert_allclose(segments.length.sum(axis=1), chords, rtol=1e-12, atol=1e-12)
    # every segment lies in the voxel it is assigned to
    mids = segments.midpoints()[segments.mask]
    index = np.floor((mids - grid.lower) / grid.spacing).astype(int)
    np.testing.assert_array_equal(np.ravel_multi_index(index.T, grid.shape),
                                  segments.voxel[segments.mask])


def test_rig_plot_draws_the_rig_and_refuses_a_bad_one(tmp_path, capsys):
    out = tmp_path / "rig.png"
    assert main(["rig", "plot", "paper", "--grid", "6", "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = CameraRig((PinholeCamera(**{"position": [0.0, 0.5, 0.0], "look_at": [1.0, 0.5, 0.0],
                                      "up": [0.0, 1.0, 0.0], "focal_length": 0.5,
                                      "sensor_size": [0.4, 0.3], "n_pixels": [5, 3]}),))
    rig_file = write_rig(bad, tmp_path / "bad.toml")
    assert main(["rig", "plot", str(rig_file), "--grid", "6", "--out", str(out)]) == 2
    assert "camera 0 at [0.0, 0.5, 0.0] m is inside the grid" in capsys.readouterr().err
