r"""A measurement scene: voxel grid, cameras, gas spectroscopy and instrument, and its forward map.

:class:`Scene` ties the flame domain to the operators. From a voxel grid, a camera rig, an
absorption table (spectral window, line-by-line step, pressure) and the FTIR resolution it
builds, in one call, the voxel forward map

.. math:: H = \text{ILSConvolution} \circ \text{RowMean} \circ \text{EmissionRTE} \circ
          \text{VoxelSampling}: f \in \mathbb{R}^{4 \times n_x \times n_y \times n_z}
          \mapsto g \in \mathbb{R}^{n_\text{rays} \times n_\text{out}},

fields (T in K, mole fractions of CO2, H2O, CH4) to measured spectra in W/(m²·sr·cm⁻¹), one
per camera pixel (a "ray" of the data is a pixel; it is the mean of ``rays_per_pixel``
sub-rays spread over the pixel, :class:`operators.RowMean`), both
as a composed :class:`operators.Operator` (:attr:`Scene.operator`: jvp, vjp, Jacobian, dot
and Taylor tests) and as one jitted JAX function (:meth:`Scene.forward`, differentiable with
``jax.vjp``/``jax.grad`` through the kernel's custom VJP), which give the same numbers.

With ``devices`` given, :meth:`Scene.forward` splits the rays over several devices
(:func:`operators.sharding.shard_rays`): the fields stay replicated, each device measures its
block of rays, and gradients are summed over the devices; the numbers agree with the
one-device map to round-off. :attr:`Scene.operator` always runs on one device.
"""

from __future__ import annotations

from functools import cached_property, partial

import jax
import jax.numpy as jnp
import numpy as np

from invflame.field import validate_values
from invflame.geometry import CameraRig, RaySegments, VoxelGrid, paper_rig, traverse
from invflame.spectroscopy.absorption_table import AbsorptionTable
from operators import ILSConvolution, Operator, RowMean
from operators.emission_rte import EmissionRTE, RTETables, batch_rays_for, emission_radiance
from operators.interop import to_jax, to_numpy
from operators.sampling import VoxelSampling, sample_voxels
from operators.sharding import place_rays, ray_mesh, replicate, shard_rays


def _window_slice(wavenumber: np.ndarray, window) -> slice:
    if window is None:
        return slice(None)
    lo, hi = (float(w) for w in window)
    inside = np.flatnonzero((wavenumber >= lo - 1e-9) & (wavenumber <= hi + 1e-9))
    if inside.size < 2:
        raise ValueError(
            f"window {lo:g}-{hi:g} cm-1 holds fewer than 2 points of the table's grid "
            f"{wavenumber[0]:g}-{wavenumber[-1]:g} cm-1"
        )
    return slice(int(inside[0]), int(inside[-1]) + 1)


def _measure(batch_rays, rays_per_pixel, tables, voxel, lengths, ils, fields):
    radiance = emission_radiance(tables, sample_voxels(fields, voxel), lengths, batch_rays)
    pixels = radiance.reshape(-1, rays_per_pixel, radiance.shape[-1]).mean(axis=1)
    return jnp.matmul(pixels, ils.T, precision=jax.lax.Precision.HIGHEST)


