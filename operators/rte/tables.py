r"""Spectral tables of the emission kernel (:mod:`operators.rte.kernel`), from absorption splines.

The kernel evaluates, per ray segment, the optical depth :math:`\tau` and the Planck radiance
:math:`B_\eta(T)` as sums of table rows times per-segment weights. All species' spline
coefficients and those of :math:`B` sit in one table per temperature interval,
``(n_intervals, n_coef, n_eta)``. Coefficients are pre-scaled by :math:`p \cdot 10^{-4}/k_B`
and written in the interval's normalized offset :math:`u \in [0, 1]`, so float32 evaluation
stays well inside its range; with ``planck="table"`` the cross-section splines are re-expanded
on the refined temperature nodes of the Planck spline (:func:`operators.rte.planck.planck_table`).

**Composition** (optional). A species' lines are broadened and shifted differently by its own
molecules than by air, so its cross-section depends on its own mole fraction :math:`X`. Given
on increasing nodes of :math:`X` (``fraction_nodes``), it is interpolated linearly between the
nodes either side, :math:`\sigma = (1 - w)\sigma_\mathrm{lo} + w\,\sigma_\mathrm{hi}`
(:func:`operators.rte.blocks.fraction_weights`): two gas slots, of amounts
:math:`X (1 - w) \Delta s / T` and :math:`X w \Delta s / T`. The table holds one block of rows
per temperature interval and combination of the species' node intervals
(:func:`operators.rte.blocks.composition_block`); the kernel gathers each segment's block, so
its sweeps are those of fixed cross-sections with more gas slots.

**Spectral points** (optional). A bin's mean transmission is not the exponential of its mean
optical depth where lines narrower than the bin saturate. The tables may then hold several
points per bin (``point_bin``), sub-bins with their own cross-sections: the kernel solves the
transfer at every point and returns, per bin, the mean radiance of its points; a background
given per bin is the same at each of its points.

**Soot** (optional). Soot particles much smaller than the wavelength absorb in the Rayleigh
limit, a continuum proportional to the soot volume fraction :math:`f_v` and the wavenumber,

.. math:: \kappa_\mathrm{soot}(\eta) = C\, f_v\, \eta \cdot 10^2, \qquad
          C = \frac{36 \pi n k}{(n^2 - k^2 + 2)^2 + 4 n^2 k^2},

in m⁻¹ for :math:`\eta` in cm⁻¹ (the :math:`10^2` converts it to m⁻¹), with :math:`m = n - ik`
the soot's complex refractive index (Modest, *Radiative Heat Transfer*, 3rd ed. 2013, ch. 12,
small-particle absorption; :func:`rayleigh_soot_constant`). It is one more table row,
:math:`C \eta \cdot 10^2`, the same in every temperature interval, weighted by
:math:`f_v \Delta s`: the kernel then takes :math:`f_v` as one more field after the mole
fractions.
"""

from __future__ import annotations

import dataclasses
from functools import cached_property, partial

import jax
import jax.numpy as jnp
import numpy as np

from operators.base import precision
from operators.rte.blocks import block_slots, check_fraction_nodes, check_point_bin
from operators.rte.planck import BOLTZMANN, planck_table

SOOT_REFRACTIVE_INDEX = (3.16, 2.39)
r"""Complex refractive index :math:`(n, k)` of soot near 675 cm⁻¹ (14.8 µm): the dispersion
relations of Chang & Charalampopoulos (Proc. R. Soc. Lond. A 430, 577–591, 1990, valid
0.4–30 µm), :math:`n = 1.811 + 0.1263 \ln\lambda + 0.0270 \ln^2\lambda + 0.0417 \ln^3\lambda`,
:math:`k = 0.5821 + 0.1213 \ln\lambda + 0.2309 \ln^2\lambda - 0.0100 \ln^3\lambda`
(:math:`\lambda` in µm), evaluated at 14.8 µm. With it :math:`C pprox 3.2`."""


