"""3-D cutaway isotherm surfaces of flame temperature fields (marching cubes, matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import BoundaryNorm  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402
from skimage.measure import marching_cubes  # noqa: E402

from invflame.field import Field  # noqa: E402
from invflame.plotting import save_figure
from invflame.plotting.fields import AXIS_NAMES, ISOTHERMS  # noqa: E402

_TITLE_INCHES = 0.5  # room above each panel for a title of up to three lines
_BAR_INCHES = 0.8  # room for the colour bar under the panels

MAX_SAMPLES = 40
"""Marching cubes steps over voxels so that at most about this many samples lie along an axis
(a 60³ grid is drawn from every second voxel), keeping the triangle count drawable."""


def isotherm_surface(field: Field, level: float, step: int = 1,
                     cut: bool = True) -> np.ndarray:
    """Triangles of the surface ``T = level`` through the voxel centres, in m.

    Parameters
    ----------
    field : Field
        Temperature [K] on a voxel grid (m).
    level : float
        Temperature of the surface in K.
    step : int, optional
        Voxels per marching-cubes step (1: every voxel).
    cut : bool, optional
        Leave out the triangles in the quarter of the box with both horizontal coordinates on
        the viewer's side of the centre (larger first, smaller second horizontal axis), so the
        inner surfaces show.

    Returns
    -------
    numpy.ndarray, shape (n_triangles, 3, 3)
        Corner coordinates (x, y, z) in m; empty when ``level`` is outside the field's range
        or, with ``step > 1``, crosses none of the sampled voxels.
    """
    temperature = field.T
    if not temperature.min() < level < temperature.max():
        return np.empty((0, 3, 3))
    grid = field.grid
    try:
        verts, faces, _, _ = marching_cubes(temperature.astype(np.float64), level=level,
                                            spacing=tuple(grid.spacing), step_size=step)
    except RuntimeError:  # no surface among the voxels sampled when step > 1
        return np.empty((0, 3, 3))
    triangles = verts[faces] + (grid.lower + 0.5 * grid.spacing)
    if cut:
        first, second = (a for a in range(3) if a != grid.up_axis)
        centres = triangles.mean(axis=1)
        away = ((centres[:, first] > grid.centre[first])
                & (centres[:, second] < grid.centre[second]))
        triangles = triangles[~away]
    return triangles


def plot_isotherms_3d(fields: Mapping[str, Field], path=None,
                      levels: Sequence[float] = ISOTHERMS,
                      scores: Mapping[str, float] | None = None, columns: int = 4,
                      width: int = 1600, dpi: int = 150,
                      alpha: tuple[float, float] = (0.25, 0.9)):
    """Cutaway isotherm surfaces in 3-D, one panel per field set (like Fig. 2 of the study).

    Each panel draws the surfaces ``T = level`` (default every 100 K from 500 to 1500 K), one
    colour per level, with the quarter of the box facing the viewer cut away; the vertical axis
    of the grid points up. All panels share the view, the colour of each level and the axes:
    each shows the whole grid box at equal scales, so the shapes compare panel to panel.

    Parameters
    ----------
    fields : mapping of str to Field
        Panel label → fields on one grid (e.g. the ground truth, then each method), in display
        order.
    path : str or os.PathLike, optional
        Write a PNG there (parent folders created).
    levels : sequence of float, optional
        Isotherm temperatures in K, increasing.
    scores : mapping of str to float, optional
        Panel label → score shown under the label as "MSE_T ..." (normalized MSE of T).
    columns : int, optional
        Panels per row.
    width : int, optional
        Width of the PNG in pixels (default 1600).
    dpi : int, optional
        Resolution of the PNG.
    alpha : (float, float), optional
        Opacity of the coolest and of the hottest surface (0–1), linear in between.

    Returns
    -------
    matplotlib.figure.Figure
        ``len(fields)`` 3-D panels and one colour bar of the levels.
    """
    if not fields:
        raise ValueError("plot_isotherms_3d needs at least one field set (label -> Field)")
    grid = next(iter(fields.values())).grid
    elsewhere = [label for label, field in fields.items() if field.grid != grid]
    if elsewhere:
        raise ValueError(f"field sets {elsewhere} lie on another grid than the first; resample "
                         "them onto one grid (Field.resample) so the panels share their axes")
    levels = [float(t) for t in levels]
    if len(levels) < 2 or np.any(np.diff(levels) <= 0):
        raise ValueError(f"levels must be at least two increasing temperatures in K; got "
                         f"{levels}")
    if columns < 1:
        raise ValueError(f"columns must be a positive number of panels per row; got {columns}")
    n_cols = min(columns, len(fields))
    n_rows = -(-len(fields) // n_cols)
    panel = width / dpi / n_cols  # square panels, in inches
    height = n_rows * (panel + _TITLE_INCHES) + _BAR_INCHES
    fig = plt.figure(figsize=(width / dpi, height))
    cells = fig.add_gridspec(n_rows, n_cols, left=0.0, right=0.97, wspace=0.02,
                             top=1.0 - _TITLE_INCHES / height, bottom=_BAR_INCHES / height,
                             hspace=_TITLE_INCHES / panel)
    spacing = np.diff(levels)
    bounds = [levels[0] - spacing[0] / 2, *(np.add(levels[:-1], spacing / 2)),
              levels[-1] + spacing[-1] / 2]
    norm = BoundaryNorm(bounds, 256)
    cmap = plt.get_cmap("turbo")

    def level_colour(level):
        """The level's colour, more opaque the hotter: the outer surfaces let the inner show."""
        hotter = (level - levels[0]) / (levels[-1] - levels[0])
        return (*cmap(norm(level))[:3], alpha[0] + (alpha[1] - alpha[0]) * hotter)

    first, second = (a for a in range(3) if a != grid.up_axis)
    order = [first, second, grid.up_axis]  # plot axes: horizontal, horizontal, up
    step = max(1, int(np.ceil(max(grid.shape) / MAX_SAMPLES)))
    for i, (label, field) in enumerate(fields.items()):
        ax = fig.add_subplot(cells[i // n_cols, i % n_cols], projection="3d")
        surfaces = [(isotherm_surface(field, level, step), level) for level in levels]
        triangles = np.concatenate([t for t, _ in surfaces])
        if len(triangles):  # one collection: matplotlib sorts its faces by depth
            colours = np.concatenate([np.tile(level_colour(level), (len(t), 1))
                                      for t, level in surfaces])
            ax.add_collection3d(Poly3DCollection(
                triangles[..., order], facecolors=colours, edgecolor="none", shade=True))
        for setter, a in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), order, strict=True):
            setter(grid.lower[a], grid.upper[a])
        ax.set_box_aspect([grid.upper[a] - grid.lower[a] for a in order],
                          zoom=0.85)  # room for labels
        ax.set_xlabel(f"{AXIS_NAMES[first]} [m]", fontsize=7, labelpad=-6)
        ax.set_ylabel(f"{AXIS_NAMES[second]} [m]", fontsize=7, labelpad=-6)
        ax.set_zlabel(f"{AXIS_NAMES[grid.up_axis]} [m]", fontsize=7, labelpad=-6)
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
            axis.set_major_locator(MaxNLocator(5))  # tick labels that do not run together
        ax.tick_params(labelsize=5.5, pad=-3)
        score = (scores or {}).get(label)
        ax.set_title(label + ("" if score is None else f"\nMSE_T {score:.4f}"), fontsize=9)
    bar_axes = fig.add_axes((0.2, 0.6 * _BAR_INCHES / height, 0.6, 0.2 * _BAR_INCHES / height))
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), cax=bar_axes,
                       orientation="horizontal", ticks=levels)
    bar.set_label("isotherm T [K]; every panel shows the whole grid, a quarter of it cut away",
                  fontsize=8)
    bar.ax.tick_params(labelsize=7)
    return save_figure(fig, path, dpi)
