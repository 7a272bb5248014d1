"""Line lists from HITRANonline (needs internet; tests replace it with local files)."""

from __future__ import annotations

import contextlib
import io
import tempfile
from pathlib import Path

from invflame.spectroscopy.isotopologues import MOLECULE_ID
from invflame.spectroscopy.linelist import LineList, read_par
from invflame.spectroscopy.partition import hapi_module


def fetch_hitran(
    molecule: str, nu_min: float, nu_max: float, isotopologues=(1,)
) -> LineList:
    """Download HITRAN lines with HAPI's ``fetch`` (Kochanov et al. 2016, JQSRT 177, 15).

    Parameters
    ----------
    molecule : str
        ``"H2O"``, ``"CO2"`` or ``"CH4"``.
    nu_min, nu_max : float
        Wavenumber window in cm⁻¹.
    isotopologues : sequence of int
        HITRAN local isotopologue numbers (default: the main one).

    Returns
    -------
    LineList
        The lines of all requested isotopologues, read from the 160-character records HAPI
        writes (in a temporary folder, removed afterwards).

    Raises
    ------
    ValueError
        For an unknown molecule or an empty window. HAPI's own errors (no connection, no
        lines) propagate.
    """
    if molecule not in MOLECULE_ID:
        raise ValueError(f"unknown molecule {molecule!r}; choose one of {sorted(MOLECULE_ID)}")
    if not nu_min < nu_max:
        raise ValueError(f"need nu_min < nu_max (cm-1), got {nu_min} and {nu_max}")
    hapi = hapi_module()
    parts = []
    with tempfile.TemporaryDirectory() as folder, contextlib.redirect_stdout(io.StringIO()):
        hapi.db_begin(folder)
        for isotopologue in isotopologues:
            table = f"{molecule}_{isotopologue}"
            hapi.fetch(table, MOLECULE_ID[molecule], int(isotopologue), nu_min, nu_max)
            parts.append(read_par(Path(folder) / f"{table}.data"))
    return LineList.concatenate(parts)
