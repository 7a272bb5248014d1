"""Isotopologue masses for the molecules of the flame window (H2O, CO2, CH4).

Molar masses (g/mol) and natural abundances from the HITRAN isotopologue table
("molparam.txt", https://hitran.org/docs/iso-meta/; Gordon et al. 2022, JQSRT 277, 107949).
HITRAN line intensities already include the natural abundance, so only the masses enter the
physics here (Doppler widths).
"""

from __future__ import annotations

import numpy as np

#: HITRAN molecule numbers of the species in the window.
MOLECULE_ID = {"H2O": 1, "CO2": 2, "CH4": 6}

#: (molecule, isotopologue) -> (formula, natural abundance, molar mass in g/mol)
ISOTOPOLOGUES: dict[tuple[int, int], tuple[str, float, float]] = {
    (1, 1): ("H2(16O)", 0.997317, 18.010565),
    (1, 2): ("H2(18O)", 0.00199983, 20.014811),
    (1, 3): ("H2(17O)", 0.000371884, 19.01478),
    (1, 4): ("HD(16O)", 0.000310693, 19.01674),
    (1, 5): ("HD(18O)", 6.23003e-07, 21.020985),
    (1, 6): ("HD(17O)", 1.15853e-07, 20.020956),
    (1, 7): ("D2(16O)", 2.41974e-08, 20.022915),
    (2, 1): ("(12C)(16O)2", 0.984204, 43.98983),
    (2, 2): ("(13C)(16O)2", 0.0110574, 44.993185),
    (2, 3): ("(16O)(12C)(18O)", 0.00394707, 45.994076),
    (2, 4): ("(16O)(12C)(17O)", 0.000733989, 44.994045),
    (2, 5): ("(16O)(13C)(18O)", 4.43446e-05, 46.997431),
    (2, 6): ("(16O)(13C)(17O)", 8.24623e-06, 45.9974),
    (2, 7): ("(12C)(18O)2", 3.95734e-06, 47.99832),
    (2, 8): ("(17O)(12C)(18O)", 1.4718e-06, 46.998291),
    (2, 9): ("(12C)(17O)2", 1.36847e-07, 45.998262),
    (2, 10): ("(13C)(18O)2", 4.446e-08, 49.001675),
    (2, 11): ("(18O)(13C)(17O)", 1.65354e-08, 48.001646),
    (2, 12): ("(13C)(17O)2", 1.53745e-09, 47.001618),
    (6, 1): ("(12C)H4", 0.988274, 16.0313),
    (6, 2): ("(13C)H4", 0.0111031, 17.034655),
    (6, 3): ("(12C)H3D", 0.000615751, 17.037475),
    (6, 4): ("(13C)H3D", 6.91785e-06, 18.04083),
}


def molar_mass(molecule, isotopologue) -> np.ndarray:
    """Molar mass of each (molecule, isotopologue) pair, g/mol.

    Parameters
    ----------
    molecule, isotopologue : array_like of int
        HITRAN molecule and isotopologue numbers (broadcast together).

    Raises
    ------
    KeyError
        For a pair not in :data:`ISOTOPOLOGUES`.
    """
    molecule, isotopologue = np.broadcast_arrays(np.asarray(molecule), np.asarray(isotopologue))
    pairs = set(zip(molecule.ravel().tolist(), isotopologue.ravel().tolist(), strict=True))
    missing = sorted(pairs - ISOTOPOLOGUES.keys())
    if missing:
        raise KeyError(
            f"no molar mass for (molecule, isotopologue) {missing}; known: H2O, CO2, CH4 "
            "isotopologues of the HITRAN table (add them to ISOTOPOLOGUES)"
        )
    out = np.empty(molecule.shape, dtype=np.float64)
    for pair in pairs:
        out[(molecule == pair[0]) & (isotopologue == pair[1])] = ISOTOPOLOGUES[pair][2]
    return out
