"""Flame state on a voxel grid: temperature and mole fractions, with validation and ``.npz`` I/O.

A :class:`Field` is what the ground truth, the synthetic phantoms and the reconstructions have in
common: a :class:`~invflame.geometry.VoxelGrid`, one float32 array of shape
``(4, nx, ny, nz)`` holding ``T`` [K], ``X_CO2``, ``X_H2O``, ``X_CH4`` (mole fractions, 1) in that
order, and a metadata dict (provenance: solver, case, time, seed, ...). A sooting flame carries
a fifth field, the soot volume fraction ``f_v`` (1), shape ``(5, nx, ny, nz)``
(:data:`SOOT_NAME`, :meth:`Field.with_soot`).

Resampling to another grid averages cells with molar-density weights ``c = p / (R T)`` (uniform
pressure), see :func:`resample_values`: the coarse cell then holds the same number of moles of
every species, and of gas in total, as the fine cells it covers; a soot volume fraction is
averaged by volume.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from invflame.atomic_files import read_npz, write_npz
from invflame.errors import InputDataError
from invflame.geometry import VoxelGrid

FIELD_NAMES = ("T", "CO2", "H2O", "CH4")
"""Order of the fields along axis 0 of :attr:`Field.values`: T [K], then mole fractions."""

SPECIES = FIELD_NAMES[1:]
"""Species whose mole fractions a field carries."""

SOOT_NAME = "soot"
"""Name of the optional fifth field, the soot volume fraction :math:`f_v` (dimensionless)."""

SOOTY_FIELD_NAMES = (*FIELD_NAMES, SOOT_NAME)
"""Order of the fields of a sooting flame: T [K], mole fractions, then :math:`f_v` [1]."""

_SUM_TOLERANCE = 1e-5  # float32 rounding allowance on sum(X) <= 1


def validate_values(values: np.ndarray, grid: VoxelGrid, *, mixture: bool = True,
                    soot: bool | None = None) -> None:
    """Check a field array against a grid; raise ``ValueError`` saying what is wrong.

    Parameters
    ----------
    values : numpy.ndarray, shape (4, nx, ny, nz) or (5, nx, ny, nz)
        ``T`` [K] then mole fractions of CO2, H2O, CH4 [1], then optionally the soot volume
        fraction [1], in [0, 1).
    grid : VoxelGrid
        Grid whose ``shape`` must be ``(nx, ny, nz)``.
    mixture : bool, optional
        Also check that the mole fractions sum to at most 1 (default). False checks each
        field's own range only, as for the iterates of a solver bounded field by field.
    soot : bool, optional
        True: the soot volume fraction must be there; False: it must not; default None:
        either.
    """
    allowed = (FIELD_NAMES, SOOTY_FIELD_NAMES) if soot is None else (
        SOOTY_FIELD_NAMES if soot else FIELD_NAMES,)
    names = next((n for n in allowed if values.shape == (len(n), *grid.shape)), None)
    if names is None:
        shapes = " or ".join(f"{(len(n), *grid.shape)} (fields {n})" for n in allowed)
        raise ValueError(f"field values must have shape {shapes}, i.e. (fields, *grid.shape); "
                         f"got {values.shape}")
    _check_ranges(values, names)
    if not mixture:
        return
    total = float(values[1:len(FIELD_NAMES)].sum(axis=0).max())
    if total > 1 + _SUM_TOLERANCE:
        raise ValueError(
            f"mole fractions of {SPECIES} must sum to at most 1; maximum sum is {total}"
        )


def validate_soot(soot, grid: VoxelGrid) -> np.ndarray:
    """A soot volume fraction per voxel as a float64 copy, checked as :func:`validate_values`
    checks the soot field; raise ``ValueError`` saying what is wrong.

    Parameters
    ----------
    soot : array_like, shape ``grid.shape``
        Soot volume fraction per voxel [1], in [0, 1).
    grid : VoxelGrid
        Grid of the voxels.
    """
    soot = np.array(soot, np.float64)
    if soot.shape != grid.shape:
        raise ValueError(f"soot must be a volume fraction per voxel of shape {grid.shape}, got "
                         f"{soot.shape}")
    _check_ranges(soot[None], (SOOT_NAME,))
    return soot


def _check_ranges(values: np.ndarray, names: tuple[str, ...]) -> None:
    """Refuse NaN or inf, T <= 0 K, mole fractions outside [0, 1] and soot volume fractions
    outside [0, 1); ``values[i]`` is the field ``names[i]``."""
    axes = tuple(range(1, values.ndim))
    lows, highs = values.min(axis=axes), values.max(axis=axes)  # NaN and inf show here
    if not (np.isfinite(lows).all() and np.isfinite(highs).all()):
        bad = ~np.isfinite(values)
        named = [names[i] for i in np.unique(np.nonzero(bad)[0])]
        raise ValueError(f"field values contain NaN or inf in {named} ({int(bad.sum())} entries)")
    for name, lo, hi in zip(names, lows.tolist(), highs.tolist(), strict=True):
        if name == "T" and lo <= 0:
            raise ValueError(f"temperature must be > 0 K everywhere; minimum is {lo} K")
        if name in SPECIES and (lo < 0 or hi > 1):
            raise ValueError(
                f"mole fraction X_{name} must lie in [0, 1]; got range [{lo}, {hi}] "
                "(clip round-off before building the field)"
            )
        if name == SOOT_NAME and (lo < 0 or hi >= 1):
            raise ValueError(f"soot volume fraction must lie in [0, 1); got range [{lo}, {hi}]")


class Field:
    """Temperature and mole fractions of CO2, H2O, CH4 on a voxel grid, and soot if any.

    Parameters
    ----------
    grid : VoxelGrid
        Grid of the voxels (m).
    values : array_like, shape (4, nx, ny, nz) or (5, nx, ny, nz)
        ``T`` [K], ``X_CO2``, ``X_H2O``, ``X_CH4`` [1] per voxel, indexed ``[field, ix, iy, iz]``,
        then optionally the soot volume fraction [1]; stored as float32 (read-only).
    metadata : dict, optional
        JSON-serialisable provenance (solver, version, case, time in s, seed, ...).

    Attributes
    ----------
    names : tuple of str
        The fields held, :data:`FIELD_NAMES` or, with soot, :data:`SOOTY_FIELD_NAMES`.

    Raises
    ------
    ValueError
        If the shape does not match the grid, a value is not finite, ``T <= 0``, a mole
        fraction is outside [0, 1], the mole fractions sum to more than 1 or a soot volume
        fraction is outside [0, 1).
    """

    names = FIELD_NAMES

    def __init__(self, grid: VoxelGrid, values, metadata: dict | None = None) -> None:
        if not isinstance(grid, VoxelGrid):
            raise TypeError(f"grid must be an invflame.geometry.VoxelGrid; got {type(grid)}")
        arr = np.array(values, dtype=np.float32)
        validate_values(arr, grid)
        arr.setflags(write=False)
        self.grid = grid
        self.values = arr
        self.names = SOOTY_FIELD_NAMES if len(arr) == len(SOOTY_FIELD_NAMES) else FIELD_NAMES
        self.metadata = dict(metadata or {})

    def __repr__(self) -> str:
        return f"Field(shape={self.grid.shape}, names={self.names}, metadata={self.metadata})"

    @property
    def T(self) -> np.ndarray:  # noqa: N802 - physics symbol
        """Temperature in K, shape ``(nx, ny, nz)``."""
        return self.values[0]

    def X(self, species: str) -> np.ndarray:  # noqa: N802 - physics symbol
        """Mole fraction of ``species`` ("CO2", "H2O" or "CH4"), shape ``(nx, ny, nz)``, 1."""
        if species not in SPECIES:
            raise KeyError(f"unknown species {species!r}; a field carries {SPECIES}")
        return self.values[FIELD_NAMES.index(species)]

    @property
    def soot(self) -> np.ndarray | None:
        """Soot volume fraction (1), shape ``(nx, ny, nz)``; None for a soot-free field."""
        return self.values[-1] if self.names == SOOTY_FIELD_NAMES else None

    @property
    def gas(self) -> Field:
        """The gas alone: T and mole fractions, without the soot."""
        if self.soot is None:
            return self
        return Field(self.grid, self.values[:len(FIELD_NAMES)], self.metadata)

    def with_soot(self, soot) -> Field:
        """This gas with a soot volume fraction per voxel (1, in [0, 1)); None: soot-free.

        Parameters
        ----------
        soot : array_like, shape ``grid.shape``, or None
            Soot volume fraction.
        """
        gas = self.gas.values
        if soot is None:
            return Field(self.grid, gas, self.metadata)
        return Field(self.grid, np.concatenate([gas, np.asarray(soot, np.float32)[None]]),
                     self.metadata)

    def __getitem__(self, name: str) -> np.ndarray:
        """Field by name: "T" (K), a species (mole fraction) or, with soot, "soot" (1)."""
        if name == SOOT_NAME and self.soot is not None:
            return self.soot
        return self.T if name == "T" else self.X(name)

    def resample(self, grid: VoxelGrid) -> Field:
        """This field averaged onto ``grid`` (see :func:`resample_values`); the field itself when
        ``grid`` is its own.

        Parameters
        ----------
        grid : VoxelGrid
            Target grid; its box must lie inside this field's box.
        """
        if grid == self.grid:
            return self
        meta = {**self.metadata, "resampled_from": list(self.grid.shape)}
        return Field(grid, resample_values(self.values, self.grid, grid), meta)

    def summary(self) -> str:
        """Min / max / mean of each field and the extent of ``T > 500 K`` as text."""
        lines = [f"grid {self.grid.shape} over {self.grid.lower} .. {self.grid.upper} m"]
        for name, v in zip(self.names, self.values, strict=True):
            mean = v.mean(dtype=np.float64)
            lines.append(f"{name:>4}: min {v.min():.6g}  max {v.max():.6g}  mean {mean:.6g}")
        lo, hi = hot_extent(self, 500.0)
        if lo is not None:
            lines.append(f"T > 500 K within {np.round(lo, 4)} .. {np.round(hi, 4)} m")
        return "\n".join(lines)

    def save(self, path) -> Path:
        """Write to a compressed ``.npz`` atomically (temporary file, then rename).

        The archive holds ``values`` (float32), ``names``, ``lower``/``upper``/``spacing`` (m),
        ``shape``, ``up_axis`` and ``metadata`` (JSON text).

        Parameters
        ----------
        path : str or os.PathLike
            Destination; parent folders are created.

        Returns
        -------
        pathlib.Path
            The path written.
        """
        return write_npz(
            path,
            values=self.values,
            names=np.array(self.names),
            lower=self.grid.lower,
            upper=self.grid.upper,
            spacing=self.grid.spacing,
            shape=np.array(self.grid.shape),
            up_axis=np.array(self.grid.up_axis),
            metadata=np.array(json.dumps(self.metadata)),
        )

    @classmethod
    def load(cls, path) -> Field:
        """Read a field written by :meth:`save`; validates it.

        Parameters
        ----------
        path : str or os.PathLike
            ``.npz`` file.

        Raises
        ------
        InputDataError
            If the file lacks an entry, has other field names, a grid that is no grid,
            metadata that are not JSON, or fails validation (the message names the path);
            :class:`~invflame.atomic_files.CorruptFileError` if it is truncated or not an
            ``.npz``. Both are ``ValueError``.
        """
        data = read_npz(path, "field file", "write it again (rerun what made it)")
        missing = {"values", "names", "lower", "upper", "shape", "up_axis"} - set(data)
        if missing:
            raise InputDataError(f"{path} is not an invflame field file: missing "
                                 f"{sorted(missing)}")
        names = tuple(str(n) for n in data["names"])
        if names not in (FIELD_NAMES, SOOTY_FIELD_NAMES):
            raise InputDataError(f"{path} holds fields {names}; expected {FIELD_NAMES}, or "
                                 f"{SOOTY_FIELD_NAMES} with soot, in that order")
        try:
            meta = json.loads(str(data["metadata"])) if "metadata" in data else {}
        except json.JSONDecodeError as err:
            raise InputDataError(f"{path}: entry 'metadata' is not JSON ({err}); write it with "
                                 "json.dumps of a dict, or leave it out") from None
        try:
            grid = VoxelGrid(data["lower"], data["upper"], tuple(int(n) for n in data["shape"]),
                             up_axis=int(data["up_axis"]))
            return cls(grid, data["values"], meta)
        except (TypeError, ValueError) as err:
            raise InputDataError(f"{path}: {err}") from None


def hot_extent(field: Field, threshold: float) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Bounding box of the voxel centres where ``T > threshold``.

    Parameters
    ----------
    field : Field
        Field to inspect.
    threshold : float
        Temperature in K.

    Returns
    -------
    (lower, upper) : numpy.ndarray, shape (3,), in m, or ``(None, None)`` if no voxel is hotter.
    """
    hot = field.T > threshold
    if not hot.any():
        return None, None
    axes = field.grid.axes()
    lo, hi = [], []
    for a in range(3):
        other = tuple(b for b in range(3) if b != a)
        idx = np.nonzero(hot.any(axis=other))[0]
        lo.append(axes[a][idx[0]])
        hi.append(axes[a][idx[-1]])
    return np.array(lo), np.array(hi)


