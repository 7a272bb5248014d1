"""Molecular spectroscopy of the 650–725 cm⁻¹ window: line lists, line shapes, absorption tables.

* :mod:`.linelist` — :class:`LineList`, HITRAN 160-character ``.par`` reader and writer
* :mod:`.hitran` — :func:`fetch_hitran` (online, via HAPI)
* :mod:`.partition`, :mod:`.isotopologues` — TIPS partition sums, isotopologue masses
* :mod:`.line_parameters` — S(T), Lorentz and Doppler widths, pressure shift
* :mod:`.cross_section` — bin-averaged Voigt cross-sections on a uniform grid
* :mod:`.absorption_table` — :class:`AbsorptionTable` σ(η, T, X_self) on its nodes
* :mod:`.absorption_coefficient` — σ, κ and Planck-mean κ of a gas state from the table
* :mod:`.spectral_points` — sub-bins where lines saturate inside a bin
* :mod:`.table_inputs`, :mod:`.table_files` — what a table is built from, its cached file
* :mod:`.planck` — Planck's law per wavenumber
"""

from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.cross_section import cross_section, default_wavenumber
from invflame.spectroscopy.hitran import fetch_hitran
from invflame.spectroscopy.linelist import LineList, read_par, write_par
from operators.rte.planck import planck

__all__ = [
    "AbsorptionTable",
    "LineList",
    "cross_section",
    "default_wavenumber",
    "fetch_hitran",
    "planck",
    "read_par",
    "write_par",
]
