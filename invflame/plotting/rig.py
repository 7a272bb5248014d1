"""A camera rig and its voxel grid in 3-D: pinholes, viewing frusta, the grid's box and cells."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402

from invflame.atomic_files import write_atomic  # noqa: E402
from invflame.geometry import CameraRig, PinholeCamera, VoxelGrid  # noqa: E402

MAX_CELL_LINES = 12
"""At most this many cell lines are drawn per axis on the grid's faces (every k-th plane)."""


def frustum_corners(camera: PinholeCamera, depth: float) -> np.ndarray:
    """The four corners (top-left, top-right, bottom-right, bottom-left) of the image's field
    of view at ``depth`` m along the optical axis, in m, shape (4, 3)."""
    nu, nv = camera.n_pixels
    cu, cv = camera.principal_point
    w, h = camera.sensor_size
    scale = depth / camera.focal_length
    x = (np.array([0.0, nu, nu, 0.0]) - cu) / nu * w * scale  # along right
    y = (cv - np.array([0.0, 0.0, nv, nv])) / nv * h * scale  # along image_up
    return (camera.position + depth * camera.forward + x[:, None] * camera.right
            + y[:, None] * camera.image_up)


def _grid_lines(grid: VoxelGrid) -> list[np.ndarray]:
    """Segments (m) of the box's edges and of cell planes on its three lower faces."""
    lines = []
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        for i in (0, 1):
            for j in (0, 1):  # the four box edges along ``axis``
                a, b = grid.lower.copy(), grid.lower.copy()
                a[others[0]] = b[others[0]] = (grid.lower, grid.upper)[i][others[0]]
                a[others[1]] = b[others[1]] = (grid.lower, grid.upper)[j][others[1]]
                b[axis] = grid.upper[axis]
                lines.append(np.stack([a, b]))
        step = max(1, -(-grid.shape[axis] // MAX_CELL_LINES))
        for plane in grid.lower[axis] + grid.spacing[axis] * np.arange(0, grid.shape[axis],
                                                                      step)[1:]:
            for other in others:  # cell lines across the faces at the lower corner
                a, b = grid.lower.copy(), grid.lower.copy()
                a[axis] = b[axis] = plane
                b[other] = grid.upper[other]
                lines.append(np.stack([a, b]))
    return lines


def plot_rig(rig: CameraRig, grid: VoxelGrid, path=None, title: str | None = None):
    """Draw the cameras (pinhole, index and optical axis), their frusta out to the grid's far
    side, and the grid's box with its cells, in metres with equal scales and the grid's up
    axis vertical.

    Parameters
    ----------
    rig : CameraRig
        The cameras.
    grid : VoxelGrid
        The reconstruction grid (m).
    path : str or os.PathLike, optional
        Write the figure here (PNG).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    order = [(grid.up_axis + 1) % 3, (grid.up_axis + 2) % 3, grid.up_axis]

    def shown(points):  # world axes to the plot's, cyclically (not mirrored), up axis last
        return np.asarray(points)[..., order]

    fig = plt.figure(figsize=(7.5, 7.0))
    ax = fig.add_subplot(projection="3d")
    ax.add_collection3d(Line3DCollection([shown(line) for line in _grid_lines(grid)],
                                         colors="0.45", linewidths=0.6))
    corners = grid.corners()
    points = [corners]
    colours = plt.cm.tab10(np.arange(rig.n_cameras) % 10)
    for index, (camera, colour) in enumerate(zip(rig.cameras, colours, strict=True)):
        depth = max(float(np.max(camera.to_camera_frame(corners)[:, 2])), camera.focal_length)
        far = frustum_corners(camera, depth)
        sides = [shown(np.stack([camera.position, far[k], far[(k + 1) % 4]]))
                 for k in range(4)]
        ax.add_collection3d(Poly3DCollection(sides, facecolors=[(*colour[:3], 0.06)],
                                             edgecolors=[colour], linewidths=0.8))
        ax.plot(*shown(np.stack([camera.position, camera.position + depth * camera.forward])).T,
                color=colour, linestyle="--", linewidth=0.8)
        ax.scatter(*shown(camera.position), color=colour, s=30, depthshade=False)
        ax.text(*shown(camera.position), f" {index}", color=colour, fontsize=11,
                fontweight="bold")
        points += [camera.position[None], far]
    every = shown(np.concatenate(points))
    low, high = every.min(axis=0), every.max(axis=0)
    centre, half = (low + high) / 2, (high - low).max() / 2 * 1.05
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre, strict=True):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    names = [f"{'xyz'[a]} [m]" for a in order]
    ax.set(xlabel=names[0], ylabel=names[1], zlabel=names[2])
    ax.set_title(title or f"{rig.n_cameras} cameras, grid {'x'.join(map(str, grid.shape))}")
    if path is not None:
        write_atomic(path, lambda handle: fig.savefig(handle, format="png", dpi=130,
                                                      bbox_inches="tight"))
    return fig