def _overlap_matrix(src_edges: np.ndarray, dst_edges: np.ndarray) -> np.ndarray:
    """Overlap lengths ``W[j, i]`` of destination cell j with source cell i along one axis (m)."""
    lo = np.maximum(dst_edges[:-1, None], src_edges[None, :-1])
    hi = np.minimum(dst_edges[1:, None], src_edges[None, 1:])
    return np.clip(hi - lo, 0.0, None)


def resample_values(values: np.ndarray, src: VoxelGrid, dst: VoxelGrid) -> np.ndarray:
    r"""Average a field array from grid ``src`` onto grid ``dst`` by cell overlap.

    Each destination voxel gets the overlap-weighted average of the source voxels it covers,
    weighted by their molar density ``c = p / (R T)`` at uniform pressure:

    .. math::  \bar T = \frac{\sum_i w_i c_i T_i}{\sum_i w_i c_i}
               = \frac{\sum_i w_i}{\sum_i w_i / T_i}, \qquad
               \bar X_s = \frac{\sum_i w_i c_i X_{s,i}}{\sum_i w_i c_i},

    with ``w_i`` the overlap volume. So the destination voxel (at ``p`` and ``\bar T``) holds the
    same moles of gas and of each species as the source voxels: number densities, which set the
    absorption, are conserved. The temperature is the harmonic (molar) mean, a little below
    the volume mean where the temperature varies within a voxel. A soot volume fraction is
    averaged by volume, :math:`\bar f_v = \sum_i w_i f_{v,i} / \sum_i w_i`: the soot volume
    is conserved. For integer coarsening factors on the same box this is block averaging;
    refining copies values (piecewise constant).

    Parameters
    ----------
    values : numpy.ndarray, shape (4, *src.shape) or (5, *src.shape)
        ``T`` [K] then mole fractions, then optionally the soot volume fraction [1].
    src, dst : VoxelGrid
        Source and destination grids; ``dst``'s box must lie inside ``src``'s.

    Returns
    -------
    numpy.ndarray, shape (len(values), *dst.shape), float32
    """
    tol = 1e-9 * float(np.max(src.extent))
    if np.any(dst.lower < src.lower - tol) or np.any(dst.upper > src.upper + tol):
        raise ValueError(
            f"target box {dst.lower} .. {dst.upper} m must lie inside the source box "
            f"{src.lower} .. {src.upper} m; resampling does not extrapolate"
        )
    if src.up_axis != dst.up_axis:
        raise ValueError(f"up_axis differs: source {src.up_axis}, target {dst.up_axis}")
    mats = []
    for a in range(3):
        src_edges = np.linspace(src.lower[a], src.upper[a], src.shape[a] + 1)
        dst_edges = np.linspace(dst.lower[a], dst.upper[a], dst.shape[a] + 1)
        mats.append(_overlap_matrix(src_edges, dst_edges))

    def average(a: np.ndarray) -> np.ndarray:
        return np.einsum("ai,bj,ck,ijk->abc", *mats, a, optimize=True)

    v = values.astype(np.float64)
    density = 1.0 / v[0]  # molar density up to the constant p / R
    weight = average(density)
    volume = average(np.ones_like(density))
    out = np.empty((len(v), *dst.shape))
    out[0] = volume / weight
    out[1:len(FIELD_NAMES)] = np.stack([average(density * x)
                                        for x in v[1:len(FIELD_NAMES)]]) / weight
    if len(v) == len(SOOTY_FIELD_NAMES):
        out[-1] = average(v[-1]) / volume
    return out.astype(np.float32)
