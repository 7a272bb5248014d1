r"""The absorption of a gas state from tabulated cross-sections: each species' cross-section,
the absorption coefficient κ and its Planck mean.

.. math:: \kappa(\eta) = \sum_s X_s\, N\, \sigma_s(\eta, T, X_s) \cdot 10^{-4},
          \qquad N = \frac{p}{k_B T}\ [\mathrm{m}^{-3}],

in m⁻¹ (the factor converts cm² to m²), with :math:`\sigma_s` (cm²/molecule) from the cubic
spline in T through the temperature nodes and linear interpolation in the species' own mole
fraction :math:`X_s` between its fraction nodes (:class:`~invflame.spectroscopy.AbsorptionTable`).
"""

from __future__ import annotations

import numpy as np
from scipy import constants

from operators.rte.blocks import interpolate_fraction
from operators.rte.planck import planck


class AbsorptionCoefficient:
    """Cross-sections, κ and Planck-mean κ of gas states, evaluated from a table's nodes.

    A base of :class:`~invflame.spectroscopy.AbsorptionTable`, whose attributes it reads:
    ``species``, ``wavenumber`` (cm⁻¹), ``pressure`` (Pa), ``temperatures`` (K),
    ``self_fraction``, the T ``spline`` of the cross-sections, ``columns`` and
    ``bin_average``.
    """

    def _check_state(self, temperature, mole_fractions, pressure):
        temperature = np.asarray(temperature, dtype=np.float64)
        mole_fractions = np.asarray(mole_fractions, dtype=np.float64)
        lo, hi = self.temperatures[[0, -1]]
        if np.any(temperature < lo) or np.any(temperature > hi) or np.isnan(temperature).any():
            raise ValueError(
                f"temperature outside the table range {lo:g}-{hi:g} K: "
                f"got {np.nanmin(temperature):g}-{np.nanmax(temperature):g} K"
            )
        if mole_fractions.shape != (len(self.species),) + temperature.shape:
            raise ValueError(
                f"mole fractions must have shape (n_species,) + T.shape = "
                f"{(len(self.species),) + temperature.shape} (species {self.species}), "
                f"got {mole_fractions.shape}"
            )
        pressure = self.pressure if pressure is None else float(pressure)
        if abs(pressure / self.pressure - 1.0) > 0.01:
            raise ValueError(
                f"the table was broadened at {self.pressure:g} Pa, asked for {pressure:g} Pa: "
                "build a table at that pressure"
            )
        return temperature, mole_fractions, pressure

    def cross_sections(self, temperature, mole_fractions) -> np.ndarray:
        """Cross-sections of each species in cm²/molecule, shape ``s + (n_species, n_eta)``:
        the T spline, and linear interpolation in each species' own mole fraction between
        its fraction nodes. Arguments as :meth:`kappa`."""
        temperature, mole_fractions, _ = self._check_state(temperature, mole_fractions, None)
        columns = self.spline(temperature)  # s + (n_columns, n_eta)
        sigma = np.empty(temperature.shape + (len(self.species), self.wavenumber.size))
        for j, nodes in enumerate(self.self_fraction):
            own = self.bin_average(columns[..., self.columns(j), :])
            sigma[..., j, :] = interpolate_fraction(own, nodes, mole_fractions[j])
        return sigma

    def kappa(self, temperature, mole_fractions, pressure: float | None = None) -> np.ndarray:
        """Absorption coefficient κ_η in m⁻¹.

        Parameters
        ----------
        temperature : array_like, shape s
            K, inside the table's node range.
        mole_fractions : array_like, shape (n_species,) + s
            Mole fractions in the order of the table's ``species`` (species-first, like the
            field arrays).
        pressure : float, optional
            Pa; defaults to, and must be within 1 % of, the table's pressure (the line shapes
            are those of the table's pressure).

        Returns
        -------
        ndarray, shape s + (n_eta,)
        """
        temperature, mole_fractions, pressure = self._check_state(
            temperature, mole_fractions, pressure
        )
        number_density = pressure / (constants.k * temperature)  # m⁻³
        sigma = self.cross_sections(temperature, mole_fractions)  # s + (n_species, n_eta), cm²
        x = np.moveaxis(mole_fractions, 0, -1)[..., None]  # s + (n_species, 1)
        return 1e-4 * number_density[..., None] * np.sum(x * sigma, axis=-2)

    def planck_mean_kappa(
        self, temperature, mole_fractions, pressure: float | None = None
    ) -> np.ndarray:
        r"""Planck-mean absorption coefficient over the table's window, m⁻¹.

        :math:`\bar\kappa = \int B_\eta(T)\, \kappa_\eta\, d\eta / \int B_\eta(T)\,
        d\eta` over the grid (a uniform grid, so sums replace the integrals). Arguments as
        :meth:`kappa`; returns shape s.
        """
        kappa = self.kappa(temperature, mole_fractions, pressure)
        b = planck(self.wavenumber, np.asarray(temperature, dtype=np.float64)[..., None])
        return np.sum(b * kappa, axis=-1) / np.sum(b, axis=-1)
