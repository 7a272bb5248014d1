"""Measured spectra and their noise: what the data term of a reconstruction compares against.

A :class:`Measurement` comes from a simulation (:mod:`invflame.experiments.measurement`) or
from a measurement file (:mod:`invflame.measurement_file`); either way it is the spectra per
pixel, their noise standard deviation and how they were made.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Measurement:
    """Measured spectra and their noise.

    Attributes
    ----------
    data : ndarray, shape (n_rays, n_out)
        Spectra per pixel in W/(m²·sr·cm⁻¹) (0 where masked).
    sigma : ndarray, shape (n_out,) or (n_rays, n_out)
        Noise standard deviation per output wavenumber, or per value, in W/(m²·sr·cm⁻¹)
        (ones for noise-free data, so that a whitened misfit is the plain sum of squares);
        ``inf`` for a masked value (a bad pixel or wavenumber: weight 0 in the data term, see
        :mod:`invflame.measurement_file`).
    noisy : bool
        Whether noise was added (False: ``sigma`` carries no information).
    provenance : dict
        How the data were made (grid, sub-rays, step, noise).
    """

    data: np.ndarray
    sigma: np.ndarray
    noisy: bool
    provenance: dict

    @property
    def n_measurements(self) -> int:
        """Number of measured values M (pixels × output wavenumbers), masked ones left out."""
        return int(np.count_nonzero(np.isfinite(np.broadcast_to(self.sigma, self.data.shape))))
