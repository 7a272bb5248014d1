"""Figures of a run's error bars: cutaways of σ_T beside T, and z-score histograms (PNG)."""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from invflame.field import Field  # noqa: E402
from invflame.plotting import save_figure
from invflame.plotting.fields import AXIS_NAMES, LABELS, vertical_planes, vertical_section  # noqa: E402

Z_RANGE = 5.0
"""Histograms show z-scores in [-Z_RANGE, Z_RANGE]; those beyond are counted at the edges."""

_ISOTHERMS = (500.0, 1000.0, 1500.0)  # K, drawn over the σ_T panels for orientation


def plot_uncertainty(estimate: Field, sigma_t: np.ndarray, truth: Field | None = None,
                     path=None, dpi: int = 130):
    """Mid-plane cutaways (the two vertical planes through the box centre) of the estimate's
    T beside its standard deviation σ_T; with a truth, a second row with the truth's T beside
    the z-score (T̂ − T)/σ_T.

    Parameters
    ----------
    estimate : Field
        The reconstruction (T in K).
    sigma_t : ndarray, shape ``estimate.grid.shape``
        σ_T in K.
    truth : Field, optional
        The ground truth on the same grid.
    path : str or os.PathLike, optional
        Write a PNG there.
    dpi : int, optional
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
    """
    grid = estimate.grid
    if sigma_t.shape != grid.shape:
        raise ValueError(f"sigma_t has shape {sigma_t.shape}, the estimate's grid {grid.shape}")
    t_max = max(float(estimate.T.max()), -np.inf if truth is None else float(truth.T.max()))
    t_min = min(float(estimate.T.min()), np.inf if truth is None else float(truth.T.min()))
    rows = [("reconstruction", estimate.T, "inferno", (t_min, t_max), LABELS["T"]),
            ("σ_T", sigma_t, "viridis", (0.0, max(float(sigma_t.max()), 1e-9)), "σ_T [K]")]
    if truth is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(estimate.T == truth.T, 0.0, (estimate.T - truth.T) / sigma_t)
        rows += [("truth", truth.T, "inferno", (t_min, t_max), LABELS["T"]),
                 ("z = (T̂ − T)/σ_T", z, "RdBu_r", (-3.0, 3.0), "z-score")]
    planes, up = vertical_planes(grid), grid.up_axis
    n_rows = len(rows) // 2
    fig, axes = plt.subplots(n_rows, 4, squeeze=False, layout="constrained",
                             figsize=(10.5, 2.9 * n_rows + 0.4))
    for index, (title, volume, cmap, (vmin, vmax), label) in enumerate(rows):
        pair = axes[index // 2, 2 * (index % 2):2 * (index % 2) + 2]
        for ax, (shown, normal) in zip(pair, planes, strict=True):
            extent = (grid.lower[shown], grid.upper[shown], grid.lower[up], grid.upper[up])
            image = ax.imshow(vertical_section(volume, shown, normal, up), origin="lower",
                              extent=extent, vmin=vmin, vmax=vmax, cmap=cmap,
                              interpolation="nearest")
            if title == "σ_T":
                temperature = vertical_section(estimate.T, shown, normal, up)
                inside = [t for t in _ISOTHERMS if temperature.min() < t < temperature.max()]
                if inside:
                    coords = grid.axes()
                    ax.contour(coords[shown], coords[up], temperature, levels=inside,
                               colors="white", linewidths=0.6, alpha=0.8)
            ax.set_title(f"{title}\n{AXIS_NAMES[shown]}–{AXIS_NAMES[up]} plane at "
                         f"{AXIS_NAMES[normal]} = {grid.centre[normal]:.2g} m", fontsize=7.5)
            ax.set_xlabel(f"{AXIS_NAMES[shown]} [m]", fontsize=7)
            ax.set_ylabel(f"{AXIS_NAMES[up]} [m]", fontsize=7)
            ax.tick_params(labelsize=6)
        bar = fig.colorbar(image, ax=pair.tolist(), shrink=0.85, pad=0.01,
                           extend="both" if cmap == "RdBu_r" else "neither")
        bar.set_label(label, fontsize=8)
        bar.ax.tick_params(labelsize=6.5)
    fig.suptitle("temperature and its posterior standard deviation (linearized); white lines "
                 "on σ_T: the reconstruction's isotherms " + ", ".join(
                     f"{t:.0f}" for t in _ISOTHERMS) + " K", fontsize=8.5)
    return save_figure(fig, path, dpi)


def plot_z_scores(z: Mapping[str, np.ndarray], hot: np.ndarray, path=None, dpi: int = 130):
    """Histograms of z-scores (estimate − truth)/σ per field, over all voxels and over the hot
    ones, against the standard normal density.

    Parameters
    ----------
    z : mapping of str to ndarray
        Field name (``"T"``, ``"CO2"``, ...) → z-score per voxel, shape ``(nx, ny, nz)``.
    hot : ndarray of bool, shape (nx, ny, nz)
        The voxels of the flame (e.g. truth above 500 K).
    path : str or os.PathLike, optional
        Write a PNG there.
    dpi : int, optional
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = plt.subplots(1, len(z), squeeze=False, layout="constrained",
                             figsize=(3.4 * len(z), 3.0))
    edges = np.linspace(-Z_RANGE, Z_RANGE, 41)
    curve = np.linspace(-Z_RANGE, Z_RANGE, 201)
    for ax, (name, scores) in zip(axes[0], z.items(), strict=True):
        for mask, label, colour in ((np.ones_like(hot), "all voxels", "tab:blue"),
                                    (hot, "hot voxels", "tab:orange")):
            values = scores[mask]
            if values.size == 0:
                continue
            beyond = int(np.sum(np.abs(values) > Z_RANGE))
            ax.hist(np.clip(values, -Z_RANGE, Z_RANGE), bins=edges, density=True,
                    histtype="step", color=colour, linewidth=1.2,
                    label=f"{label} ({values.size}; {beyond} beyond ±{Z_RANGE:g})")
        ax.plot(curve, np.exp(-curve**2 / 2) / np.sqrt(2 * np.pi), "k--", linewidth=1,
                label="N(0, 1)")
        quantity = LABELS.get(name, name).removesuffix(" [K]")
        ax.set_xlabel(f"z of {quantity} = (estimate − truth)/σ (dimensionless)", fontsize=8)
        ax.set_ylabel("density", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=6.5, loc="upper left")
    fig.suptitle("calibration of the error bars: z-scores of the truth", fontsize=9)
    return save_figure(fig, path, dpi)
