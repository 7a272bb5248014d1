r"""Planck's law per unit wavenumber, exact and as a temperature spline per wavenumber.

Spectral radiance of a black body per unit wavenumber :math:`\eta` (cm⁻¹),

.. math:: B_\eta(T) = \frac{c_1 \eta^3}{\exp(c_2 \eta / T) - 1},
          \qquad c_1 = 2 h c^2 \cdot 10^8, \qquad c_2 = \frac{h c}{k_B} \cdot 10^2,

in W/(m²·sr·cm⁻¹), with the exact SI constants :math:`h, c, k_B` (CODATA 2018 / SI 2019).
The factors :math:`10^8` and :math:`10^2` convert the wavenumber from m⁻¹ to cm⁻¹ and the
radiance from per m⁻¹ to per cm⁻¹: :math:`c_1 = 1.191042972\ldots\times10^{-8}`
W·cm⁴/(m²·sr), :math:`c_2 = 1.438776877\ldots` cm·K.

:func:`planck_table` fits a cubic spline in :math:`T` per wavenumber on nodes refined until it
matches the exact law to a relative tolerance, so that a radiative-transfer kernel can evaluate
:math:`B` with the same gathered coefficients and the same polynomial as the absorption
cross-sections instead of one more exponential per spectral point.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from scipy.interpolate import CubicSpline

PLANCK = 6.62607015e-34
"""Planck constant :math:`h` in J·s (exact, SI 2019)."""
SPEED_OF_LIGHT = 299792458.0
"""Speed of light :math:`c` in m/s (exact)."""
BOLTZMANN = 1.380649e-23
"""Boltzmann constant :math:`k_B` in J/K (exact, SI 2019)."""
C1 = 2.0 * PLANCK * SPEED_OF_LIGHT**2 * 1e8
r"""First radiation constant for radiance per cm⁻¹, :math:`2hc^2 \cdot 10^8` in W·cm⁴/(m²·sr)."""
C2 = PLANCK * SPEED_OF_LIGHT / BOLTZMANN * 1e2
"""Second radiation constant :math:`hc/k_B` in cm·K."""


def planck(wavenumber, temperature):
    r"""Black-body spectral radiance :math:`B_\eta(T)` in W/(m²·sr·cm⁻¹).

    Parameters
    ----------
    wavenumber : array_like
        Wavenumber :math:`\eta` in cm⁻¹.
    temperature : array_like
        Temperature in K (positive), broadcast against ``wavenumber``.

    Returns
    -------
    array
        NumPy for NumPy inputs, JAX (jit- and grad-compatible) when either input is a JAX
        array.

    Raises
    ------
    ValueError
        For NumPy inputs with a non-positive wavenumber or temperature (JAX inputs are not
        checked, so that the function stays traceable).
    """
    if isinstance(wavenumber, jax.Array) or isinstance(temperature, jax.Array):
        return C1 * wavenumber**3 / jnp.expm1(C2 * wavenumber / temperature)
    wavenumber = np.asarray(wavenumber, dtype=np.float64)
    temperature = np.asarray(temperature, dtype=np.float64)
    if np.any(wavenumber <= 0) or np.any(temperature <= 0):
        raise ValueError("planck needs positive wavenumbers (cm-1) and temperatures (K)")
    return C1 * wavenumber**3 / np.expm1(C2 * wavenumber / temperature)


def planck_table(wavenumber, nodes, rtol: float = 1e-7, max_refinements: int = 12):
    r"""Nodes and cubic-spline coefficients of :math:`B_\eta(T)` for every wavenumber.

    Starting from ``nodes``, every interval where the spline (not-a-knot) misses the exact
    law by more than ``rtol`` (relative, checked at the interval's quarter points) is split in
    two, and the spline refitted, until no interval misses. The returned nodes always contain
    the given ones, so another piecewise cubic on ``nodes`` stays a cubic on each refined
    interval.

    Parameters
    ----------
    wavenumber : array_like, shape (n_eta,)
        Wavenumbers in cm⁻¹.
    nodes : array_like, shape (n,)
        Initial temperature nodes in K, strictly increasing, positive.
    rtol : float, optional
        Relative accuracy to reach between the first and last node (default 1e-7).
    max_refinements : int, optional
        Most rounds of splitting before giving up with an error.

    Returns
    -------
    nodes : ndarray, shape (m,)
        Refined temperature nodes in K.
    coef : ndarray, shape (4, m - 1, n_eta)
        Coefficients :math:`c_j` of :math:`B = \sum_j c_j (T - T_i)^{3-j}` on interval
        :math:`i`, in W/(m²·sr·cm⁻¹)/K^(3-j).
    """
    wavenumber = np.asarray(wavenumber, dtype=np.float64)
    nodes = np.asarray(nodes, dtype=np.float64)
    if nodes.ndim != 1 or nodes.size < 2 or np.any(np.diff(nodes) <= 0) or nodes[0] <= 0:
        raise ValueError("nodes must be at least 2 strictly increasing positive temperatures (K)")
    for _ in range(max_refinements):
        spline = CubicSpline(nodes, planck(wavenumber[None, :], nodes[:, None]), axis=0)
        quarters = nodes[:-1, None] + np.diff(nodes)[:, None] * np.array([0.25, 0.5, 0.75])
        exact = planck(wavenumber[None, None, :], quarters[..., None])
        error = np.abs(spline(quarters) / exact - 1.0).max(axis=(1, 2))
        bad = error > rtol
        if not bad.any():
            return nodes, spline.c
        nodes = np.sort(np.concatenate([nodes, 0.5 * (nodes[:-1] + nodes[1:])[bad]]))
    raise RuntimeError(
        f"the Planck spline did not reach rtol={rtol:g} in {max_refinements} refinements; "
        "raise rtol or start from finer nodes"
    )
