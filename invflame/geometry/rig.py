"""Camera rigs: several pinhole cameras whose rays are stacked into one list."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from invflame.errors import GeometryError
from invflame.geometry.camera import PinholeCamera, framing_sensor_size
from invflame.geometry.grid import VoxelGrid


@dataclass(frozen=True)
class CameraRig:
    """An ordered set of cameras; ray lists are concatenated camera after camera.

    Within a camera the ray order is that of :meth:`PinholeCamera.rays` (row-major over
    ``image[v, u]``, row 0 at the top).

    Parameters
    ----------
    cameras : sequence of PinholeCamera
        At least one camera.
    """

    cameras: tuple[PinholeCamera, ...]

    def __post_init__(self) -> None:
        cams = tuple(self.cameras)
        if not cams or not all(isinstance(c, PinholeCamera) for c in cams):
            raise ValueError("a CameraRig needs a non-empty sequence of PinholeCamera")
        object.__setattr__(self, "cameras", cams)

    def __len__(self) -> int:
        return len(self.cameras)

    @property
    def n_cameras(self) -> int:
        """Number of cameras."""
        return len(self.cameras)

    @property
    def image_shapes(self) -> tuple[tuple[int, int], ...]:
        """Image shape ``(nv, nu)`` of each camera."""
        return tuple(c.image_shape for c in self.cameras)

    @property
    def n_rays(self) -> int:
        """Total number of pixels (measured spectra) over all cameras."""
        return sum(c.n_rays for c in self.cameras)

    @property
    def ray_offsets(self) -> np.ndarray:
        """Start of each camera's rays in the stacked list, plus the total: (n_cameras + 1,)."""
        return np.concatenate([[0], np.cumsum([c.n_rays for c in self.cameras])])

    def rays(self, rays_per_pixel: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Stacked ray origins in m and unit directions, shapes ``(n_rays * rays_per_pixel,
        3)``: camera after camera, pixel-major (see :meth:`PinholeCamera.rays`)."""
        origins, directions = zip(*(c.rays(rays_per_pixel) for c in self.cameras), strict=True)
        return np.concatenate(origins), np.concatenate(directions)

    def split_images(self, values) -> list[np.ndarray]:
        """Cut a per-ray array (n_rays, …) into one image (nv, nu, …) per camera."""
        values = np.asarray(values)
        if values.shape[:1] != (self.n_rays,):
            raise ValueError(
                f"expected a leading axis of {self.n_rays} rays; got shape {values.shape}"
            )
        off = self.ray_offsets
        return [
            values[off[i] : off[i + 1]].reshape(shape + values.shape[1:])
            for i, shape in enumerate(self.image_shapes)
        ]

    def to_images(self, values) -> np.ndarray:
        """Reshape a per-ray array (n_rays, …) to (n_cameras, nv, nu, …).

        All cameras must have the same pixel counts; otherwise use :meth:`split_images`.
        """
        if len(set(self.image_shapes)) != 1:
            raise ValueError(
                f"cameras have different image shapes {self.image_shapes}; use split_images"
            )
        return np.stack(self.split_images(values))


PAPER_AZIMUTHS = (0.0, 180.0, 90.0, 270.0)
"""Azimuths of the study's four cameras (degrees, see :func:`ring_rig`): two viewing axes."""


def ring_rig(
    grid: VoxelGrid,
    azimuths,
    distance: float = 1.5,
    n_pixels: int = 32,
    focal_length: float = 0.59,
    margin: float = 0.02,
) -> CameraRig:
    r"""Cameras on a horizontal circle around the domain, each looking at its centre.

    Camera ``i`` sits at ``distance`` from the box centre in the direction
    :math:`\cos\phi_i\,e_a + \sin\phi_i\,e_b`, with :math:`\phi_i` = ``azimuths[i]``
    and :math:`e_a, e_b` the unit vectors of the two horizontal axes, a < b (x and z for a
    y-up grid), with the grid's up axis as up. All cameras share one square sensor, the
    smallest that frames the whole box from every camera, enlarged by ``margin`` on each
    side. Cameras opposite each other (azimuths 180° apart) see the same line integrals, so
    the number of distinct viewing axes, not of cameras, limits what the rig resolves.

    Parameters
    ----------
    grid : VoxelGrid
        Domain to look at.
    azimuths : sequence of float
        Camera azimuths in degrees, from :math:`e_a` towards :math:`e_b`.
    distance : float, optional
        Camera distance from the box centre in m.
    n_pixels : int, optional
        Pixels per side (square images).
    focal_length : float, optional
        Focal length in m.
    margin : float, optional
        Relative margin around the projected box (unitless).
    """
    azimuths = np.radians(np.asarray(azimuths, dtype=np.float64))
    if azimuths.ndim != 1 or azimuths.size == 0 or not np.all(np.isfinite(azimuths)):
        raise ValueError(f"azimuths must be a non-empty sequence of finite angles in degrees, "
                         f"got {np.degrees(azimuths)!r}")
    centre = grid.centre
    up = np.eye(3)[grid.up_axis]
    first, second = (a for a in range(3) if a != grid.up_axis)
    reach = max(grid.extent[a] / 2 for a in (first, second))
    if not distance > reach:
        raise GeometryError(f"camera distance {distance:g} m puts the cameras inside the grid "
                            f"(it reaches {reach:g} m from its centre on the horizontal axes): "
                            f"use a distance above {reach:g} m (the paper's 1.5)")
    # rounded so that the axis-aligned azimuths give exact unit vectors
    cos, sin = np.round(np.cos(azimuths), 14), np.round(np.sin(azimuths), 14)
    positions = [centre + distance * (c * np.eye(3)[first] + s * np.eye(3)[second])
                 for c, s in zip(cos, sin, strict=True)]
    corners = grid.corners()
    sensor = max(
        max(framing_sensor_size(p, centre, up, focal_length, corners, margin)) for p in positions
    )
    return CameraRig(
        tuple(
            PinholeCamera(p, centre, up, focal_length, (sensor, sensor), (n_pixels, n_pixels))
            for p in positions
        )
    )


def paper_rig(
    grid: VoxelGrid,
    distance: float = 1.5,
    n_pixels: int = 32,
    focal_length: float = 0.59,
    margin: float = 0.02,
) -> CameraRig:
    """Four cameras around the domain, as in the flame-tomography study: :func:`ring_rig` at
    :data:`PAPER_AZIMUTHS`.

    Cameras sit at ``distance`` from the box centre on the + and − directions of the two
    horizontal axes (x and z for a y-up grid), in the order +a, −a, +b, −b where a < b are
    the horizontal axis indices; each looks at the box centre with the grid's up axis as up.
    The square sensor is the smallest one that frames the whole box from every camera,
    enlarged by ``margin`` on each side. For the pool-fire box (1 m cube, centre 1.5 m
    away, f = 0.59 m) the nearest face projects to a half-width of 0.59 · 0.5 / 1.0 =
    0.295 m, so the default sensor is 2 · 0.295 · 1.02 = 0.6018 m square (field of view
    about 54.0°).

    Parameters
    ----------
    grid, distance, n_pixels, focal_length, margin
        As for :func:`ring_rig` (m, pixels per side, m, unitless).
    """
    return ring_rig(grid, PAPER_AZIMUTHS, distance, n_pixels, focal_length, margin)
