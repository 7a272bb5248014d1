r"""Line parameters at a temperature and pressure: intensity, widths, shift.

All functions take a :class:`~invflame.spectroscopy.linelist.LineList` and return one value per
line. Reference conditions are those of HITRAN: :math:`T_\mathrm{ref}` = 296 K,
:math:`p_\mathrm{ref}` = 1 atm (Rothman et al. 1998, JQSRT 60, 665, appendix; HITRAN
"definitions and units", https://hitran.org/docs/definitions-and-units/).
"""

from __future__ import annotations

import numpy as np
from scipy import constants

from invflame.spectroscopy.isotopologues import molar_mass
from invflame.spectroscopy.linelist import LineList
from invflame.spectroscopy.partition import partition_function

T_REF = 296.0  # K
ATM = constants.atm  # Pa
#: Second radiation constant c₂ = hc/k_B in cm·K (CODATA).
C2 = 100.0 * constants.h * constants.c / constants.k


def _check_temperature(temperature: float) -> float:
    temperature = float(temperature)
    if not temperature > 0:
        raise ValueError(f"temperature must be positive (K), got {temperature}")
    return temperature


def line_intensity(lines: LineList, temperature: float) -> np.ndarray:
    r"""Line intensities :math:`S(T)` in cm/molecule.

    .. math:: S(T) = S(T_\mathrm{ref}) \frac{Q(T_\mathrm{ref})}{Q(T)}
              \frac{e^{-c_2 E''/T}}{e^{-c_2 E''/T_\mathrm{ref}}}
              \frac{1 - e^{-c_2 \nu/T}}{1 - e^{-c_2 \nu/T_\mathrm{ref}}}

    with TIPS partition functions :math:`Q` (:mod:`invflame.spectroscopy.partition`).

    Parameters
    ----------
    lines : LineList
    temperature : float
        Gas temperature in K.
    """
    temperature = _check_temperature(temperature)
    q_ratio = np.empty(len(lines))
    pairs = np.stack([lines.molecule, lines.isotopologue], axis=1)
    for molecule, isotopologue in np.unique(pairs, axis=0) if len(lines) else []:
        where = (lines.molecule == molecule) & (lines.isotopologue == isotopologue)
        q = partition_function(molecule, isotopologue, [T_REF, temperature])
        q_ratio[where] = q[0] / q[1]
    boltzmann = np.exp(-C2 * lines.E_lower * (1.0 / temperature - 1.0 / T_REF))
    stimulated = -np.expm1(-C2 * lines.nu / temperature) / -np.expm1(-C2 * lines.nu / T_REF)
    return lines.S296 * q_ratio * boltzmann * stimulated


def lorentz_hwhm(
    lines: LineList, temperature: float, pressure: float, self_pressure: float = 0.0
) -> np.ndarray:
    r"""Pressure-broadened (Lorentz) half width at half maximum in cm⁻¹.

    .. math:: \gamma_L = (T_\mathrm{ref}/T)^{n_\mathrm{air}}
              \left(\gamma_\mathrm{air} (p - p_\mathrm{self}) + \gamma_\mathrm{self}\,
              p_\mathrm{self}\right), \quad p \text{ in atm}

    The HITRAN record has no temperature exponent for self broadening; ``n_air`` is used for
    both, as HAPI does.

    Parameters
    ----------
    lines : LineList
    temperature : float
        K.
    pressure : float
        Total pressure in Pa.
    self_pressure : float
        Partial pressure of the absorbing gas in Pa, ``0 <= self_pressure <= pressure``.
    """
    temperature = _check_temperature(temperature)
    if not 0.0 <= self_pressure <= pressure:
        raise ValueError(
            f"need 0 <= self_pressure <= pressure (Pa), got {self_pressure} and {pressure}"
        )
    p_self, p_air = self_pressure / ATM, (pressure - self_pressure) / ATM
    scale = (T_REF / temperature) ** lines.n_air
    return scale * (lines.gamma_air * p_air + lines.gamma_self * p_self)


def pressure_shift(lines: LineList, pressure: float, self_pressure: float = 0.0) -> np.ndarray:
    r"""Pressure shift of the line positions in cm⁻¹.

    .. math:: \Delta\nu = \delta_\mathrm{air}\,(p - p_\mathrm{self}) +
              \delta_\mathrm{self}\, p_\mathrm{self}, \quad p \text{ in atm}

    each perturber's shift weighted by its partial pressure, as the widths are (HITRAN's
    convention for a mixture, as HAPI applies it: Kochanov et al. 2016, JQSRT 177, 15–30). The
    160-character HITRAN record holds no self shift, so :math:`\delta_\mathrm{self} = 0`: in
    a gas of self fraction x the air shift acts with the weight 1 − x.

    Parameters
    ----------
    lines : LineList
    pressure : float
        Total pressure in Pa.
    self_pressure : float
        Partial pressure of the absorbing gas in Pa, ``0 <= self_pressure <= pressure``.
    """
    if not 0.0 <= self_pressure <= pressure:
        raise ValueError(
            f"need 0 <= self_pressure <= pressure (Pa), got {self_pressure} and {pressure}"
        )
    return lines.delta_air * ((pressure - self_pressure) / ATM)


def doppler_hwhm(lines: LineList, temperature: float) -> np.ndarray:
    r"""Doppler (Gaussian) half width at half maximum in cm⁻¹.

    .. math:: \gamma_D = \frac{\nu}{c} \sqrt{\frac{2 \ln 2\, k_B T}{m}}

    with the isotopologue mass :math:`m` from the HITRAN isotopologue table
    (:mod:`invflame.spectroscopy.isotopologues`).

    Parameters
    ----------
    lines : LineList
    temperature : float
        K.
    """
    temperature = _check_temperature(temperature)
    mass = molar_mass(lines.molecule, lines.isotopologue) * 1e-3 / constants.N_A  # kg
    return lines.nu / constants.c * np.sqrt(2.0 * np.log(2.0) * constants.k * temperature / mass)
