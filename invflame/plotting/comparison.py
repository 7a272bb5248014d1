"""Comparison grids of flame fields: one row per field set, one column per quantity and plane.

:func:`plot_comparison` shows the ground truth, the start and each reconstruction on the two
vertical mid-planes, on the truth's colour scale; :func:`plot_errors` shows each estimate minus
the truth on a symmetric diverging scale. Both put the score of each panel (e.g. the normalized
MSE) in its title and one colour bar per quantity under its columns.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from invflame.field import Field  # noqa: E402
from invflame.plotting import save_figure
from invflame.plotting.fields import (  # noqa: E402
    AXIS_NAMES,
    COLORMAPS,
    ISOTHERMS,
    LABELS,
    vertical_planes,
    vertical_section,
)

QUANTITIES = ("T", "CO2", "H2O")
"""Quantities shown by default: the fields the emission constrains (CH4 barely emits here)."""

ERROR_PERCENTILE = 99.0
"""The error maps' colour limit: this percentile of |estimate − truth| over every panel shown,
so one method far off does not wash out the others (larger errors saturate)."""

FLAME_EDGE = 500.0
"""The truth's isotherm drawn on the error maps (K): the edge of the flame."""

_PANEL_INCHES = 1.55  # height of one row of panels


def _check(truth: Field, estimates: Mapping[str, Field], quantities: Sequence[str]) -> None:
    if not estimates:
        raise ValueError("give at least one estimate (label -> Field) to compare with the truth")
    for label, field in estimates.items():
        if field.grid != truth.grid:
            raise ValueError(f"estimate {label!r} lies on grid {field.grid.shape}, the truth on "
                             f"{truth.grid.shape}; resample it (Field.resample) first")
    unknown = [q for q in quantities if q not in LABELS]
    if unknown:
        raise ValueError(f"unknown quantities {unknown}; choose from {list(LABELS)}")


def _panel_grid(grid, rows: Sequence[str], quantities: Sequence[str],
                section: Callable[[str, str, int, int], np.ndarray],
                scale: Mapping[str, tuple[float, float, str, str]],
                title: Callable[[str, str], str], isotherms: Mapping[str, np.ndarray],
                levels: Sequence[float], line_colour: str,
                colorbar_label: Callable[[str], str], heading: str, width: int, dpi: int):
    """Draw rows × (quantities × two vertical mid-planes) images.

    ``section(row, quantity, shown, normal)`` gives a panel's image (rows along the up axis);
    ``scale[quantity]`` its (vmin, vmax, colour map, colour bar extension);
    ``title(row, quantity)`` the text over its panels (under the quantity and plane on the
    first row); ``isotherms[row]`` a temperature volume (K) whose contours at ``levels`` go on
    the row's T panels in ``line_colour``.
    """
    planes = vertical_planes(grid)
    up = grid.up_axis
    n_rows, n_cols = len(rows), len(quantities) * len(planes)
    fig, axes = plt.subplots(n_rows, n_cols, squeeze=False, layout="constrained",
                             figsize=(width / dpi, _PANEL_INCHES * n_rows + 1.1),
                             sharex="col", sharey="row")
    coords = grid.axes()
    for r, row in enumerate(rows):
        for q, quantity in enumerate(quantities):
            vmin, vmax, cmap, _ = scale[quantity]
            for p, (shown, normal) in enumerate(planes):
                ax = axes[r, q * len(planes) + p]
                extent = (grid.lower[shown], grid.upper[shown], grid.lower[up], grid.upper[up])
                ax.imshow(section(row, quantity, shown, normal), origin="lower", extent=extent,
                          vmin=vmin, vmax=vmax, cmap=cmap, interpolation="nearest")
                if quantity == "T" and row in isotherms:
                    temperature = vertical_section(isotherms[row], shown, normal, up)
                    inside = [t for t in levels if temperature.min() < t < temperature.max()]
                    if inside:
                        ax.contour(coords[shown], coords[up], temperature, levels=inside,
                                   colors=line_colour, linewidths=0.5, alpha=0.7)
                text = title(row, quantity)
                if r == 0:
                    plane = f"{LABELS[quantity]}, {AXIS_NAMES[shown]}–{AXIS_NAMES[up]} plane"
                    text = f"{plane}\n{text}" if text else plane
                ax.set_title(text, fontsize=7, pad=2)
                ax.tick_params(labelsize=6, length=2, pad=1)
                if r == n_rows - 1:
                    ax.set_xlabel(f"{AXIS_NAMES[shown]} [m] (at {AXIS_NAMES[normal]} = "
                                  f"{grid.centre[normal]:.2g} m)", fontsize=6.5)
            if q == 0:
                axes[r, 0].set_ylabel(f"{row}\n{AXIS_NAMES[up]} [m]", fontsize=8,
                                      fontweight="bold")
    for q, quantity in enumerate(quantities):
        span = axes[:, q * len(planes):(q + 1) * len(planes)]
        bar = fig.colorbar(span[0, 0].images[0], ax=span.ravel().tolist(), location="bottom",
                           shrink=0.9, aspect=25, pad=0.01, extend=scale[quantity][3])
        bar.set_label(colorbar_label(quantity), fontsize=8)
        bar.ax.xaxis.set_major_locator(MaxNLocator(6))  # labels that do not run together
        bar.ax.tick_params(labelsize=6.5)
    fig.suptitle(heading, fontsize=9)
    return fig


def _score_title(scores: Mapping[str, Mapping[str, float]] | None, row: str,
                 quantity: str) -> str:
    value = (scores or {}).get(row, {}).get(quantity)
    return "" if value is None else f"MSE {value:.4f}"


