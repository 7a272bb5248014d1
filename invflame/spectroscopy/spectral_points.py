r"""Sub-bins where a bin's transmission is not the exponential of its mean optical depth.

An absorption table's bins (0.04 cm⁻¹ by default) are wider than flame lines at 1 atm (Lorentz
half widths 0.01–0.03 cm⁻¹ at 1000–2000 K). Where a bin holds a partly saturated line core, its
mean transmission :math:`\overline{e^{-\tau}}` exceeds :math:`e^{-\bar\tau}` (Jensen's
inequality): one optical depth per bin overstates the emission, by up to 12 % in single
1 cm⁻¹ windows of the CO2 Q branches at 2000 K (``studies/validate_forward.py --split``).

So the table splits such bins into ``m`` = 2, 4 or 8 equal sub-bins, the *spectral points*,
each with its own mean cross-section; the kernel solves the transfer at every point and the
radiance of a bin is the mean over its points (:class:`operators.rte.tables.RTETables`).
Which bins, and into how many, is planned once per table (:func:`plan_points`), from the
cross-sections on the finest sub-bins and a set of reference columns of gas (homogeneous slabs,
:data:`REFERENCES`): for each reference and bin ``k`` the error of ``m`` points against the
finest ones, :math:`e_k(m) = B_k |\bar t_m - \bar t_8|`; in every window of about 1 cm⁻¹ the
fewest points that keep the window's summed error below :data:`BUDGET` times its emission
(per bin the ``m`` minimizing :math:`e_k(m) + \lambda m`, with per window the largest
:math:`\lambda` that meets the budget); over the references, the most points any asks for.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy import constants

from operators.rte.blocks import interpolate_fraction
from operators.rte.planck import planck

#: Most sub-bins per bin (a power of two): 0.005 cm⁻¹ at the default 0.04 cm⁻¹ bins.
MAX_POINTS_PER_BIN = 8
#: The summed error allowed in each window, relative to the window's emission.
BUDGET = 4e-3
#: Width of the windows the budget holds in, cm⁻¹.
WINDOW = 1.0
#: Reference columns of flame gas the plan keeps accurate: temperature (K, the nearest table
#: node is taken), mole fractions and path length (m), every combination.
REFERENCES = [
    {"T": t, "CO2": co2, "H2O": h2o, "length": length}
    for t, (co2, h2o), length in itertools.product(
        (800.0, 1200.0, 1600.0, 2000.0, 2400.0),
        ((0.03, 0.02), (0.1, 0.12), (0.1, 0.25)),
        (0.2, 1.0),
    )
]


def fine_grid(wavenumber, subdivision: int) -> np.ndarray:
    """Centres of ``subdivision`` equal sub-bins of every bin of a uniform grid, cm⁻¹."""
    wavenumber = np.asarray(wavenumber, dtype=np.float64)
    step = (wavenumber[-1] - wavenumber[0]) / (wavenumber.size - 1)
    offsets = ((np.arange(subdivision) + 0.5) / subdivision - 0.5) * step
    return (wavenumber[:, None] + offsets[None, :]).ravel()


def point_starts(points_per_bin, subdivision: int) -> np.ndarray:
    """Index of the first fine sub-bin of every point (:func:`fine_grid` order)."""
    points_per_bin = np.asarray(points_per_bin)
    bin_of_point = np.repeat(np.arange(points_per_bin.size), points_per_bin)
    first = np.cumsum(points_per_bin) - points_per_bin
    within = np.arange(bin_of_point.size) - first[bin_of_point]
    return bin_of_point * subdivision + within * (subdivision // points_per_bin[bin_of_point])


def points_of(fine, points_per_bin, subdivision: int) -> np.ndarray:
    """Means of fine sub-bin values over each point, along the last axis.

    Parameters
    ----------
    fine : ndarray, shape (..., n_bins * subdivision)
        Values on :func:`fine_grid`.
    points_per_bin : array of int, shape (n_bins,)
        Divisors of ``subdivision``.
    subdivision : int
    """
    points_per_bin = np.asarray(points_per_bin)
    width = np.repeat(subdivision // points_per_bin, points_per_bin)
    return np.add.reduceat(fine, point_starts(points_per_bin, subdivision), axis=-1) / width


def plan_points(wavenumber, temperatures, fine_sigma, species, fraction_nodes,
                pressure: float, budget: float = BUDGET, references=None) -> np.ndarray:
    """Points per bin (module notes): 1, 2, 4, … up to the fine subdivision.

    Parameters
    ----------
    wavenumber : ndarray, shape (n_bins,)
        Uniform bin centres, cm⁻¹.
    temperatures : ndarray, shape (n_T,)
        Table nodes, K.
    fine_sigma : ndarray, shape (n_T, n_columns, n_bins * subdivision)
        Cross-sections on the finest sub-bins, cm²/molecule, one column per species and
        fraction node (species-major).
    species : tuple of str
        Names of the table's species, in column order.
    fraction_nodes : tuple of tuple of float
        Self-fraction nodes per species.
    pressure : float
        Pa.
    budget : float, optional
        Summed error allowed per window, relative to its emission (default :data:`BUDGET`).
    references : list of dict, optional
        Reference columns (default :data:`REFERENCES`); mole fractions of species the table
        does not hold are ignored.

    Returns
    -------
    ndarray of int, shape (n_bins,)
    """
    wavenumber = np.asarray(wavenumber, dtype=np.float64)
    n_bins = wavenumber.size
    subdivision = fine_sigma.shape[-1] // n_bins
    levels = 2 ** np.arange(int(np.log2(subdivision)) + 1)
    step = (wavenumber[-1] - wavenumber[0]) / (n_bins - 1)
    window = np.arange(n_bins) // max(1, int(round(WINDOW / step)))
    first = np.cumsum([0, *map(len, fraction_nodes)])
    chosen = np.ones(n_bins, dtype=int)
    for reference in REFERENCES if references is None else references:
        node = int(np.argmin(np.abs(temperatures - reference["T"])))
        temperature = temperatures[node]
        density = pressure / (constants.k * temperature) * 1e-4  # molecules/m³ · m²/cm²
        tau = np.zeros(fine_sigma.shape[-1])
        for s, name in enumerate(species):
            x = float(reference.get(name, 0.0))
            own = fine_sigma[node, first[s]:first[s + 1]]
            if x == 0.0 or not own.any():
                continue
            own = interpolate_fraction(own, fraction_nodes[s], x)
            tau += x * density * own * reference["length"]
        tau = tau.reshape(n_bins, subdivision)
        transmission = np.stack([np.exp(-tau.reshape(n_bins, m, -1).mean(-1)).mean(-1)
                                 for m in levels], axis=-1)  # (n_bins, levels)
        radiance = planck(wavenumber, temperature)
        error = radiance[:, None] * np.abs(transmission - transmission[:, -1:])
        allowed = budget * np.bincount(window, radiance * (1 - transmission[:, -1]))
        chosen = np.maximum(chosen, _fewest_points(error, levels, window, allowed))
    return chosen


def _fewest_points(error, levels, window, allowed):
    """Per bin the level minimizing ``error + λ·level``, with λ per window the largest of a
    geometric ladder whose summed error stays within ``allowed``."""
    scale = np.maximum(allowed, np.finfo(float).tiny)[:, None] * np.logspace(1, -10, 56)
    cost = error[:, None, :] + scale[window][:, :, None] * levels  # (bins, ladder, levels)
    pick = np.argmin(cost, axis=-1)
    spent = np.take_along_axis(error, pick, axis=-1)  # (bins, ladder)
    within = np.stack([np.bincount(window, column) for column in spent.T], -1) \
        <= allowed[:, None] * (1 + 1e-12)
    rung = np.argmax(within, axis=-1)  # first (largest λ) that meets the budget
    rung = np.where(within.any(axis=-1), rung, within.shape[-1] - 1)
    return levels[pick[np.arange(window.size), rung[window]]]
