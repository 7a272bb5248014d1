"""Accuracy of an absorption table's temperature spline against line-by-line evaluation."""

from __future__ import annotations

import numpy as np

from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.cross_section import cross_section, grid_step
from invflame.spectroscopy.spectral_points import MAX_POINTS_PER_BIN, fine_grid

#: Width of the running mean applied before comparing spectra, cm⁻¹.
SMOOTHING = 1.0


def smooth(spectrum, step: float, width: float = SMOOTHING) -> np.ndarray:
    """Running mean over ``width`` (cm⁻¹) along the last axis ('valid' part only).

    Parameters
    ----------
    spectrum : array_like, shape (..., n_eta)
    step : float
        Grid step in cm⁻¹.
    width : float
        Window width in cm⁻¹ (rounded to a whole number of grid steps).
    """
    n = max(1, int(round(width / step)))
    csum = np.cumsum(np.asarray(spectrum, dtype=np.float64), axis=-1)
    zero = np.zeros(csum.shape[:-1] + (1,))
    csum = np.concatenate([zero, csum], axis=-1)
    return (csum[..., n:] - csum[..., :-n]) / n


def spline_error(table: AbsorptionTable, linelists: dict, temperatures,
                 subdivision: int = MAX_POINTS_PER_BIN) -> np.ndarray:
    """Largest relative error of the spline, per temperature and species, after smoothing.

    Compares ``table.spline(T)``, averaged over each bin's spectral points, with
    :func:`cross_section` evaluated directly at each ``T`` on the same ``subdivision`` sub-bins
    of every bin as the table was built from (same grid, pressure and self-broadening
    fraction), at each of a species' fraction nodes, both smoothed to 1 cm⁻¹.

    Parameters
    ----------
    table : AbsorptionTable
    linelists : dict of str -> LineList
        The line lists the table was built from.
    temperatures : array_like, shape (n,)
        K, usually between the nodes.
    subdivision : int, optional
        Sub-bins per bin of the table's build (:meth:`AbsorptionTable.build`).

    Returns
    -------
    ndarray, shape (n, n_species)
        max over η and the fraction nodes of |spline − direct| / direct (where direct > 0);
        0 for species without lines.
    """
    step = grid_step(table.wavenumber)
    fine = fine_grid(table.wavenumber, subdivision)
    temperatures = np.atleast_1d(np.asarray(temperatures, dtype=np.float64))
    errors = np.zeros((temperatures.size, len(table.species)))
    for i, temperature in enumerate(temperatures):
        interpolated = table.bin_average(table.spline(np.asarray(temperature)))
        for j, name in enumerate(table.species):
            lines = linelists.get(name)
            if lines is None or len(lines) == 0:
                continue
            for column, fraction in zip(range(interpolated.shape[0])[table.columns(j)],
                                        table.self_fraction[j], strict=True):
                direct = cross_section(lines, fine, temperature, table.pressure, fraction)
                reference = smooth(direct.reshape(-1, subdivision).mean(axis=1), step)
                difference = np.abs(smooth(interpolated[column], step) - reference)
                covered = reference > 0
                errors[i, j] = max(errors[i, j],
                                   np.max(difference[covered] / reference[covered]))
    return errors
