r"""A line-by-line reference for the emission of hot gas layers, computed with HAPI.

The cross-sections come from the HITRAN Application Programming Interface (HAPI, Kochanov et
al. 2016, JQSRT 177, 15–30; the ``hitran-api`` package) reading the same HITRAN line records
as invflame: the packaged H2O lines (HITRAN2012, 600–800 cm⁻¹) and the generated ¹²C¹⁶O₂ list
(:func:`invflame.spectroscopy.co2_lines.generate_co2_lines`), written as 160-character records.
Nothing else of invflame enters: line shapes, intensities, the formal solution of the radiative
transfer equation and Planck's law are computed here. Nothing is downloaded (no ``hapi.fetch``).

**Cross-sections.** ``hapi.absorptionCoefficient_Voigt`` in cm²/molecule (``HITRAN_units``) at
temperature :math:`T` (K) and 1 atm, with the diluent ``{'self': x, 'air': 1 - x}`` for a gas of
mole fraction :math:`x`: HAPI weights the widths *and* the pressure shifts by the diluent
fractions, so the air shift is applied at the air fraction :math:`1 - x` (HITRAN records hold no
self shift). Each line is cut 25 cm⁻¹ from its centre (``WavenumberWing`` = 25 and
``WavenumberWingHW`` = 0: HAPI takes the larger of the two). The profile is sampled on a fine
uniform grid of step 0.0025 cm⁻¹: every line-by-line bin :math:`[c - 0.02, c + 0.02]`
(:math:`c = 650 + 0.04 k` cm⁻¹, :math:`k = 0 \ldots 1875`) holds the 16 points
:math:`c - 0.02 + (j + \tfrac12)\, 0.0025`, :math:`j = 0 \ldots 15`. The line tables span
600–800 cm⁻¹, so lines up to 25 cm⁻¹ outside 650–725 cm⁻¹ contribute their wings. HAPI is
slow (about 12 s for one CO2 state, 1 s for H2O): each cross-section is kept in a disk cache,
``$INVFLAME_CACHE/hapi`` (default ``~/.cache/invflame/hapi``).

**Radiance.** Layers nearest the camera first, each :math:`(T_k, X_{CO_2}, X_{H_2O}, L_k)`, in
front of a cold background:

.. math::

    I(\eta) = \sum_k B_\eta(T_k)\,(1 - t_k) \prod_{j<k} t_j, \qquad
    t_k = e^{-\kappa_k L_k}, \qquad
    \kappa_k = \sum_s X_s\, N_k\, \sigma_s(\eta, T_k, X_s) \cdot 10^{-4}\ \mathrm{m^{-1}},
    \qquad N_k = p/(k_B T_k)\ \mathrm{m^{-3}},

evaluated on the fine grid and averaged over each 0.04 cm⁻¹ bin (the mean of the radiance, so
of the transmission, not of the optical depth).

Planck's law per unit wavenumber :math:`\tilde\nu` in m⁻¹ is
:math:`B_{\tilde\nu} = 2hc^2\tilde\nu^3 / (e^{hc\tilde\nu/k_BT} - 1)` in W/(m²·sr·m⁻¹). With
:math:`\eta` in cm⁻¹, :math:`\tilde\nu = 100\,\eta`, and an interval of 1 cm⁻¹ is 100 m⁻¹, so
:math:`B_\eta = 100\, B_{\tilde\nu}(100\,\eta)` in W/(m²·sr·cm⁻¹).

Run ``python studies/hapi_reference.py`` to compare the HAPI cross-sections with invflame's
line-by-line code (:func:`invflame.spectroscopy.cross_section.cross_section`) on the fine grid,
for one H2O and one CO2 state, with invflame's pressure shift and with either convention for
the shift in a mixture (:func:`compare_cross_sections`).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import functools
import hashlib
import io
import json
import os
import sys
import tempfile
import time
from importlib import resources
from pathlib import Path

import numpy as np
from scipy import constants

from operators.disk_cache import cache_dir

#: Line-by-line bins of invflame: centres 650 + 0.04 k cm⁻¹, k = 0 … 1875.
BIN_FIRST = 650.0
BIN_STEP = 0.04
N_BINS = 1876
#: Fine points per bin and their step (cm⁻¹).
SUBSAMPLES = 16
FINE_STEP = BIN_STEP / SUBSAMPLES
#: Line cutoff from the line centre, cm⁻¹.
WING = 25.0
#: Total pressure, Pa (1 atm).
PRESSURE = constants.atm
#: HAPI table names of the species.
TABLES = {"H2O": "H2O_HITRAN2012", "CO2": "CO2_generated"}
#: Bump when the computation changes: cached cross-sections then recompute.
REFERENCE_VERSION = "1"


def _hapi():
    """The ``hapi`` module, imported without its banner on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        import hapi
    return hapi