def rayleigh_soot_constant(n: float = SOOT_REFRACTIVE_INDEX[0],
                           k: float = SOOT_REFRACTIVE_INDEX[1]) -> float:
    r"""The dimensionless constant :math:`C = 36 \pi n k / ((n^2 - k^2 + 2)^2 + 4 n^2 k^2)` of
    Rayleigh-limit soot absorption, :math:`\kappa = C f_v / \lambda` (module notes).

    Parameters
    ----------
    n, k : float, optional
        Real part and (positive) imaginary part of the refractive index :math:`m = n - ik`
        (default :data:`SOOT_REFRACTIVE_INDEX`).

    Raises
    ------
    ValueError
        For ``n`` or ``k`` not positive.
    """
    if not (n > 0 and k > 0):
        raise ValueError(f"the soot refractive index n - ik needs n > 0 and k > 0, got n = {n!r}, "
                         f"k = {k!r}")
    return float(36 * np.pi * n * k / ((n**2 - k**2 + 2) ** 2 + 4 * n**2 * k**2))


@partial(jax.tree_util.register_dataclass,
         data_fields=["nodes", "inv_width", "coef", "wavenumber", "point_bin", "point_weight"],
         meta_fields=["species", "n_species", "planck", "soot", "fraction_nodes", "n_bins"])