def plot_comparison(truth: Field, estimates: Mapping[str, Field],
                    scores: Mapping[str, Mapping[str, float]] | None = None, path=None,
                    quantities: Sequence[str] = QUANTITIES, isotherms: Sequence[float] = ISOTHERMS,
                    truth_label: str = "ground truth", width: int = 1600, dpi: int = 150):
    """Mid-plane cutaways of the truth and of each estimate, one row each.

    Columns: each quantity on the two vertical planes through the box centre (x–y and z–y for a
    y-up grid), vertical axis up. Every quantity has one colour scale, the truth's range,
    shared by all rows (values beyond it saturate; the colour bar then has an arrow), and one
    colour bar under its columns. White lines on the temperature panels: the row's own
    isotherms (default every 100 K from 500 to 1500 K).

    Parameters
    ----------
    truth : Field
        Ground truth: T [K] and mole fractions [1] on a voxel grid (m).
    estimates : mapping of str to Field
        Row label → fields on the truth's grid, in display order (e.g. the start, then each
        method).
    scores : mapping of str to mapping of str to float, optional
        Row label → quantity → score shown in the panel's title as "MSE ..." (the normalized
        MSE, dimensionless); rows or quantities without one get no score.
    path : str or os.PathLike, optional
        Write a PNG there (parent folders created).
    quantities : sequence of str, optional
        Fields shown, from "T", "CO2", "H2O", "CH4" (default T, CO2, H2O).
    isotherms : sequence of float, optional
        Contour temperatures in K (empty: none).
    truth_label : str, optional
        Label of the truth's row.
    width : int, optional
        Width of the PNG in pixels (default 1600).
    dpi : int, optional
        Resolution of the PNG; the height follows from the number of rows.

    Returns
    -------
    matplotlib.figure.Figure
        ``len(estimates) + 1`` rows × ``2 len(quantities)`` image panels, then one colour bar
        per quantity (close it with ``matplotlib.pyplot.close``).
    """
    _check(truth, estimates, quantities)
    fields = {truth_label: truth, **estimates}
    scale = {}
    for q in quantities:
        low, high = float(truth[q].min()), float(truth[q].max())
        high = high if high > low else low + (1.0 if q == "T" else 1e-6)
        lows = min(float(f[q].min()) for f in estimates.values()) < low
        highs = max(float(f[q].max()) for f in estimates.values()) > high
        extend = {(False, False): "neither", (True, False): "min", (False, True): "max",
                  (True, True): "both"}[(lows, highs)]
        scale[q] = (low, high, COLORMAPS[q], extend)

    fig = _panel_grid(
        truth.grid, list(fields), quantities,
        lambda row, q, shown, normal: vertical_section(fields[row][q], shown, normal,
                                                       truth.grid.up_axis),
        scale, lambda row, q: _score_title(scores, row, q),
        {row: f.T for row, f in fields.items()}, isotherms, "white",
        lambda q: f"{LABELS[q]} (colour range: the truth's)",
        "mid-planes through the box centre" + (
            f"; white lines: isotherms {min(isotherms):.0f}–{max(isotherms):.0f} K"
            if len(isotherms) else "") + "; MSE: normalized MSE of the field over the domain",
        width, dpi)
    return save_figure(fig, path, dpi)


def plot_errors(truth: Field, estimates: Mapping[str, Field],
                scores: Mapping[str, Mapping[str, float]] | None = None, path=None,
                quantities: Sequence[str] = QUANTITIES, width: int = 1600, dpi: int = 150):
    """Error maps: each estimate minus the truth on the two vertical mid-planes, one row each.

    Same layout as :func:`plot_comparison` without the truth's row; a diverging colour scale
    per quantity, symmetric about 0 and limited at the :data:`ERROR_PERCENTILE` percentile of
    |estimate − truth| over every panel shown (red: too high, blue: too low). The truth's
    :data:`FLAME_EDGE` isotherm on the temperature panels shows where the flame is.

    Parameters
    ----------
    truth : Field
        Ground truth: T [K] and mole fractions [1] on a voxel grid (m).
    estimates : mapping of str to Field
        Row label → fields on the truth's grid, in display order.
    scores : mapping of str to mapping of str to float, optional
        Row label → quantity → score shown in the panel's title as "MSE ...".
    path : str or os.PathLike, optional
        Write a PNG there (parent folders created).
    quantities : sequence of str, optional
        Fields shown (default T, CO2, H2O).
    width : int, optional
        Width of the PNG in pixels (default 1600).
    dpi : int, optional
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
        ``len(estimates)`` rows × ``2 len(quantities)`` image panels, then one colour bar per
        quantity, in K for T and in mole fraction for the species.
    """
    _check(truth, estimates, quantities)
    grid, up = truth.grid, truth.grid.up_axis
    planes = vertical_planes(grid)

    def section(row, q, shown, normal):
        return vertical_section(estimates[row][q] - truth[q], shown, normal, up)

    scale = {}
    for q in quantities:
        errors = np.concatenate([np.abs(section(row, q, s, n)).ravel()
                                 for row in estimates for s, n in planes])
        limit = float(np.percentile(errors, ERROR_PERCENTILE))
        limit = limit if limit > 0 else (1.0 if q == "T" else 1e-6)
        extend = "both" if errors.max() > limit else "neither"
        scale[q] = (-limit, limit, "RdBu_r", extend)
    fig = _panel_grid(
        grid, list(estimates), quantities, section, scale,
        lambda row, q: _score_title(scores, row, q), dict.fromkeys(estimates, truth.T),
        (FLAME_EDGE,), "black", lambda q: f"estimate − truth of {LABELS[q]}",
        f"estimate − truth on the mid-planes (red: too high, blue: too low); black line: the "
        f"truth's {FLAME_EDGE:.0f} K isotherm; MSE: normalized MSE of the field over the domain",
        width, dpi)
    return save_figure(fig, path, dpi)
