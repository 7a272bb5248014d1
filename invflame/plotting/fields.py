"""Figures of flame fields: mid-plane cutaways with temperature isocontours (PNG)."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from invflame.field import FIELD_NAMES, Field  # noqa: E402
from invflame.plotting import save_figure

ISOTHERMS = tuple(float(t) for t in range(500, 1600, 100))
"""Default temperature isocontours in K: every 100 K from 500 to 1500 K."""

LABELS = {"T": "T [K]", "CO2": "X$_{CO_2}$", "H2O": "X$_{H_2O}$", "CH4": "X$_{CH_4}$"}
"""Axis label of each field (mole fractions are dimensionless)."""

COLORMAPS = {"T": "inferno", "CO2": "viridis", "H2O": "viridis", "CH4": "cividis"}
"""Colour map of each field."""

AXIS_NAMES = "xyz"


def mid_plane(volume: np.ndarray, normal: int) -> np.ndarray:
    """Slice of a ``(nx, ny, nz)`` array through the centre, perpendicular to axis ``normal``.

    With an even count along ``normal`` the centre lies between two voxel layers, and their
    mean is returned.
    """
    n = volume.shape[normal]
    lo, hi = (n - 1) // 2, n // 2
    take = np.take(volume, [lo, hi], axis=normal)
    return take.mean(axis=normal)


def vertical_section(volume: np.ndarray, shown: int, normal: int, up: int) -> np.ndarray:
    """Mid-plane of a ``(nx, ny, nz)`` array as an image: rows along the up axis ``up``,
    columns along the horizontal axis ``shown``, through the centre along ``normal``."""
    plane = mid_plane(volume, normal)  # remaining axes in increasing order
    return plane.T if shown < up else plane


def vertical_planes(grid) -> list[tuple[int, int]]:
    """(horizontal axis shown, normal axis) of the two vertical mid-planes of a
    :class:`~invflame.geometry.VoxelGrid`."""
    horizontal = [a for a in range(3) if a != grid.up_axis]
    return [(horizontal[0], horizontal[1]), (horizontal[1], horizontal[0])]


def plot_fields(
    fields: Field | Sequence[Field],
    labels: Sequence[str] | None = None,
    path=None,
    isotherms: Sequence[float] = ISOTHERMS,
    dpi: int = 150,
):
    """Side-by-side mid-plane cutaways of one or more fields, one row per quantity.

    Each field gets two columns, the two vertical planes through the box centre (x–y and
    z–y for a y-up grid), with the vertical axis up. Rows are T, X_CO2, X_H2O, X_CH4 with one
    colour scale per row shared by all fields (ground truth and reconstructions compare
    directly). The field's own temperature isocontours (default every 100 K from 500 to
    1500 K) are drawn over every panel.

    Parameters
    ----------
    fields : Field or sequence of Field
        Fields to show (e.g. ground truth first, then reconstructions).
    labels : sequence of str, optional
        Column titles, one per field; default each field's ``metadata["source"]``, else
        "field 0", "field 1", ...
    path : str or os.PathLike, optional
        Write a PNG there (parent folders created).
    isotherms : sequence of float, optional
        Contour temperatures in K; those outside a field's range are skipped.
    dpi : int, optional
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (close it with ``matplotlib.pyplot.close`` when done).
    """
    fields = [fields] if isinstance(fields, Field) else list(fields)
    if not fields:
        raise ValueError("plot_fields needs at least one Field")
    if labels is None:
        labels = [f.metadata.get("source", f"field {i}") for i, f in enumerate(fields)]
    if len(labels) != len(fields):
        raise ValueError(f"{len(labels)} labels for {len(fields)} fields; give one per field")

    n_rows, n_cols = len(FIELD_NAMES), 2 * len(fields)
    fig, axes = plt.subplots(
        n_rows, n_cols, figsize=(2.6 * n_cols + 1.2, 2.5 * n_rows), squeeze=False,
        constrained_layout=True,
    )
    for row, name in enumerate(FIELD_NAMES):
        vmin = min(float(f[name].min()) for f in fields)
        vmax = max(float(f[name].max()) for f in fields)
        if vmax <= vmin:
            vmax = vmin + (1.0 if name == "T" else 1e-6)
        for k, (field, label) in enumerate(zip(fields, labels, strict=True)):
            grid = field.grid
            up = grid.up_axis
            coords = grid.axes()
            for j, (shown, normal) in enumerate(vertical_planes(grid)):
                ax = axes[row, 2 * k + j]
                image = vertical_section(field[name], shown, normal, up)
                extent = (
                    grid.lower[shown], grid.upper[shown], grid.lower[up], grid.upper[up]
                )
                im = ax.imshow(
                    image, origin="lower", extent=extent, vmin=vmin, vmax=vmax,
                    cmap=COLORMAPS[name], interpolation="nearest",
                )
                temperature = vertical_section(field.T, shown, normal, up)
                levels = [t for t in isotherms if temperature.min() < t < temperature.max()]
                if levels:
                    ax.contour(
                        coords[shown], coords[up], temperature, levels=levels,
                        colors="white", linewidths=0.5, alpha=0.8,
                    )
                ax.set_aspect("equal")
                ax.tick_params(labelsize=7)
                if row == 0:
                    at = grid.centre[normal]
                    ax.set_title(
                        f"{label}\n{AXIS_NAMES[shown]}–{AXIS_NAMES[up]} plane, "
                        f"{AXIS_NAMES[normal]} = {at:.2g} m",
                        fontsize=8,
                    )
                if row == n_rows - 1:
                    ax.set_xlabel(f"{AXIS_NAMES[shown]} [m]", fontsize=8)
                if k == 0 and j == 0:
                    ax.set_ylabel(f"{AXIS_NAMES[up]} [m]", fontsize=8)
        cbar = fig.colorbar(im, ax=axes[row, :].tolist(), shrink=0.9, pad=0.01)
        cbar.set_label(LABELS[name], fontsize=9)
        cbar.ax.tick_params(labelsize=7)
    if isotherms:
        fig.suptitle(
            f"mid-plane cutaways; white lines: isotherms {min(isotherms):.0f}–"
            f"{max(isotherms):.0f} K", fontsize=9,
        )
    return save_figure(fig, path, dpi)
