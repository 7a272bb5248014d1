r"""Absorption cross-sections tabulated in temperature and self fraction.

:class:`AbsorptionTable` holds :math:`\sigma_s(\eta, T, X_s)` (cm²/molecule) for the species
CO2, H2O, CH4 on temperature nodes at one pressure and, per species, on nodes of its own mole
fraction :math:`X_s` (its lines are broadened and shifted by its own molecules otherwise than by
air); the cubic spline in T through them (:class:`operators.tabulated.PiecewiseCubic`) and
linear interpolation in :math:`X_s` between the fraction nodes give the cross-section of any
state, as the emission operator evaluates it, and from it the absorption coefficient κ in m⁻¹
(:mod:`~invflame.spectroscopy.absorption_coefficient`). A species given one fraction node has
the cross-section of that fraction whatever the gas holds (the broadening ``"fixed"``,
:data:`~invflame.spectroscopy.table_inputs.FIXED_SELF_FRACTION`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from invflame.atomic_files import CorruptFileError
from invflame.errors import InputDataError
from invflame.spectroscopy.absorption_coefficient import AbsorptionCoefficient
from invflame.spectroscopy.cross_section import grid_step
from invflame.spectroscopy.line_parameters import ATM
from invflame.spectroscopy.spectral_points import MAX_POINTS_PER_BIN
from invflame.spectroscopy.table_files import read_table, write_table
from invflame.spectroscopy.table_inputs import (
    DEFAULT_SELF_FRACTION,
    DEFAULT_TEMPERATURES,
    SPECIES,
    default_linelists,
    resolve,
    table_key,
    tabulate,
)
from operators.disk_cache import cache_dir
from operators.rte.tables import RTETables
from operators.tabulated import PiecewiseCubic

__all__ = ["DEFAULT_SELF_FRACTION", "DEFAULT_TEMPERATURES", "SPECIES", "AbsorptionTable",
           "default_linelists"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class AbsorptionTable(AbsorptionCoefficient):
    r"""Cross-sections :math:`\sigma_s(\eta, T, X_s)` on temperature and self-fraction nodes,
    with their T spline.

    A species without lines has zero cross-section. In particular CH4 has no lines in the
    default table: its bands (ν4 near 1306 cm⁻¹, ν2 near 1533 cm⁻¹) lie outside 650–725 cm⁻¹,
    so it is transparent there.

    **Interpolation accuracy.** With the default 28 nodes (:data:`DEFAULT_TEMPERATURES`), the
    spline differs from direct line-by-line evaluation at the midpoints between nodes by at most
    0.29 % (CO2, near 2370 K) and 0.28 % (H2O, near 1390 K) of the cross-section smoothed to
    1 cm⁻¹, over every self-fraction node (measured on the default table;
    ``benchmarks/bench_absorption.py`` prints it, a test checks it stays below 0.5 %).

    Attributes
    ----------
    species : tuple of str
        Species names, e.g. ``("CO2", "H2O", "CH4")``.
    wavenumber : ndarray, shape (n_eta,)
        Uniform grid of bin centres, cm⁻¹.
    pressure : float
        Pressure in Pa at which the lines were broadened.
    temperatures : ndarray, shape (n_T,)
        Temperature nodes, K, strictly increasing.
    sigma : ndarray, shape (n_T, n_columns, n_points)
        Cross-sections averaged over each spectral point's sub-bin, cm²/molecule, one column
        per species and self-fraction node, species-major.
    self_fraction : tuple of tuple of float
        Per species, the increasing mole fractions of its columns (self broadening).
    points_per_bin : ndarray of int, shape (n_eta,)
        Equal sub-bins per bin, the spectral points
        (:mod:`~invflame.spectroscopy.spectral_points`); ones when every bin is one point.
    bin_width : float
        Width of a bin in cm⁻¹ (default: the grid step; a table of every k-th bin of another,
        :meth:`take_bins`, keeps the other's).
    spline : PiecewiseCubic
        Cubic spline of ``sigma`` in T (not-a-knot), ``spline(T)`` has shape
        ``T.shape + (n_columns, n_points)``.
    """

    species: tuple
    wavenumber: np.ndarray
    pressure: float
    temperatures: np.ndarray
    sigma: np.ndarray
    self_fraction: tuple
    points_per_bin: np.ndarray | None = None
    bin_width: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "species", tuple(str(s) for s in self.species))
        object.__setattr__(self, "self_fraction", tuple(
            tuple(float(x) for x in np.atleast_1d(f)) for f in self.self_fraction))
        object.__setattr__(self, "wavenumber", np.asarray(self.wavenumber, dtype=np.float64))
        object.__setattr__(self, "temperatures", np.asarray(self.temperatures, dtype=np.float64))
        object.__setattr__(self, "sigma", np.asarray(self.sigma, dtype=np.float64))
        object.__setattr__(self, "pressure", float(self.pressure))
        if len(self.self_fraction) != len(self.species):
            raise ValueError("self_fraction needs the fraction nodes of every species")
        points = np.ones(self.wavenumber.size, dtype=int) if self.points_per_bin is None \
            else np.asarray(self.points_per_bin)
        if points.shape != self.wavenumber.shape or not np.issubdtype(points.dtype, np.integer) \
                or points.min() < 1:
            raise ValueError(f"points_per_bin must be one positive integer per bin "
                             f"({self.wavenumber.size}), got {points!r}")
        object.__setattr__(self, "points_per_bin", points)
        object.__setattr__(self, "bin_width", float(
            self.bin_width if self.bin_width is not None
            else grid_step(self.wavenumber) if self.wavenumber.size > 1 else 0.0))
        expected = (self.temperatures.size, sum(map(len, self.self_fraction)), int(points.sum()))
        if self.sigma.shape != expected:
            raise ValueError(
                f"sigma must have shape (n_T, n_columns, n_points) = {expected}, "
                f"got {self.sigma.shape}"
            )
        object.__setattr__(self, "spline", PiecewiseCubic(self.temperatures, self.sigma))

    @property
    def points(self) -> np.ndarray:
        """Wavenumbers of the spectral points (sub-bin centres), cm⁻¹, shape (n_points,)."""
        m = self.points_per_bin[self.point_bin]
        within = np.arange(m.size) - (np.cumsum(self.points_per_bin) - self.points_per_bin
                                      )[self.point_bin]
        return self.wavenumber[self.point_bin] + ((within + 0.5) / m - 0.5) * self.bin_width

    @property
    def point_bin(self) -> np.ndarray:
        """The bin of every spectral point, shape (n_points,)."""
        return np.repeat(np.arange(self.wavenumber.size), self.points_per_bin)

    def bin_average(self, values) -> np.ndarray:
        """Means over each bin's spectral points, along the last axis (n_points -> n_eta)."""
        starts = np.cumsum(self.points_per_bin) - self.points_per_bin
        return np.add.reduceat(np.asarray(values), starts, axis=-1) / self.points_per_bin

    def take_bins(self, band: slice) -> AbsorptionTable:
        """The table of the bins ``band`` (a slice of :attr:`wavenumber`, any stride), with
        their spectral points."""
        bins = np.arange(self.wavenumber.size)[band]
        if bins.size == 0:
            raise ValueError(f"band {band} picks no bin of the {self.wavenumber.size}")
        points = np.isin(self.point_bin, bins)
        return AbsorptionTable(self.species, self.wavenumber[bins], self.pressure,
                               self.temperatures, self.sigma[..., points], self.self_fraction,
                               self.points_per_bin[bins], self.bin_width)

    def columns(self, species: int) -> slice:
        """The columns of :attr:`sigma` of species number ``species``, one per fraction node."""
        first = sum(len(f) for f in self.self_fraction[:species])
        return slice(first, first + len(self.self_fraction[species]))

    # ------------------------------------------------------------------ construction

    @classmethod
    def build(
        cls,
        linelists: dict,
        wavenumber=None,
        temperatures=None,
        pressure: float = ATM,
        species=SPECIES,
        self_fraction: dict | None = None,
        progress: bool = False,
        subdivision: int = MAX_POINTS_PER_BIN,
    ) -> AbsorptionTable:
        """Compute a table line by line (:func:`.cross_section.cross_section`).

        Parameters
        ----------
        linelists : dict of str -> LineList
            Lines per species; a species of ``species`` without an entry gets zero
            cross-section. Give lines up to 25 cm⁻¹ beyond the grid (line wings).
        wavenumber : array_like, optional
            Uniform grid, cm⁻¹ (default 650–725 cm⁻¹ at 0.04 cm⁻¹).
        temperatures : array_like, optional
            Strictly increasing nodes in K (default :data:`DEFAULT_TEMPERATURES`).
        pressure : float
            Pa (default 1 atm).
        species : sequence of str
            Table species, in order (default CO2, H2O, CH4).
        self_fraction : dict of str -> float or sequence of float, optional
            Per species, the mole fraction of self broadening: one number, fixed whatever
            the gas holds, or increasing nodes in [0, 1] to interpolate between (default
            :data:`DEFAULT_SELF_FRACTION`, 0 for species not in it).
        progress : bool
            Show a progress bar.
        subdivision : int, optional
            Most spectral points per bin, a power of two: the cross-sections are computed on
            that many sub-bins of every bin and :func:`.spectral_points.plan_points` chooses
            where fewer do (default :data:`.spectral_points.MAX_POINTS_PER_BIN`); 1: one
            optical depth per bin.
        """
        species, wavenumber, temperatures, fractions = resolve(
            linelists, species, wavenumber, temperatures, self_fraction
        )
        sigma, points = tabulate(linelists, species, wavenumber, temperatures, pressure,
                                 fractions, subdivision, progress)
        return cls(species, wavenumber, pressure, temperatures, sigma, fractions, points)

    @classmethod
    def cached(
        cls,
        linelists: dict,
        wavenumber=None,
        temperatures=None,
        pressure: float = ATM,
        species=SPECIES,
        self_fraction: dict | None = None,
        progress: bool = True,
        subdivision: int = MAX_POINTS_PER_BIN,
    ) -> AbsorptionTable:
        """:meth:`build`, or load the table built from the same inputs from the disk cache.

        Arguments as :meth:`build`. The cache file (in ``$INVFLAME_CACHE``, by default
        ``~/.cache/invflame``) is named by :func:`~.table_inputs.table_key`, a hash of the line
        data, grid, temperature nodes, pressure, self-broadening fractions and
        :data:`~.table_inputs.TABLE_VERSION`; it
        holds that key and a hash of its own arrays. A cache file that is damaged (empty,
        truncated, garbage), holds another key or fails its hash is rebuilt, with a warning
        naming it on the ``invflame.spectroscopy.absorption_table`` logger; where the cache
        cannot be written (the folder cannot be made, no space, no permission) the table built
        is returned uncached, with a warning naming the file and the reason.
        """
        species, wavenumber, temperatures, fractions = resolve(
            linelists, species, wavenumber, temperatures, self_fraction
        )
        key = table_key(linelists, species, wavenumber, temperatures, pressure, fractions,
                        subdivision)
        path = cache_dir() / f"absorption-{key[:24]}.npz"
        if path.is_file():
            try:
                return cls.load(path, key=key)
            except (CorruptFileError, InputDataError) as err:
                logger.warning("rebuilding the cached absorption table %s: %s", path, err)
        fractions = dict(zip(species, fractions, strict=True))
        table = cls.build(linelists, wavenumber, temperatures, pressure, species, fractions,
                          progress, subdivision)
        try:
            table.save(path, key=key)
        except OSError as err:
            logger.warning("the absorption table is used without being cached: %s cannot be "
                           "written (%s); set INVFLAME_CACHE to a writable folder", path,
                           err.strerror)
        return table

    @classmethod
    def default(cls, progress: bool = True, self_fraction: dict | None = None,
                subdivision: int = MAX_POINTS_PER_BIN) -> AbsorptionTable:
        """The table of the study: CO2, H2O, CH4 at 1 atm, 650–725 cm⁻¹ at 0.04 cm⁻¹.

        Lines from :func:`default_linelists`; CH4 has none (zero cross-section); self
        broadening and spectral points as :meth:`build` takes them (default
        :data:`DEFAULT_SELF_FRACTION`, up to 8 points per bin). Built once (about a minute on
        two CPU cores) and then loaded from the disk cache.
        """
        return cls.cached(default_linelists(), self_fraction=self_fraction, progress=progress,
                          subdivision=subdivision)

    # ------------------------------------------------------------------ storage

    def save(self, path, key: str = "") -> None:
        """Write the table to an ``.npz`` file (atomic: temporary file, then rename).

        Parameters
        ----------
        path : str or Path
            Destination.
        key : str, optional
            The :func:`~.table_inputs.table_key` the table was built from, stored with it (the
            cache checks it on :meth:`load`); a SHA-256 hash of the arrays is stored too.
        """
        write_table(path, {
            "species": np.array(self.species), "wavenumber": self.wavenumber,
            "pressure": np.asarray(self.pressure), "temperatures": self.temperatures,
            "sigma": self.sigma, "self_fraction": np.concatenate(self.self_fraction),
            "nodes_per_species": np.array([len(f) for f in self.self_fraction]),
            "points_per_bin": self.points_per_bin, "bin_width": np.asarray(self.bin_width)},
            key)

    @classmethod
    def load(cls, path, key: str | None = None) -> AbsorptionTable:
        """Read a table written by :meth:`save`, checking its content hash.

        Parameters
        ----------
        path : str or Path
            The ``.npz`` file.
        key : str, optional
            The :func:`~.table_inputs.table_key` the file must hold (a cache lookup); default: any.

        Raises
        ------
        CorruptFileError, InputDataError
            As :func:`~.table_files.read_table`: a damaged file, missing entries, a failed
            hash or another key.
        """
        data = read_table(path, key)
        return cls(
            species=tuple(data["species"].tolist()),
            wavenumber=data["wavenumber"],
            pressure=float(data["pressure"]),
            temperatures=data["temperatures"],
            sigma=data["sigma"],
            self_fraction=np.split(data["self_fraction"],
                                   np.cumsum(data["nodes_per_species"])[:-1]),
            points_per_bin=data["points_per_bin"],
            bin_width=float(data["bin_width"]),
        )

    def kernel_tables(self, band: slice = slice(None), dtype=np.float32, planck: str = "table",
                      soot: float | None = None) -> RTETables:
        """The emission kernel's tables (:meth:`operators.rte.tables.RTETables.from_spline`)
        of this table's cross-sections over the bins ``band``.

        Parameters
        ----------
        band : slice, optional
            Bins of :attr:`wavenumber` (default all).
        dtype : numpy dtype, optional
            float32 (default) or float64.
        planck : {"table", "exact"}, optional
            How the kernel evaluates Planck's law.
        soot : float, optional
            The Rayleigh soot constant (the kernel then takes a soot volume fraction field);
            default None, gas only.
        """
        table = self.take_bins(band)
        return RTETables.from_spline(table.points, table.temperatures, table.spline.coef,
                                     table.pressure, dtype, planck, soot=soot,
                                     fraction_nodes=table.self_fraction,
                                     point_bin=table.point_bin)
