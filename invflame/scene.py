r"""A measurement scene: voxel grid, cameras, gas spectroscopy and instrument, and its forward map.

:class:`Scene` ties the flame domain to the operators. From a voxel grid, a camera rig, an
absorption table (spectral window, line-by-line step, pressure) and the FTIR resolution it
builds, in one call, the voxel forward map

.. math:: H = \text{ILSConvolution} \circ \text{RowMean} \circ \text{EmissionRTE} \circ
          \text{VoxelSampling}: f \in \mathbb{R}^{4 \times n_x \times n_y \times n_z}
          \mapsto g \in \mathbb{R}^{n_\text{rays} \times n_\text{out}},

fields (T in K, mole fractions of CO2, H2O, CH4) to measured spectra in W/(m²·sr·cm⁻¹), one
per camera pixel (a "ray" of the data is a pixel; it is the mean of ``rays_per_pixel``
sub-rays spread over the pixel). The map is one JAX function around the emission kernel
(gather onto the segments, kernel, mean over sub-rays, lineshape), and everything evaluates
that one function: :meth:`Scene.forward` (jitted, differentiable with ``jax.vjp``/``jax.grad``
through the kernel's custom VJP), :meth:`Scene.simulate` (the fields checked, then
:meth:`~Scene.forward`) and :attr:`Scene.operator`, the same function as an
:class:`operators.Operator` (:class:`operators.emission_rte.KernelOperator`: jvp, vjp,
Jacobian, dot and Taylor tests). The pieces stay available as operators of their own
(:attr:`Scene.sampling`, :attr:`Scene.emission`, :attr:`Scene.ils`) on the same tables.

With a ``background`` (:mod:`invflame.background`: a black-body wall or measured spectra per
camera), every sub-ray of a camera ends on that camera's background, which the kernel adds
through the ray's transmittance, :math:`I = I_\text{flame} + \tau_\text{ray} I_\text{bg}`;
without one (the default) the numbers are those of a flame against a cold, black background.

With ``devices`` given, the map splits the rays over several devices
(:func:`operators.sharding.shard_rays`): the fields stay replicated, each device measures its
block of rays, and gradients are summed over the devices; the numbers agree with the
one-device map to round-off. :meth:`Scene.forward` and :attr:`Scene.operator` both run so.
"""

from __future__ import annotations

import copy
from functools import cached_property, partial

import jax
import jax.numpy as jnp
import numpy as np

from invflame.background import Background
from invflame.errors import GeometryError
from invflame.field import validate_values
from invflame.geometry import CameraRig, RaySegments, VoxelGrid, paper_rig, traverse
from invflame.spectroscopy.absorption_table import AbsorptionTable
from operators import ILSConvolution
from operators.base import check_precision, precision
from operators.emission_rte import EmissionRTE, KernelOperator, RTETables, batch_rays_for
from operators.interop import to_jax, to_numpy
from operators.rte_tables import rayleigh_soot_constant
from operators.sampling import VoxelSampling, sample_voxels
from operators.sharding import place_rays, ray_mesh, replicate, shard_rays


def _checked_soot(soot, grid: VoxelGrid) -> np.ndarray:
    """A soot volume fraction field as float64, if its shape and values are usable."""
    soot = np.asarray(soot, np.float64)
    if soot.shape != grid.shape:
        raise ValueError(f"soot must be a volume fraction per voxel of shape {grid.shape}, got "
                         f"{soot.shape}")
    if not (np.all(np.isfinite(soot)) and soot.min() >= 0 and soot.max() < 1):
        raise ValueError(f"soot volume fractions must be finite and in [0, 1), got "
                         f"{np.nanmin(soot):g} to {np.nanmax(soot):g}")
    return soot


def _soot_setting(soot, soot_input: bool, grid: VoxelGrid) -> tuple[np.ndarray | None, bool]:
    """The known soot field (checked) and whether soot is an input field; not both."""
    if soot is not None and soot_input:
        raise ValueError("give either a known soot field (soot) or soot as an input field "
                         "(soot_input=True), not both")
    return (None if soot is None else _checked_soot(soot, grid)), bool(soot_input)


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