def bin_centres() -> np.ndarray:
    """Centres of invflame's line-by-line bins, shape (1876,), cm⁻¹."""
    return BIN_FIRST + BIN_STEP * np.arange(N_BINS)


def fine_grid() -> np.ndarray:
    """The fine grid, shape (1876 · 16,), cm⁻¹: 16 points at the centres of equal sub-bins of
    each line-by-line bin, bin by bin."""
    offsets = (np.arange(SUBSAMPLES) + 0.5) * FINE_STEP - BIN_STEP / 2
    return (bin_centres()[:, None] + offsets).ravel()


def bin_average(values) -> np.ndarray:
    """Mean over each line-by-line bin of values on :func:`fine_grid`, shape (..., 1876)."""
    values = np.asarray(values)
    return values.reshape(*values.shape[:-1], N_BINS, SUBSAMPLES).mean(axis=-1)


def reference_dir() -> Path:
    """Folder of the HAPI tables and cached cross-sections: ``<cache_dir()>/hapi``."""
    return cache_dir() / "hapi"


def _records(species: str) -> str:
    """The 160-character HITRAN records of a species' lines, 600–800 cm⁻¹, one per line."""
    if species == "H2O":
        data = resources.files("invflame") / "data" / "H2O_HITRAN2012_600-800.par"
        text = data.read_text(encoding="ascii")
    elif species == "CO2":
        from invflame.spectroscopy.co2_lines import generate_co2_lines
        from invflame.spectroscopy.linelist import write_par

        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "CO2.par"
            write_par(generate_co2_lines().window(600.0, 800.0), path)
            text = path.read_text(encoding="ascii")
    else:
        raise ValueError(f"species must be one of {sorted(TABLES)}, got {species!r}")
    return "".join(line.rstrip("\r\n") + "\n" for line in text.splitlines() if line.strip())