@dataclasses.dataclass(frozen=True)
class RTETables:
    r"""Spectral tables of the emission kernel, prepared from absorption splines.

    Build with :meth:`from_spline`. A JAX pytree: its arrays travel as arguments of jitted
    functions (no large constants baked into compiled code).

    Attributes
    ----------
    nodes : jax.Array, shape (m,)
        Temperature nodes in K (those of the cross-sections, refined for Planck's law when
        ``planck == "table"``).
    inv_width : jax.Array, shape (m - 1,)
        Inverse interval widths in 1/K.
    coef : jax.Array, shape ((m - 1) * n_blocks, n_coef, n_points)
        Per temperature interval and composition block (index ``interval * n_blocks +
        block``, :func:`operators.rte.blocks.n_composition_blocks`), the coefficients of
        :math:`u^3, u^2, u, 1` (``u`` the normalized offset in the interval) of
        :math:`\sigma_s p 10^{-4}/k_B` (K/m) for each gas slot (each absorbing species in
        ``species`` order, two slots for one with several fraction nodes), then (``soot``) the
        soot row :math:`C \eta \cdot 10^2` (m⁻¹ per unit volume fraction, in the constant's
        place), then (``planck == "table"``) of
        :math:`B_\eta` in W/(m²·sr·cm⁻¹).
    wavenumber : jax.Array, shape (n_points,)
        The spectral points' wavenumbers in cm⁻¹.
    point_bin : jax.Array of int32, shape (n_points,)
        The bin of each point (module notes, spectral points); ``arange(n_points)`` when every
        bin is one point.
    point_weight : jax.Array, shape (n_points,)
        One over the number of points of each point's bin.
    species : tuple of int
        Indices (0-based, among the mole-fraction fields) of the species with a non-zero
        cross-section; the others are skipped.
    fraction_nodes : tuple of tuple of float
        Per species of :attr:`species`, the mole fractions at which its cross-section is
        tabulated (module notes, composition): one node, a fixed cross-section; several, linear
        interpolation in the species' own mole fraction.
    n_species : int
        Number of mole-fraction fields.
    planck : {"table", "exact"}
        How :math:`B_\eta(T)` is evaluated.
    soot : bool
        Whether the kernel input ends with a soot volume fraction field (then ``species``
        also holds its index, ``n_species``); the input has :attr:`n_fields` fields.
    """

    nodes: jax.Array
    inv_width: jax.Array
    coef: jax.Array
    wavenumber: jax.Array
    species: tuple[int, ...]
    n_species: int
    planck: str
    soot: bool = False
    fraction_nodes: tuple[tuple[float, ...], ...] = ()
    point_bin: jax.Array | None = None
    point_weight: jax.Array | None = None
    n_bins: int = 0

    @classmethod
    def from_spline(cls, wavenumber, temperatures, coef, pressure: float = 101325.0,
                    dtype=np.float32, planck: str = "table",
                    planck_rtol: float = 1e-7, soot: float | None = None,
                    fraction_nodes=None, point_bin=None) -> RTETables:
        r"""Prepare the kernel tables from cubic-spline coefficients of cross-sections.

        Parameters
        ----------
        wavenumber : array_like, shape (n_points,)
            Wavenumbers of the spectral points in cm⁻¹.
        temperatures : array_like, shape (n_T,)
            Spline nodes in K, strictly increasing.
        coef : array_like, shape (4, n_T - 1, n_columns, n_points)
            :class:`~operators.tabulated.PiecewiseCubic` coefficients of the cross-sections
            :math:`\sigma_s(\eta, T)` in cm²/molecule: on interval ``i``,
            :math:`\sigma = \sum_j c_{j,i} (T - T_i)^{3-j}`. One column per mole-fraction
            field, or, with ``fraction_nodes``, one per field and node, field-major.
        pressure : float, optional
            Total pressure in Pa (default 101325).
        dtype : numpy dtype, optional
            float32 (default, fast) or float64.
        planck : {"table", "exact"}, optional
            Planck's law as a spline on refined nodes (default, one polynomial instead of an
            exponential per spectral point) or evaluated exactly.
        planck_rtol : float, optional
            Relative accuracy of the Planck spline between the first and last node.
        soot : float, optional
            The Rayleigh soot constant :math:`C` (dimensionless, e.g.
            :func:`rayleigh_soot_constant`): the kernel then takes a soot volume fraction
            field after the mole fractions. Default None: no soot.
        fraction_nodes : sequence of sequence of float, optional
            Per mole-fraction field, the increasing mole fractions (0 to 1) of its columns of
            ``coef`` (module notes, composition). Default: one column per field, whatever its
            mole fraction.
        point_bin : array_like of int, shape (n_points,), optional
            The bin of each point: non-decreasing, from 0, no bin skipped (module notes,
            spectral points). Default: every point a bin of its own.
        """
        wavenumber = np.asarray(wavenumber, dtype=np.float64)
        temperatures = np.asarray(temperatures, dtype=np.float64)
        coef = np.asarray(coef, dtype=np.float64)
        n_t, n_eta = temperatures.size, wavenumber.size
        if wavenumber.ndim != 1:
            raise ValueError(f"wavenumber must be 1-D (cm-1), got shape {wavenumber.shape}")
        if coef.ndim != 4 or coef.shape[0] != 4 or coef.shape[1] != n_t - 1 \
                or coef.shape[3] != n_eta:
            raise ValueError(
                f"coef must have shape (4, n_T - 1, n_columns, n_eta) = (4, {n_t - 1}, "
                f"n_columns, {n_eta}) for {n_t} temperature nodes and {n_eta} wavenumbers; "
                f"got {coef.shape}"
            )
        nodes_per_field = check_fraction_nodes(fraction_nodes, coef.shape[2])
        if not pressure > 0:
            raise ValueError(f"pressure must be positive (Pa), got {pressure}")
        if planck not in ("table", "exact"):
            raise ValueError(f"planck must be 'table' or 'exact', got {planck!r}")
        if np.dtype(dtype) not in (np.float32, np.float64):
            raise ValueError(f"dtype must be float32 or float64, got {np.dtype(dtype)}")
        if soot is not None and not (np.isfinite(soot) and soot > 0):
            raise ValueError(f"soot must be the positive Rayleigh constant C (see "
                             f"rayleigh_soot_constant) or None, got {soot!r}")
        first = np.cumsum([0, *map(len, nodes_per_field)])
        columns = [np.arange(first[f], first[f + 1]) for f in range(len(nodes_per_field))]
        species = tuple(f for f, c in enumerate(columns) if np.any(coef[:, :, c] != 0))
        fraction_nodes = tuple(nodes_per_field[f] for f in species)
        if planck == "table":
            nodes, b_coef = planck_table(wavenumber, temperatures, rtol=planck_rtol)
        else:
            nodes = temperatures
        scale = pressure * 1e-4 / BOLTZMANN
        sigma = _restrict(temperatures, coef, nodes) * scale * _powers_of_width(nodes, 4)
        blocks = block_slots([columns[f] for f in species])
        n_gas = 4 * sum(map(len, blocks[0]))
        n_rows = n_gas + (soot is not None) + 4 * (planck == "table")
        table = np.empty((nodes.size - 1, len(blocks), n_rows, n_eta), dtype)
        for b, slots in enumerate(blocks):  # (4, m - 1, k, n_eta) -> (m - 1, k * 4, n_eta)
            chosen = sigma[:, :, np.concatenate(slots)] if slots else sigma[:, :, :0]
            table[:, b, :n_gas] = chosen.transpose(1, 2, 0, 3).reshape(nodes.size - 1, -1, n_eta)
        if soot is not None:
            table[:, :, n_gas] = soot * 1e2 * wavenumber
            species += (len(nodes_per_field),)
        if planck == "table":
            b_rows = (b_coef * _powers_of_width(nodes, b_coef.ndim)).transpose(1, 0, 2)
            table[:, :, -4:] = b_rows[:, None]
        table = table.reshape(-1, n_rows, n_eta)
        point_bin = check_point_bin(point_bin, n_eta)
        weight = 1.0 / np.bincount(point_bin)[point_bin]
        with precision(dtype):  # float64 arrays stay float64 outside JAX's 64-bit mode
            return cls(jnp.asarray(nodes, dtype), jnp.asarray(1.0 / np.diff(nodes), dtype),
                       jnp.asarray(table, dtype), jnp.asarray(wavenumber, dtype),
                       species, len(nodes_per_field), planck, soot is not None, fraction_nodes,
                       jnp.asarray(point_bin, jnp.int32), jnp.asarray(weight, dtype),
                       int(point_bin[-1]) + 1)

    @property
    def dtype(self):
        """Floating-point type of the tables (and of the kernel's arithmetic)."""
        return self.coef.dtype

    @property
    def n_fields(self) -> int:
        """Fields of the kernel input: T, the mole fractions, and the soot volume fraction
        when :attr:`soot`."""
        return 1 + self.n_species + int(self.soot)

    @property
    def n_eta(self) -> int:
        """Number of spectral bins: of the radiance the kernel returns, and of a background."""
        return self.n_bins

    @property
    def n_points(self) -> int:
        """Number of spectral points, at which the kernel solves the transfer."""
        return self.wavenumber.shape[0]

    @property
    def binned(self) -> bool:
        """Whether some bin has several points (the kernel then averages over them)."""
        return self.n_points != self.n_bins

    @cached_property
    def temperature_range(self) -> tuple[float, float]:
        """The first and last temperature node in K, as Python numbers (read from JAX's
        device once, not at every check)."""
        return float(self.nodes[0]), float(self.nodes[-1])

    def check_temperature(self, temperature, where: str) -> None:
        """Refuse temperatures the tables do not cover.

        Parameters
        ----------
        temperature : array_like
            Temperatures in K. A value may pass the first or last node by its own rounding
            (one machine epsilon, relative), as a float32 solver's bound does.
        where : str
            Names the caller in the message.

        Raises
        ------
        ValueError
            If a temperature lies outside the nodes' range, naming the span and the range.
        """
        temperature = np.asarray(temperature)
        t_min, t_max = self.temperature_range
        eps = (np.finfo(temperature.dtype).eps
               if np.issubdtype(temperature.dtype, np.floating) else 0.0)
        low, high = float(temperature.min()), float(temperature.max())
        if low < t_min * (1 - eps) or high > t_max * (1 + eps):
            raise ValueError(f"{where}: temperature spans {low:g}-{high:g} K, outside the "
                             f"absorption tables' {t_min:g}-{t_max:g} K")


def _restrict(nodes, coef, fine):
    """Coefficients of a piecewise cubic on ``nodes`` re-expanded on the refinement ``fine``.

    Both in powers of the offset from the left node, highest first; ``coef`` has shape
    ``(4, len(nodes) - 1, ...)``.
    """
    index = np.clip(np.searchsorted(nodes, fine[:-1], side="right") - 1, 0, nodes.size - 2)
    c = coef[:, index]
    x = (fine[:-1] - nodes[index]).reshape((-1,) + (1,) * (coef.ndim - 2))
    return np.stack([
        c[0],
        3 * c[0] * x + c[1],
        (3 * c[0] * x + 2 * c[1]) * x + c[2],
        ((c[0] * x + c[1]) * x + c[2]) * x + c[3],
    ])


def _powers_of_width(nodes, ndim):
    """``width**(3 - j)`` shaped to scale coefficients ``(4, m - 1, ...)`` to offsets in [0, 1]."""
    width = np.diff(nodes)
    return (width[None, :] ** np.arange(3, -1, -1)[:, None]).reshape((4, -1) + (1,) * (ndim - 2))