def _measure(radiance, rays_per_pixel, tables, voxel, lengths, camera, ils, shared, fields):
    """Pixel spectra ``(n_pixels, n_out)`` of voxel fields, ``radiance`` the emission kernel.

    ``camera`` (the camera of each sub-ray, or None) picks each sub-ray's background from
    ``shared["background"]`` ``(n_cameras, n_eta)``; ``shared["soot"]`` ``(nx, ny, nz)``, when
    there, is appended to the fields as the soot volume fraction.
    """
    if "soot" in shared:
        fields = jnp.concatenate([fields, shared["soot"][None]])
    background = None if camera is None else shared["background"][camera]
    radiance = radiance(tables, sample_voxels(fields, voxel), lengths, background)
    pixels = radiance.reshape(-1, rays_per_pixel, radiance.shape[-1]).mean(axis=1)
    return jnp.matmul(pixels, ils.T, precision=jax.lax.Precision.HIGHEST)


class Scene:
    r"""Grid, cameras, spectroscopy and instrument of a flame-emission measurement.

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
        FTIR resolution :math:`1/\mathrm{MOPD}` in cm⁻¹ (default 8), see
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
    background : invflame.background.Background, optional
        What the cameras see behind the flame (a black-body wall, measured spectra per
        camera); default None, no background.
    soot : array_like, shape ``grid.shape``, optional
        A known soot volume fraction per voxel (dimensionless, in [0, 1)), absorbing and
        emitting the Rayleigh continuum :math:`C f_v \eta` beside the gas
        (:mod:`operators.rte_tables`); default None, no soot. It is held fixed: the map's
        input stays (T, mole fractions).
    soot_constant : float, optional
        The Rayleigh constant :math:`C` of the soot
        (default :func:`operators.rte_tables.rayleigh_soot_constant`).
    soot_input : bool, optional
        True: the soot volume fraction is a fifth field of the map's input, after the mole
        fractions (:attr:`field_shape` ``(5, nx, ny, nz)``), to be reconstructed; the map then
        differentiates with respect to it too. Not with ``soot``. Default False.

    Attributes
    ----------
    segments : RaySegments
        Voxels and path lengths (m) of every sub-ray, ``n_rays · rays_per_pixel`` rows,
        pixel-major (the sub-rays of pixel ``p`` are rows ``p·rays_per_pixel`` onwards).
    wavenumber : ndarray, shape (n_eta,)
        Line-by-line grid in cm⁻¹.
    out_wavenumber : ndarray, shape (n_out,)
        Instrument output grid in cm⁻¹.
    tables : operators.emission_rte.RTETables
        The emission kernel's tables, prepared once for all of the scene's maps.
    operator : operators.emission_rte.KernelOperator
        The voxel forward map ``field_shape → data_shape`` as an operator: the function of
        :meth:`forward`, with its jvp, vjp and Jacobian.
    mesh : jax.sharding.Mesh or None
        Devices the rays are split over (``None``: not sharded).
    background : invflame.background.Background or None
        The background behind the flame.
    soot : ndarray, shape ``grid.shape``, or None
        The known soot volume fraction.
    soot_input : bool
        Whether the soot volume fraction is the fifth field of the input.
    """

    def __init__(self, grid: VoxelGrid, rig: CameraRig, table: AbsorptionTable,
                 resolution: float = 8.0, out_wavenumber=None, window=None,
                 dtype=np.float32, planck: str = "table", memory_budget: int | None = None,
                 batch_rays: int | None = None, devices=None, rays_per_pixel: int = 1,
                 background: Background | None = None, soot=None,
                 soot_constant: float | None = None, soot_input: bool = False):
        if not isinstance(grid, VoxelGrid):
            raise TypeError(f"grid must be an invflame.geometry.VoxelGrid, got {type(grid)}")
        if not isinstance(rig, CameraRig):
            raise TypeError(f"rig must be an invflame.geometry.CameraRig, got {type(rig)}")
        self.grid, self.rig, self.table = grid, rig, table
        self.dtype = np.dtype(dtype)
        self.planck = planck
        self.memory_budget = memory_budget
        self._band = _window_slice(table.wavenumber, window)
        self.wavenumber = table.wavenumber[self._band]
        self.rays_per_pixel = int(rays_per_pixel)
        self.segments: RaySegments = traverse(grid, *rig.rays(rays_per_pixel))
        if not self.segments.hit.any():
            raise GeometryError(
                f"no ray of the {rig.n_cameras} camera(s) crosses the grid {grid.lower.tolist()}"
                f"-{grid.upper.tolist()} m: point the cameras at the grid (look_at its centre) "
                "or widen their sensors")
        self.ils = ILSConvolution(self.wavenumber, self.n_rays, resolution, out_wavenumber,
                                  dtype=self.dtype)
        self.out_wavenumber = self.ils.out_wavenumber
        self.soot, self.soot_input = _soot_setting(soot, soot_input, grid)
        self.tables = self._tables(soot_constant)
        self.mesh = None if devices is None else ray_mesh(devices)
        n_traced = self.segments.n_rays
        rays_per_device = n_traced if self.mesh is None else -(-n_traced
                                                               // self.mesh.devices.size)
        self.batch_rays = int(batch_rays or batch_rays_for(self.tables, rays_per_device,
                                                           memory_budget))
        if background is not None and not isinstance(background, Background):
            raise TypeError(f"background must be an invflame.background.Background (e.g. "
                            f"BlackbodyWall(T, emissivity)), got {type(background).__name__}")
        self.background = background
        self.operator = self._operator()

    def _tables(self, soot_constant: float | None) -> RTETables:
        """The kernel's tables on the scene's window, with a soot row when it has soot."""
        sooty = self.soot is not None or self.soot_input
        if sooty and soot_constant is None:
            soot_constant = rayleigh_soot_constant()
        return self.table.kernel_tables(self._band, self.dtype, self.planck,
                                        soot=soot_constant if sooty else None)

    def _operator(self) -> KernelOperator:
        """The forward map on the scene's rays, tables, instrument and background."""
        camera = None if self.background is None else self._sub_ray_camera()
        rays = [self.segments.voxel, self.segments.length.astype(self.dtype), camera]
        shared = {}
        if self.background is not None:
            shared["background"] = self.background.on_grid(self.wavenumber, self.rig.n_cameras
                                                           ).astype(self.dtype)
        if self.soot is not None:
            shared["soot"] = self.soot.astype(self.dtype)
        constants = [np.asarray(self.ils.matrix, self.dtype), shared]
        with precision(self.dtype):
            if self.mesh is None:
                arrays = (self.tables, *jax.tree_util.tree_map(jnp.asarray, rays + constants))
            else:  # constants cut and placed once: rays split, tables and instrument replicated
                # whole pixels per device: pad with copies of the last sub-ray (outputs dropped)
                pad = self.rays_per_pixel * (-self.n_rays % self.mesh.devices.size)
                rays = jax.tree_util.tree_map(
                    lambda a: np.pad(a, [(0, pad)] + [(0, 0)] * (a.ndim - 1), mode="edge"), rays)
                arrays = (replicate(self.tables, self.mesh), *place_rays(rays, 0, self.mesh),
                          *replicate(constants, self.mesh))
        return KernelOperator(self._measurement, arrays, self.batch_rays, self.field_shape,
                              self.data_shape, self.dtype, "Scene",
                              domain=partial(self.check_fields, mixture=False))

    def _sub_ray_camera(self) -> np.ndarray:
        """The camera (index in the rig) of every traced sub-ray, ``(n_rays · rays_per_pixel,)``."""
        sub_rays = np.diff(self.rig.ray_offsets) * self.rays_per_pixel
        return np.repeat(np.arange(self.rig.n_cameras), sub_rays)

    def with_background(self, background: Background | None) -> Scene:
        """The same scene (rays, tables, instrument, devices) in front of another background.

        Parameters
        ----------
        background : invflame.background.Background or None
            The new background (None: none).
        """
        if background is not None and not isinstance(background, Background):
            raise TypeError(f"background must be an invflame.background.Background, got "
                            f"{type(background).__name__}")
        scene = copy.copy(self)
        scene.__dict__.pop("emission", None)
        scene.background = background
        scene.operator = scene._operator()
        return scene

    def with_soot(self, soot, soot_constant: float | None = None,
                  soot_input: bool = False) -> Scene:
        """The same scene (rays, instrument, background, devices) with another known soot
        field, or with the soot volume fraction as a fifth input field.

        Parameters
        ----------
        soot : array_like, shape ``grid.shape``, or None
            Soot volume fraction per voxel (dimensionless, in [0, 1)); None: no known soot.
        soot_constant : float, optional
            As for :class:`Scene`.
        soot_input : bool, optional
            As for :class:`Scene` (not with ``soot``).
        """
        scene = copy.copy(self)
        for cached in ("emission", "sampling"):
            scene.__dict__.pop(cached, None)
        scene.soot, scene.soot_input = _soot_setting(soot, soot_input, self.grid)
        scene.tables = scene._tables(soot_constant)
        scene.operator = scene._operator()
        return scene

    def _measurement(self, radiance):
        """The map ``(tables, voxel, lengths, camera, ils, shared, fields) -> spectra`` on the
        kernel ``radiance`` (:func:`_measure`), split over :attr:`mesh` when there is one."""
        measure = partial(_measure, radiance, self.rays_per_pixel)
        if self.mesh is None:
            return measure
        sharded = shard_rays(measure, ray_axes=(None, 0, 0, 0, None, None, None),
                             devices=self.mesh)
        return lambda *args: sharded(*args)[:self.n_rays]

    @classmethod
    def paper(cls, n_cells: int = 60, n_pixels: int = 32, table: AbsorptionTable | None = None,
              rays_per_pixel: int = 9, **kwargs) -> Scene:
        """The study's configuration: 1 m cube of ``n_cells**3`` voxels (y up), four cameras
        of ``n_pixels**2`` pixels at 1.5 m, 650–725 cm⁻¹ at 0.04 cm⁻¹, 8 cm⁻¹ resolution.

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
        """Input shape ``(4, nx, ny, nz)``: T (K), then mole fractions of CO2, H2O, CH4; with
        :attr:`soot_input` ``(5, nx, ny, nz)``, the soot volume fraction (1) last."""
        return (1 + len(self.table.species) + int(self.soot_input), *self.grid.shape)

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
        """Fields on the ray segments → line-by-line radiance ``(n_rays · rays_per_pixel,
        n_eta)``, on the scene's tables, in front of its background (with soot, its input
        has the soot volume fraction as a fifth field)."""
        background = None
        if self.background is not None:
            per_camera = self.background.on_grid(self.wavenumber, self.rig.n_cameras)
            background = per_camera[self._sub_ray_camera()]
        return EmissionRTE.from_tables(self.tables, self.segments.length,
                                       batch_rays=self.batch_rays, background=background)

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

        Raises
        ------
        ValueError
            For fields of another shape, and for a float64 scene while JAX's 64-bit mode is
            off (call inside :func:`operators.base.precision`, or with ``jax_enable_x64``).
        """
        check_precision(self.dtype, "this scene")
        fields = to_jax(fields, dtype=self.dtype)
        if fields.shape != self.field_shape:
            raise ValueError(f"fields must have shape {self.field_shape}, got {fields.shape}")
        return self.operator.function(*self.operator.args, fields)

    def simulate(self, fields) -> np.ndarray:
        """:meth:`forward` as a NumPy array, for fields checked by :meth:`check_fields`, in the
        scene's dtype (float64 inside :func:`operators.base.precision`)."""
        fields = self.check_fields(fields)
        with precision(self.dtype):
            return to_numpy(self.forward(fields))

    def check_fields(self, fields, mixture: bool = True) -> np.ndarray:
        """``fields`` as a NumPy array, if it is a physical state the tables cover.

        The forward map (:attr:`operator`) checks every point it is evaluated or linearized at
        so, with ``mixture=False``: solvers bound each field to its own range, and their
        iterates may pass through mole fractions summing above 1, where the model is still
        defined (absorption is linear in each mole fraction).

        Parameters
        ----------
        fields : array_like, shape :attr:`field_shape`
            T in K, mole fractions and, with soot as an input, the soot volume fraction.
        mixture : bool, optional
            Also refuse mole fractions summing above 1 (default).

        Raises
        ------
        ValueError
            For what :func:`invflame.field.validate_values` refuses (a wrong shape, NaN, T ≤ 0,
            a mole fraction outside [0, 1], mole fractions summing above 1, a soot volume
            fraction outside [0, 1)), for another number of fields than :attr:`field_shape`
            and for a temperature outside the absorption table's range (K); the message names
            the field and the offending values.
        """
        fields = to_numpy(fields)
        validate_values(fields, self.grid, mixture=mixture)
        if fields.shape != self.field_shape:
            soot = "with" if self.soot_input else "without"
            raise ValueError(f"fields must have shape {self.field_shape} (a scene {soot} soot "
                             f"as an input field), got {fields.shape}")
        self.tables.check_temperature(fields[0], "Scene")
        return fields

    def to_images(self, values) -> np.ndarray:
        """Per-ray values ``(n_rays, …)`` as images ``(n_cameras, nv, nu, …)``."""
        return self.rig.to_images(values)
