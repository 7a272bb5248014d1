"""Accuracy of an absorption table's temperature spline against line-by-line evaluation."""

from __future__ import annotations

import numpy as np

from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.cross_section import cross_section, grid_step

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


def spline_error(table: AbsorptionTable, linelists: dict, temperatures) -> np.ndarray:
    """Largest relative error of the spline, per temperature and species, after smoothing.

    Compares ``table.spline(T)`` with :func:`cross_section` evaluated directly at each ``T``
    (same grid, pressure and self-broadening fractions), both smoothed to 1 cm⁻¹.

    Parameters
    ----------
    table : AbsorptionTable
    linelists : dict of str -> LineList
        The line lists the table was built from.
    temperatures : array_like, shape (n,)
        K, usually between the nodes.

    Returns
    -------
    ndarray, shape (n, n_species)
        max over η of |spline − direct| / direct (where direct > 0); 0 for species
        without lines.
    """
    step = grid_step(table.wavenumber)
    temperatures = np.atleast_1d(np.asarray(temperatures, dtype=np.float64))
    errors = np.zeros((temperatures.size, len(table.species)))
    for i, temperature in enumerate(temperatures):
        interpolated = table.spline(np.asarray(temperature))
        for j, name in enumerate(table.species):
            lines = linelists.get(name)
            if lines is None or len(lines) == 0:
                continue
            direct = cross_section(
                lines, table.wavenumber, temperature, table.pressure, table.self_fraction[j]
            )
            reference = smooth(direct, step)
            difference = np.abs(smooth(interpolated[j], step) - reference)
            covered = reference > 0
            errors[i, j] = np.max(difference[covered] / reference[covered])
    return errors
