r"""Planck's law per unit wavenumber (NumPy).

.. math:: B_\eta(T) = \frac{2 h c^2 \tilde\eta^3}{\exp(h c \tilde\eta / k_B T) - 1},
          \qquad \tilde\eta = 100\,\eta \ \text{m}^{-1}

in W/(m²·sr·m⁻¹), times 100 to give W/(m²·sr·cm⁻¹). CODATA constants from
:mod:`scipy.constants`.
"""

from __future__ import annotations

import numpy as np
from scipy import constants

#: First radiation constant for radiance, 2hc², in W·m²/sr.
C1L = 2.0 * constants.h * constants.c**2
#: Second radiation constant hc/k_B in m·K.
C2_SI = constants.h * constants.c / constants.k


def planck(wavenumber, temperature) -> np.ndarray:
    """Blackbody spectral radiance, W/(m²·sr·cm⁻¹).

    Parameters
    ----------
    wavenumber : array_like
        Wavenumbers in cm⁻¹ (> 0).
    temperature : array_like
        Temperatures in K (> 0), broadcast against ``wavenumber``.

    Returns
    -------
    ndarray, the broadcast shape of the arguments
    """
    eta = 100.0 * np.asarray(wavenumber, dtype=np.float64)  # m⁻¹
    temperature = np.asarray(temperature, dtype=np.float64)
    if np.any(eta <= 0) or np.any(temperature <= 0):
        raise ValueError("planck needs positive wavenumbers (cm-1) and temperatures (K)")
    return 100.0 * C1L * eta**3 / np.expm1(C2_SI * eta / temperature)