class Scene:
    """Grid, cameras, spectroscopy and instrument of a flame-emission measurement.

    Parameters
    ----------
    grid : VoxelGrid
        Reconstruction grid (m).
    rig : CameraRig
        Cameras; their stacked pixels are the measurement rays.
    table : AbsorptionTable
        Cross-sections of (CO2, H2O, CH4) on the line-by-line grid (cm⁻¹) at one pressure
        (Pa); its grid step is the line-by-line step.
    resolution : float, optional
        FTIR resolution :math:`1/\\mathrm{MOPD}` in cm⁻¹ (default 8), see
        :mod:`operators.ils`.
    out_wavenumber : array_like, optional
        Output grid in cm⁻¹ (default :func:`operators.ils.default_output_grid`).
    window : (float, float), optional
        Sub-window of the table's grid to use, in cm⁻¹ (default: all of it).
    dtype : numpy dtype, optional
        float32 (default, fast) or float64 (derivative checks).
    planck : {"table", "exact"}, optional
        Planck's law as a spline or exact, see :class:`operators.emission_rte.RTETables`.
    memory_budget : int, optional
        Bytes for one batch of rays in the emission kernel (default: per JAX backend).
    batch_rays : int, optional
        Rays per batch, overriding ``memory_budget``.
    devices : int, sequence of jax.Device or jax.sharding.Mesh, optional
        Split the rays of :meth:`forward` over these devices (see
        :func:`operators.sharding.ray_mesh`; an int: the first ``n`` devices). Default
        ``None``: one device, no sharding.
    rays_per_pixel : int, optional
        Sub-rays per pixel, ``k²`` for a ``k × k`` stratified subdivision of the pixel (default
        1; :meth:`paper` and configurations use 9). A pixel's spectrum is the mean of its
        sub-rays'; one ray per pixel leaves voxels between the pixels' centre rays unseen
        (:func:`invflame.geometry.ray_coverage`).

    Attributes
    ----------
    segments : RaySegments
        Voxels and path lengths (m) of every sub-ray, ``n_rays · rays_per_pixel`` rows,
        pixel-major (the sub-rays of pixel ``p`` are rows ``p·rays_per_pixel`` onwards).
    wavenumber : ndarray, shape (n_eta,)
        Line-by-line grid in cm⁻¹.
    out_wavenumber : ndarray, shape (n_out,)
        Instrument output grid in cm⁻¹.
    mesh : jax.sharding.Mesh or None
        Devices the rays of :meth:`forward` are split over (``None``: not sharded).
    """

    def __init__(self, grid: VoxelGrid, rig: CameraRig, table: AbsorptionTable,
                 resolution: float = 8.0, out_wavenumber=None, window=None,
                 dtype=np.float32, planck: str = "table", memory_budget: int | None = None,
                 batch_rays: int | None = None, devices=None, rays_per_pixel: int = 1):
        if not isinstance(grid, VoxelGrid):
            raise TypeError(f"grid must be an invflame.geometry.VoxelGrid, got {type(grid)}")
        if not isinstance(rig, CameraRig):
            raise TypeError(f"rig must be an invflame.geometry.CameraRig, got {type(rig)}")
        self.grid, self.rig, self.table = grid, rig, table
        self.dtype = np.dtype(dtype)
        self.planck = planck
        self.memory_budget = memory_budget
        band = _window_slice(table.wavenumber, window)
        self.wavenumber = table.wavenumber[band]
        self._coef = table.spline.coef[..., band]
        self.rays_per_pixel = int(rays_per_pixel)
        self.segments: RaySegments = traverse(grid, *rig.rays(rays_per_pixel))
        self.ils = ILSConvolution(self.wavenumber, self.n_rays, resolution, out_wavenumber,
                                  dtype=self.dtype)
        self.out_wavenumber = self.ils.out_wavenumber
        self.tables = RTETables.from_spline(self.wavenumber, table.temperatures, self._coef,
                                            table.pressure, self.dtype, planck)
        self.mesh = None if devices is None else ray_mesh(devices)
        n_traced = self.segments.n_rays
        rays_per_device = n_traced if self.mesh is None else -(-n_traced
                                                               // self.mesh.devices.size)
        self.batch_rays = int(batch_rays or batch_rays_for(self.tables, rays_per_device,
                                                           memory_budget))
        measure = partial(_measure, self.batch_rays, self.rays_per_pixel)
        rays = (self.segments.voxel, self.segments.length.astype(self.dtype))
        ils_matrix = np.asarray(self.ils.matrix, self.dtype)
        if self.mesh is None:
            self._arrays = (self.tables, *(jnp.asarray(a) for a in rays),
                            jnp.asarray(ils_matrix))
            self._measure = jax.jit(measure)
        else:  # constants cut and placed once: rays split, tables and instrument replicated
            # whole pixels per device: pad with copies of the last sub-ray (outputs dropped)
            pad = self.rays_per_pixel * (-self.n_rays % self.mesh.devices.size)
            rays = tuple(np.pad(a, [(0, pad), (0, 0)], mode="edge") for a in rays)
            self._arrays = (replicate(self.tables, self.mesh), *place_rays(rays, 0, self.mesh),
                            replicate(ils_matrix, self.mesh))
            sharded = shard_rays(measure, ray_axes=(None, 0, 0, None, None), devices=self.mesh)
            self._measure = jax.jit(lambda *args: sharded(*args)[:self.n_rays])

    @classmethod
    def paper(cls, n_cells: int = 60, n_pixels: int = 32, table: AbsorptionTable | None = None,
              rays_per_pixel: int = 9, **kwargs) -> Scene:
        """The study's configuration: 1 m cube of ``n_cells``³ voxels (y up), four cameras of
        ``n_pixels``² pixels at 1.5 m, 650–725 cm⁻¹ at 0.04 cm⁻¹, 8 cm⁻¹ resolution.

        Parameters
        ----------
        n_cells, n_pixels : int, optional
            Grid cells per axis and pixels per image side.
        rays_per_pixel : int, optional
            Sub-rays per pixel (default 9 = 3 × 3: with the pixel footprint about 2.9 voxels
            wide, every voxel is crossed; one ray per pixel leaves 46 % of the 60³ voxels
            unseen, ``benchmarks/ray_coverage.py``).
        table : AbsorptionTable, optional
            Default :meth:`AbsorptionTable.default` (built once, then cached on disk).
        **kwargs
            Passed to :class:`Scene` (``dtype``, ``resolution``, ...).
        """
        grid = VoxelGrid.poolfire(n_cells)
        table = AbsorptionTable.default() if table is None else table
        return cls(grid, paper_rig(grid, n_pixels=n_pixels), table,
                   rays_per_pixel=rays_per_pixel, **kwargs)

    # -- sizes ---------------------------------------------------------------------------
    @property
    def n_rays(self) -> int:
        """Number of measured spectra: pixels over all cameras."""
        return self.rig.n_rays

    @property
    def pressure(self) -> float:
        """Pressure in Pa (the table's)."""
        return self.table.pressure

    @property
    def step(self) -> float:
        """Line-by-line step in cm⁻¹."""
        return float(self.wavenumber[1] - self.wavenumber[0])

    @property
    def resolution(self) -> float:
        """FTIR resolution in cm⁻¹."""
        return self.ils.resolution

    @property
    def field_shape(self) -> tuple[int, int, int, int]:
        """Input shape ``(4, nx, ny, nz)``: T (K), then mole fractions of CO2, H2O, CH4."""
        return (1 + len(self.table.species), *self.grid.shape)

    @property
    def data_shape(self) -> tuple[int, int]:
        """Output shape ``(n_rays, n_out)``."""
        return (self.n_rays, self.out_wavenumber.size)

    # -- the forward map -------------------------------------------------------------------
    @cached_property
    def sampling(self) -> VoxelSampling:
        """Voxel fields → fields on the ray segments."""
        return VoxelSampling(self.segments.voxel, self.grid.shape, self.field_shape[0],
                             dtype=self.dtype)

    @cached_property
    def emission(self) -> EmissionRTE:
        """Fields on the ray segments → line-by-line radiance ``(n_rays, n_eta)``."""
        return EmissionRTE(self.wavenumber, self.table.temperatures, self._coef,
                           self.segments.length, self.pressure, self.dtype, self.planck,
                           batch_rays=self.batch_rays)

    @cached_property
    def pixel_mean(self) -> RowMean:
        """Sub-ray spectra ``(n_rays · rays_per_pixel, n_eta)`` → pixel spectra ``(n_rays,
        n_eta)``."""
        return RowMean(self.n_rays, self.rays_per_pixel, self.wavenumber.size, dtype=self.dtype)

    @cached_property
    def operator(self) -> Operator:
        """``ILSConvolution @ RowMean @ EmissionRTE @ VoxelSampling``: ``field_shape →
        data_shape`` (the mean over sub-rays is left out with one ray per pixel)."""
        if self.rays_per_pixel == 1:
            return self.ils @ self.emission @ self.sampling
        return self.ils @ self.pixel_mean @ self.emission @ self.sampling

    def forward(self, fields):
        """Measured spectra ``(n_rays, n_out)`` in W/(m²·sr·cm⁻¹), one jitted JAX call.

        Parameters
        ----------
        fields : array_like, shape ``field_shape``
            T in K and mole fractions; NumPy, JAX or torch.

        Returns
        -------
        jax.Array
            Differentiable with :func:`jax.vjp`/:func:`jax.grad` (reverse mode).
        """
        fields = to_jax(fields, dtype=self.dtype)
        if fields.shape != self.field_shape:
            raise ValueError(f"fields must have shape {self.field_shape}, got {fields.shape}")
        return self._measure(*self._arrays, fields)

    def simulate(self, fields) -> np.ndarray:
        """:meth:`forward` as a NumPy array, for fields checked by :meth:`check_fields`."""
        return to_numpy(self.forward(self.check_fields(fields)))

    def check_fields(self, fields) -> np.ndarray:
        """``fields`` as a NumPy array, if it is a physical state the tables cover.

        Raises
        ------
        ValueError
            For what :func:`invflame.field.validate_values` refuses (a wrong shape, NaN, T ≤ 0,
            a mole fraction outside [0, 1], mole fractions summing above 1) and for a
            temperature outside the absorption table's range (K); the message names the field
            and the offending values.
        """
        fields = to_numpy(fields)
        validate_values(fields, self.grid)
        t_min, t_max = float(self.table.temperatures[0]), float(self.table.temperatures[-1])
        if fields[0].min() < t_min or fields[0].max() > t_max:
            raise ValueError(f"temperature spans {fields[0].min():g}-{fields[0].max():g} K, "
                             f"outside the absorption table's {t_min:g}-{t_max:g} K")
        return fields

    def to_images(self, values) -> np.ndarray:
        """Per-ray values ``(n_rays, …)`` as images ``(n_cameras, nv, nu, …)``."""
        return self.rig.to_images(values)
