"""Gas composition: molar masses, mass → mole fractions, and methane–air flame states.

Methane burns in air by the global step (Turns, *An Introduction to Combustion*, 3rd ed., 2012,
eq. 2.30 with x = 1, y = 4; air = O2 + 3.76 N2)::

    CH4 + 2 (O2 + 3.76 N2) → CO2 + 2 H2O + 7.52 N2

:func:`burke_schumann_methane` gives the state of complete, infinitely fast combustion as a
function of the mixture fraction Z (Burke & Schumann 1928; Poinsot & Veynante, *Theoretical and
Numerical Combustion*, 2005, sec. 3.2.5), the limit the OpenFOAM case's
``irreversibleinfiniteReaction`` also takes.
"""

from __future__ import annotations

import numpy as np

MOLAR_MASS = {
    "CH4": 16.0428,
    "O2": 31.9988,
    "N2": 28.0134,
    "CO2": 44.0095,
    "H2O": 18.0153,
    "CO": 28.0101,
    "H2": 2.01588,
    "Ar": 39.948,
    "C3H8": 44.0956,
}
"""Molar masses in g/mol (IUPAC 2013 standard atomic weights)."""

AIR_O2_MOLE_FRACTION = 1.0 / 4.76
"""O2 mole fraction of air as the reaction above takes it (O2 + 3.76 N2)."""


def mass_to_mole_fractions(mass_fractions: dict, molar_masses: dict) -> dict:
    """Mole fractions ``X_i = (Y_i / W_i) / Σ_j (Y_j / W_j)`` over all given species.

    Parameters
    ----------
    mass_fractions : dict of str to array_like
        Mass fraction ``Y_i`` [1] of every species of the mixture (same shapes); values are
        clipped to [0, 1] first (solvers leave round-off undershoots).
    molar_masses : dict of str to float
        ``W_i`` in g/mol for every key of ``mass_fractions``.

    Returns
    -------
    dict of str to numpy.ndarray
        ``X_i`` [1], float64, summing to 1.
    """
    missing = set(mass_fractions) - set(molar_masses)
    if missing:
        raise KeyError(f"no molar mass for species {sorted(missing)}; pass them in g/mol")
    moles = {
        s: np.clip(np.asarray(y, dtype=np.float64), 0.0, 1.0) / molar_masses[s]
        for s, y in mass_fractions.items()
    }
    total = sum(moles.values())
    if np.any(total <= 0):
        raise ValueError("all mass fractions are zero somewhere; the mixture is undefined")
    return {s: n / total for s, n in moles.items()}


def _stoichiometric_fuel_mass_fraction() -> float:
    w = MOLAR_MASS
    reactants = w["CH4"] + 2 * w["O2"] + 7.52 * w["N2"]
    return w["CH4"] / reactants


Z_STOICHIOMETRIC = _stoichiometric_fuel_mass_fraction()
"""Stoichiometric mixture fraction of methane–air, ≈ 0.0552."""


def burke_schumann_methane(mixture_fraction, temperature_rise_st: float, ambient: float):
    """Temperature and mass fractions of methane–air burnt completely at mixture fraction Z.

    Lean side (``Z ≤ Z_st``): air plus the products of all the fuel; rich side: fuel plus the
    products of all the oxygen. The temperature rise is piecewise linear in Z, peaking at
    ``Z_st`` (constant heat capacity; fuel and air enter at ``ambient``).

    Parameters
    ----------
    mixture_fraction : array_like
        Z [1], the mass fraction of matter that came from the fuel stream, in [0, 1].
    temperature_rise_st : float
        Temperature rise at ``Z_st`` in K (adiabatic ≈ 1950 K; less with radiative loss).
    ambient : float
        Temperature of fuel and air in K.

    Returns
    -------
    temperature : numpy.ndarray
        T in K.
    mass_fractions : dict of str to numpy.ndarray
        ``Y`` of CH4, O2, CO2, H2O, N2 [1], summing to 1.
    """
    z = np.clip(np.asarray(mixture_fraction, dtype=np.float64), 0.0, 1.0)
    w = MOLAR_MASS
    z_st = Z_STOICHIOMETRIC
    air_o2 = AIR_O2_MOLE_FRACTION * w["O2"]
    y_o2_air = air_o2 / (air_o2 + (1 - AIR_O2_MOLE_FRACTION) * w["N2"])
    burnt_fuel = np.minimum(z, z_st * (1 - z) / (1 - z_st))  # fuel mass consumed per unit mass
    y = {
        "CH4": z - burnt_fuel,
        "O2": y_o2_air * (1 - z) - burnt_fuel * 2 * w["O2"] / w["CH4"],
        "CO2": burnt_fuel * w["CO2"] / w["CH4"],
        "H2O": burnt_fuel * 2 * w["H2O"] / w["CH4"],
        "N2": (1 - y_o2_air) * (1 - z),
    }
    y["O2"] = np.clip(y["O2"], 0.0, None)  # zero on the rich side, up to round-off
    temperature = ambient + temperature_rise_st * burnt_fuel / z_st
    return temperature, y
