r"""What a measurement scene is made of, as one immutable object: :class:`SceneSettings`.

A :class:`~invflame.scene.Scene` is built from its settings alone: the voxel grid, the cameras,
the absorption table and its window, the instrument, the numerics (dtype, Planck's law, batches,
devices, sub-rays per pixel), the background and the soot. The settings check what they can
without tracing a ray or building a table; :meth:`~invflame.scene.Scene.replace` makes a new
scene of changed settings, so nothing a scene derives outlives the settings it came from.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from invflame.background import Background
from invflame.field import validate_soot
from invflame.geometry import CameraRig, VoxelGrid
from invflame.spectroscopy.absorption_table import AbsorptionTable


@dataclass(frozen=True, eq=False)
class SceneSettings:
    r"""Grid, cameras, spectroscopy, instrument, numerics, background and soot of a scene.

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
        Planck's law as a spline or exact, see :class:`operators.rte.tables.RTETables`.
    memory_budget : int, optional
        Bytes for one batch of rays in the emission kernel (default: per JAX backend).
    batch_rays : int, optional
        Rays per batch, overriding ``memory_budget``.
    devices : int, sequence of jax.Device or jax.sharding.Mesh, optional
        Split the rays of the forward map over these devices (see
        :func:`operators.sharding.ray_mesh`; an int: the first ``n`` devices). Default
        ``None``: one device, no sharding.
    rays_per_pixel : int, optional
        Sub-rays per pixel, ``k²`` for a ``k × k`` stratified subdivision of the pixel (default
        1; :meth:`~invflame.scene.Scene.paper` and configurations use 9). A pixel's spectrum
        is the mean of its sub-rays'; one ray per pixel leaves voxels between the pixels'
        centre rays unseen (:func:`invflame.geometry.ray_coverage`).
    background : invflame.background.Background, optional
        What the cameras see behind the flame (a black-body wall, measured spectra per
        camera); default None, no background.
    soot : array_like, shape ``grid.shape``, optional
        A known soot volume fraction per voxel (dimensionless, in [0, 1)), absorbing and
        emitting the Rayleigh continuum :math:`C f_v \eta` beside the gas
        (:mod:`operators.rte.tables`); default None, no soot. It is held fixed: the map's
        input stays (T, mole fractions). Kept as a read-only float64 copy.
    soot_constant : float, optional
        The Rayleigh constant :math:`C` of the soot
        (default :func:`operators.rte.tables.rayleigh_soot_constant`).
    soot_input : bool, optional
        True: the soot volume fraction is a fifth field of the map's input, after the mole
        fractions (field shape ``(5, nx, ny, nz)``), to be reconstructed; the map then
        differentiates with respect to it too. Not with ``soot``. Default False.
    camera_windows : sequence of ((float, float) or None), optional
        Each camera's own spectral window ``(min, max)`` in cm⁻¹, None for a camera that
        measures every output channel (:mod:`invflame.measurement`); default None, every
        camera measures every channel. The map renders every channel for every pixel; the
        windows say which of them are data
        (:attr:`~invflame.scene.Scene.measured_channels`).

    Attributes
    ----------
    band : slice
        The bins of the table's grid inside ``window``.

    Raises
    ------
    TypeError
        For a grid, rig or background of another type.
    ValueError
        For a window holding fewer than 2 points of the table's grid, a soot field of another
        shape or outside [0, 1), for both ``soot`` and ``soot_input``, and for camera windows
        that are not one ``(min, max)`` with ``min < max`` (or None) per camera.
    """

    grid: VoxelGrid
    rig: CameraRig
    table: AbsorptionTable
    resolution: float = 8.0
    out_wavenumber: np.ndarray | None = None
    window: tuple[float, float] | None = None
    dtype: np.dtype = np.float32
    planck: str = "table"
    memory_budget: int | None = None
    batch_rays: int | None = None
    devices: object = None
    rays_per_pixel: int = 1
    background: Background | None = None
    soot: np.ndarray | None = None
    soot_constant: float | None = None
    soot_input: bool = False
    camera_windows: tuple | None = None
    band: slice = field(init=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.grid, VoxelGrid):
            raise TypeError(f"grid must be an invflame.geometry.VoxelGrid, got {type(self.grid)}")
        if not isinstance(self.rig, CameraRig):
            raise TypeError(f"rig must be an invflame.geometry.CameraRig, got {type(self.rig)}")
        if self.background is not None and not isinstance(self.background, Background):
            raise TypeError(f"background must be an invflame.background.Background (e.g. "
                            f"BlackbodyWall(T, emissivity)), got "
                            f"{type(self.background).__name__}")
        if self.soot is not None and self.soot_input:
            raise ValueError("give either a known soot field (soot) or soot as an input field "
                             "(soot_input=True), not both")
        soot = None if self.soot is None else validate_soot(self.soot, self.grid)
        if soot is not None:
            soot.setflags(write=False)
        normal = {"dtype": np.dtype(self.dtype), "rays_per_pixel": int(self.rays_per_pixel),
                  "soot": soot, "soot_input": bool(self.soot_input),
                  "band": _window_slice(self.table.wavenumber, self.window),
                  "camera_windows": _camera_windows(self.camera_windows, self.rig.n_cameras)}
        for name, value in normal.items():
            object.__setattr__(self, name, value)

    @property
    def sooty(self) -> bool:
        """Whether the scene's medium holds soot: a known field or an input field."""
        return self.soot is not None or self.soot_input


def _camera_windows(windows, n_cameras: int) -> tuple | None:
    """``windows`` as a tuple of ``(min, max)`` float pairs (cm⁻¹) or None, one per camera;
    None when no camera has a window."""
    if windows is None:
        return None
    windows = tuple(None if w is None else (float(w[0]), float(w[1])) for w in windows)
    if len(windows) != n_cameras or any(w is not None and not w[0] < w[1] for w in windows):
        raise ValueError(f"camera_windows must give one (min, max) window in cm-1 with min < "
                         f"max, or None, for each of the {n_cameras} cameras; got {windows}")
    return windows if any(w is not None for w in windows) else None


def _window_slice(wavenumber: np.ndarray, window) -> slice:
    """The bins of ``wavenumber`` (cm⁻¹) inside ``window`` (cm⁻¹; None: all of them)."""
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
