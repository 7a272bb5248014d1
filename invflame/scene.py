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
:class:`operators.Operator` (:class:`operators.rte.operator.KernelOperator`: jvp, vjp,
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

A scene is built from one immutable :class:`~invflame.scene_settings.SceneSettings`
(:attr:`Scene.settings`); :meth:`Scene.replace` builds a new scene from changed settings, so
nothing the old one derived (rays, tables, operators, cached pieces) can go stale.
"""

from __future__ import annotations

import dataclasses
from functools import cached_property, partial

import jax
import jax.numpy as jnp
import numpy as np

from invflame.background import Background
from invflame.errors import GeometryError
from invflame.field import validate_values
from invflame.geometry import CameraRig, RaySegments, VoxelGrid, paper_rig, traverse
from invflame.measurement import channel_mask
from invflame.scene_settings import SceneSettings
from invflame.spectroscopy.absorption_table import AbsorptionTable
from operators import ILSConvolution
from operators.base import precision
from operators.interop import to_jax, to_numpy
from operators.jax_precision import check_precision
from operators.rte import EmissionRTE, KernelOperator, RTETables, batch_rays_for
from operators.rte.tables import rayleigh_soot_constant
from operators.sampling import VoxelSampling, sample_voxels
from operators.sharding import place_rays, ray_mesh, replicate, shard_rays


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


_HANDED_ON = {"segments": {"grid", "rig", "rays_per_pixel"},
              "tables": {"table", "window", "dtype", "planck", "soot", "soot_input",
                         "soot_constant"}}
"""The pieces :meth:`Scene.replace` hands on to the new scene, each with the settings it is
computed from: a piece is handed on only when none of these settings changes."""


class Scene:
    r"""Grid, cameras, spectroscopy and instrument of a flame-emission measurement.

    Parameters
    ----------
    grid, rig, table
        The reconstruction grid, the cameras and the absorption table, see
        :class:`~invflame.scene_settings.SceneSettings`.
    **settings
        The other settings by keyword (``resolution``, ``out_wavenumber``, ``window``,
        ``dtype``, ``planck``, ``memory_budget``, ``batch_rays``, ``devices``,
        ``rays_per_pixel``, ``background``, ``soot``, ``soot_constant``, ``soot_input``,
        ``camera_windows``), as there.

    Attributes
    ----------
    settings : invflame.scene_settings.SceneSettings
        What the scene is built from; the attributes below derive from it.
    segments : RaySegments
        Voxels and path lengths (m) of every sub-ray, ``n_rays · rays_per_pixel`` rows,
        pixel-major (the sub-rays of pixel ``p`` are rows ``p·rays_per_pixel`` onwards).
    wavenumber : ndarray, shape (n_eta,)
        Line-by-line grid in cm⁻¹.
    out_wavenumber : ndarray, shape (n_out,)
        Instrument output grid in cm⁻¹.
    tables : operators.rte.tables.RTETables
        The emission kernel's tables, prepared once for all of the scene's maps.
    operator : operators.rte.operator.KernelOperator
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
    camera_windows : tuple of ((float, float) or None), or None
        Each camera's own spectral window in cm⁻¹ (:attr:`measured_channels`).
    """

    def __init__(self, grid: VoxelGrid, rig: CameraRig, table: AbsorptionTable, **settings):
        self._assemble(SceneSettings(grid, rig, table, **settings), {})

    def _assemble(self, settings: SceneSettings, handed_on: dict) -> None:
        """Build the scene of ``settings``, taking the pieces in ``handed_on`` (see
        :data:`_HANDED_ON`) as they are."""
        self.settings = s = settings
        self.grid, self.rig, self.table = s.grid, s.rig, s.table
        self.dtype, self.planck, self.memory_budget = s.dtype, s.planck, s.memory_budget
        self.rays_per_pixel, self.background = s.rays_per_pixel, s.background
        self.soot, self.soot_input, self.camera_windows = s.soot, s.soot_input, s.camera_windows
        self.wavenumber = s.table.wavenumber[s.band]
        self.segments: RaySegments = (handed_on["segments"] if "segments" in handed_on
                                      else self._traced())
        self.ils = ILSConvolution(self.wavenumber, self.n_rays, s.resolution, s.out_wavenumber,
                                  dtype=self.dtype)
        self.out_wavenumber = self.ils.out_wavenumber
        self.tables: RTETables = handed_on["tables"] if "tables" in handed_on else self._tables()
        self.mesh = None if s.devices is None else ray_mesh(s.devices)
        n_traced = self.segments.n_rays
        rays_per_device = n_traced if self.mesh is None else -(-n_traced
                                                               // self.mesh.devices.size)
        self.batch_rays = int(s.batch_rays or batch_rays_for(self.tables, rays_per_device,
                                                             s.memory_budget))
        self.operator = self._operator()

    def _tables(self) -> RTETables:
        """The kernel's tables on the scene's window, with a soot row when it has soot."""
        s = self.settings
        constant = rayleigh_soot_constant() if s.soot_constant is None else s.soot_constant
        return s.table.kernel_tables(s.band, self.dtype, self.planck,
                                     soot=constant if s.sooty else None)

    def _traced(self) -> RaySegments:
        """The segments of every sub-ray through the grid, if any ray crosses it."""
        segments = traverse(self.grid, *self.rig.rays(self.rays_per_pixel))
        if not segments.hit.any():
            raise GeometryError(
                f"no ray of the {self.rig.n_cameras} camera(s) crosses the grid "
                f"{self.grid.lower.tolist()}-{self.grid.upper.tolist()} m: point the cameras "
                "at the grid (look_at its centre) or widen their sensors")
        return segments

    def replace(self, **changes) -> Scene:
        """A new scene of these settings with ``changes``; the traced rays and the kernel's
        tables are shared with this scene when the settings they come from stay the same.

        Parameters
        ----------
        **changes
            New values of settings (see :class:`~invflame.scene_settings.SceneSettings`),
            e.g. ``background=BlackbodyWall(300.0)`` or ``soot=None, soot_input=True``.

        Raises
        ------
        TypeError
            For a name that is not a setting.
        """
        names = {f.name for f in dataclasses.fields(SceneSettings) if f.init}
        if unknown := sorted(set(changes) - names):
            raise TypeError(f"Scene.replace: {unknown} are not settings of a scene; the "
                            f"settings are {sorted(names)}")
        scene = type(self).__new__(type(self))
        scene._assemble(dataclasses.replace(self.settings, **changes),
                        {piece: getattr(self, piece) for piece, needs in _HANDED_ON.items()
                         if needs.isdisjoint(changes)})
        return scene

    def with_background(self, background: Background | None) -> Scene:
        """:meth:`replace` with another ``background`` (None: none)."""
        return self.replace(background=background)

    def with_soot(self, soot, soot_constant: float | None = None,
                  soot_input: bool = False) -> Scene:
        """:meth:`replace` with another known ``soot`` field (None: none) or with
        ``soot_input``, the soot volume fraction as a fifth input field, and
        ``soot_constant``, as for :class:`~invflame.scene_settings.SceneSettings`."""
        return self.replace(soot=soot, soot_constant=soot_constant, soot_input=soot_input)

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
            unseen, ``studies/ray_coverage.py``).
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

    @property
    def measured_channels(self) -> np.ndarray:
        """The output channels each pixel measures, those inside its camera's window: bool,
        :attr:`data_shape` (all True without :attr:`camera_windows`)."""
        return channel_mask(self.rig, self.camera_windows, self.out_wavenumber)

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
            For what :func:`invflame.field.validate_values` refuses (a shape other than
            :attr:`field_shape`, NaN, T ≤ 0, a mole fraction outside [0, 1], mole fractions
            summing above 1, a soot volume fraction outside [0, 1)) and for a temperature
            outside the absorption table's range (K); the message names the field and the
            offending values.
        """
        fields = to_numpy(fields)
        validate_values(fields, self.grid, mixture=mixture, soot=self.soot_input)
        self.tables.check_temperature(fields[0], "Scene")
        return fields

    def to_images(self, values) -> np.ndarray:
        """Per-ray values ``(n_rays, …)`` as images ``(n_cameras, nv, nu, …)``."""
        return self.rig.to_images(values)