def _write_if_changed(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` (atomically) unless it already holds it."""
    if path.is_file() and path.read_text(encoding="ascii") == text:
        return
    partial = path.with_name(path.name + ".partial")
    partial.write_text(text, encoding="ascii")
    os.replace(partial, path)


@functools.cache
def open_tables() -> dict:
    """Write the HAPI tables (``NAME.data`` records and ``NAME.header``) and load them.

    The tables live in ``reference_dir() / "tables"``, a folder of their own, since
    ``hapi.db_begin`` loads every table of its folder. Done once per process.

    Returns
    -------
    dict of str -> str
        SHA-256 of each species' records, for the cache keys.
    """
    hapi = _hapi()
    folder = reference_dir() / "tables"
    folder.mkdir(parents=True, exist_ok=True)
    digests = {}
    for species, name in TABLES.items():
        records = _records(species)
        digests[species] = hashlib.sha256(records.encode("ascii")).hexdigest()
        header = {**hapi.HITRAN_DEFAULT_HEADER, "table_name": name}
        _write_if_changed(folder / f"{name}.data", records)
        _write_if_changed(folder / f"{name}.header", json.dumps(header, indent=2))
    with contextlib.redirect_stdout(io.StringIO()):
        hapi.db_begin(str(folder))
    return digests


def _cache_key(species: str, temperature: float, self_fraction: float) -> str:
    hapi = _hapi()
    digest = hashlib.sha256()
    digest.update(
        f"v{REFERENCE_VERSION} {species} T={temperature!r} x={self_fraction!r} "
        f"grid={BIN_FIRST!r},{BIN_STEP!r},{N_BINS},{SUBSAMPLES} wing={WING!r} "
        f"hapi={hapi.HAPI_VERSION} lines={open_tables()[species]}".encode()
    )
    return digest.hexdigest()


def cross_section(species: str, temperature: float, self_fraction: float) -> np.ndarray:
    """HAPI Voigt cross-section of a species on :func:`fine_grid`, cm²/molecule, at 1 atm.

    Loaded from the disk cache when computed before with the same inputs (species, T, x,
    grid, cutoff, HAPI version, line records).

    Parameters
    ----------
    species : {"CO2", "H2O"}
    temperature : float
        K.
    self_fraction : float
        Mole fraction of the species (the ``'self'`` diluent), 0 to 1.

    Returns
    -------
    ndarray, shape (1876 · 16,), float64
    """
    if species not in TABLES:
        raise ValueError(f"species must be one of {sorted(TABLES)}, got {species!r}")
    temperature, self_fraction = float(temperature), float(self_fraction)
    key = _cache_key(species, temperature, self_fraction)
    path = reference_dir() / f"sigma-{species}-{temperature:g}K-x{self_fraction:g}-{key[:16]}.npz"
    if path.is_file():
        with np.load(path) as saved:
            if str(saved["key"]) == key:
                return saved["sigma"]
    print(f"HAPI: {species} at {temperature:g} K, x = {self_fraction:g} ...", end=" ",
          file=sys.stderr, flush=True)
    start = time.perf_counter()
    grid = fine_grid()
    with contextlib.redirect_stdout(io.StringIO()):
        nu, sigma = _hapi().absorptionCoefficient_Voigt(
            SourceTables=TABLES[species],
            Environment={"T": temperature, "p": PRESSURE / constants.atm},
            Diluent={"self": self_fraction, "air": 1.0 - self_fraction},
            HITRAN_units=True,
            WavenumberGrid=grid,
            WavenumberWing=WING,
            WavenumberWingHW=0.0,
        )
    if not np.allclose(nu, grid, rtol=0, atol=1e-9):
        raise RuntimeError("HAPI returned the cross-section on another grid")
    print(f"{time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
    partial = path.with_name(path.name + ".partial.npz")
    np.savez(partial, sigma=np.asarray(sigma, dtype=np.float64), key=np.array(key))
    os.replace(partial, path)
    return np.asarray(sigma, dtype=np.float64)


def planck(wavenumber, temperature) -> np.ndarray:
    """Black-body spectral radiance in W/(m²·sr·cm⁻¹) at wavenumbers in cm⁻¹ and T in K."""
    nu = 100.0 * np.asarray(wavenumber, dtype=np.float64)  # m⁻¹
    h, c, k = constants.h, constants.c, constants.k
    per_inverse_metre = 2.0 * h * c**2 * nu**3 / np.expm1(h * c * nu / (k * temperature))
    return 100.0 * per_inverse_metre


def absorption_coefficient(temperature: float, x_co2: float, x_h2o: float) -> np.ndarray:
    """Absorption coefficient κ on :func:`fine_grid` in m⁻¹ of a CO2–H2O–air mixture at 1 atm.

    Parameters
    ----------
    temperature : float
        K.
    x_co2, x_h2o : float
        Mole fractions (dimensionless); each gas is its own ``'self'`` diluent.
    """
    number_density = PRESSURE / (constants.k * temperature)  # m⁻³
    kappa = np.zeros(N_BINS * SUBSAMPLES)
    for species, fraction in (("CO2", x_co2), ("H2O", x_h2o)):
        if fraction > 0:
            sigma = cross_section(species, temperature, fraction)  # cm²/molecule
            kappa += fraction * number_density * sigma * 1e-4
    return kappa


def radiance(layers, average: str = "radiance") -> np.ndarray:
    """Spectral radiance of homogeneous layers in front of a cold background.

    Parameters
    ----------
    layers : sequence of (float, float, float, float)
        ``(T, X_CO2, X_H2O, length)`` per layer, nearest the camera first: temperature in K,
        mole fractions (dimensionless), length in m.
    average : {"radiance", "optical depth"}
        ``"radiance"`` (default, the reference): the radiance is solved on the fine grid and
        averaged over each bin. ``"optical depth"``: κ is averaged over each bin first and the
        radiance solved on the bins with Planck's law at the bin centres, as a model on
        bin-averaged cross-sections does (the difference is the error of that averaging).

    Returns
    -------
    ndarray, shape (1876,)
        Radiance over each line-by-line bin (centres :func:`bin_centres`) in
        W/(m²·sr·cm⁻¹).
    """
    if average not in ("radiance", "optical depth"):
        raise ValueError(f"average must be 'radiance' or 'optical depth', got {average!r}")
    fine = average == "radiance"
    eta = fine_grid() if fine else bin_centres()
    total = np.zeros(eta.size)
    passed = np.ones(eta.size)  # transmittance of the layers in front
    for temperature, x_co2, x_h2o, length in layers:
        kappa = absorption_coefficient(temperature, x_co2, x_h2o)
        transmittance = np.exp(-(kappa if fine else bin_average(kappa)) * length)
        total += planck(eta, temperature) * (1.0 - transmittance) * passed
        passed *= transmittance
    return bin_average(total) if fine else total


def compare_cross_sections(species: str, temperature: float, self_fraction: float) -> dict:
    r"""Relative differences of invflame's cross-section from HAPI's on :func:`fine_grid`.

    invflame's line-by-line code is evaluated with its own pressure shift, and with the line
    positions moved here (its shift set to zero) by :math:`\delta_\mathrm{air} p` and by
    HAPI's :math:`\delta_\mathrm{air} (1 - x) p`, to separate the shift convention from the
    rest.

    Returns
    -------
    dict of str -> (float, float, float)
        Per variant: band-integral difference, maximum and median absolute difference over
        1 cm⁻¹ bins (25 line-by-line bins from 650 cm⁻¹).
    """
    from invflame.spectroscopy.absorption_table import default_linelists
    from invflame.spectroscopy.cross_section import cross_section as invflame_sigma

    reference = cross_section(species, temperature, self_fraction)
    lines = default_linelists(np.array([BIN_FIRST, bin_centres()[-1]]))[species]
    n_wide = N_BINS // 25

    def per_cm(values):
        return bin_average(values)[: n_wide * 25].reshape(n_wide, 25).mean(axis=1)

    shift = lines.delta_air * (PRESSURE / constants.atm)  # cm⁻¹
    variants = {
        "invflame's own": lines,
        "d_air p": dataclasses.replace(lines, nu=lines.nu + shift, delta_air=0 * shift),
        "d_air (1 - x) p": dataclasses.replace(
            lines, nu=lines.nu + (1.0 - self_fraction) * shift, delta_air=0 * shift),
    }
    result = {}
    for name, variant in variants.items():
        sigma = invflame_sigma(variant, fine_grid(), temperature, PRESSURE, self_fraction)
        wide = np.abs(per_cm(sigma) / per_cm(reference) - 1.0)
        result[name] = (sigma.sum() / reference.sum() - 1.0, wide.max(), np.median(wide))
    return result


def main(argv=None) -> int:
    """Print the agreement of the HAPI cross-sections with invflame's for a few states."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--temperature", type=float, default=1500.0, help="K (default 1500)")
    args = parser.parse_args(argv)
    print(f"cross-sections at {args.temperature:g} K, 1 atm, on the 0.0025 cm-1 grid: "
          "invflame / HAPI - 1")
    print("| species | x_self | shift in invflame | band [%] | max 1 cm-1 [%] "
          "| median 1 cm-1 [%] |")
    print("|---|---:|---|---:|---:|---:|")
    for species, fraction in (("H2O", 0.12), ("CO2", 0.10)):
        for name, (band, worst, median) in compare_cross_sections(
                species, args.temperature, fraction).items():
            print(f"| {species} | {fraction:g} | {name} | {100 * band:+.3f} | "
                  f"{100 * worst:.3f} | {100 * median:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
