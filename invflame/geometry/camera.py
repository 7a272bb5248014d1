"""Pinhole camera: rays through the pixels, and the projection of points to pixels.

A pixel integrates the radiance arriving over its area. :meth:`PinholeCamera.rays` samples
each pixel by ``k × k`` sub-rays through the centres of a regular ``k × k`` subdivision of the
pixel (stratified, deterministic); the measured value of a pixel is the mean of its sub-rays'.

Camera frame
------------
``forward`` points from the camera position to the look-at point; ``right`` is
``forward × up`` normalized; the image's own up is ``right × forward`` (the given up
vector made orthogonal to ``forward``).

Image convention
----------------
Pixel values are stored as ``image[v, u]`` with ``u = 0 … nu-1`` the column (left to
right, along ``right``) and ``v = 0 … nv-1`` the row from the **top** (against the up
vector). Rays are listed row-major: ray ``k = v * nu + u``, so ``values.reshape(nv, nu)``
gives the image, and ``matplotlib.pyplot.imshow(image)`` (default ``origin="upper"``)
shows it upright with the up vector pointing up the screen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _unit(vector, name: str) -> np.ndarray:
    v = np.asarray(vector, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be a finite 3-vector; got {vector!r}")
    norm = np.linalg.norm(v)
    if norm == 0.0:
        raise ValueError(f"{name} must be non-zero")
    return v / norm


@dataclass(frozen=True, eq=False)
class PinholeCamera:
    """Ideal pinhole camera with a flat sensor behind the pinhole.

    Parameters
    ----------
    position : array_like, shape (3,)
        Pinhole (centre of projection) in m.
    look_at : array_like, shape (3,)
        Point on the optical axis in m; must differ from ``position``.
    up : array_like, shape (3,)
        Approximate up direction of the image (unitless); must not be parallel to the
        optical axis.
    focal_length : float
        Distance from pinhole to sensor in m.
    sensor_size : tuple of float
        Sensor ``(width, height)`` in m; width along the image columns (``right``).
    n_pixels : tuple of int
        Pixel counts ``(nu, nv)``: columns and rows. The image has shape ``(nv, nu)``.
    principal_point : tuple of float, optional
        Where the optical axis meets the sensor, ``(u, v)`` in pixels from the image's top-left
        corner (the centre of pixel ``image[v, u]`` is at ``(u + 0.5, v + 0.5)``); default the
        sensor's centre ``(nu / 2, nv / 2)``.
    """

    position: np.ndarray
    look_at: np.ndarray
    up: np.ndarray
    focal_length: float
    sensor_size: tuple[float, float]
    n_pixels: tuple[int, int]
    principal_point: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        position = np.asarray(self.position, dtype=np.float64)
        look_at = np.asarray(self.look_at, dtype=np.float64)
        for name, v in (("position", position), ("look_at", look_at)):
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be a finite 3-vector in m; got {v!r}")
        if np.array_equal(position, look_at):
            raise ValueError("look_at must differ from the camera position")
        forward = _unit(look_at - position, "look_at - position")
        up = _unit(self.up, "up")
        right = np.cross(forward, up)
        if np.linalg.norm(right) < 1e-9:
            raise ValueError(
                f"up {self.up!r} is parallel to the viewing direction {forward}; pick an up "
                "vector across the optical axis"
            )
        if not (np.isfinite(self.focal_length) and self.focal_length > 0):
            raise ValueError(f"focal_length must be positive (m); got {self.focal_length!r}")
        sensor = tuple(float(s) for s in self.sensor_size)
        if len(sensor) != 2 or not all(np.isfinite(s) and s > 0 for s in sensor):
            raise ValueError(
                f"sensor_size must be (width, height), both positive (m); got {self.sensor_size!r}"
            )
        pixels = tuple(self.n_pixels)
        if len(pixels) != 2 or not all(
            isinstance(n, int | np.integer) and not isinstance(n, bool) and n > 0 for n in pixels
        ):
            raise ValueError(f"n_pixels must be two positive integers (nu, nv); got {pixels!r}")
        centre = (pixels[0] / 2, pixels[1] / 2)
        principal = centre if self.principal_point is None else tuple(self.principal_point)
        if len(principal) != 2 or not all(
            isinstance(c, int | float | np.number) and not isinstance(c, bool) and np.isfinite(c)
            for c in principal
        ):
            raise ValueError(f"principal_point must be two finite numbers (u, v) in pixels; got "
                             f"{self.principal_point!r}")
        for name, value in (("position", position), ("look_at", look_at), ("up", up)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "focal_length", float(self.focal_length))
        object.__setattr__(self, "sensor_size", sensor)
        object.__setattr__(self, "n_pixels", tuple(int(n) for n in pixels))
        object.__setattr__(self, "principal_point", tuple(float(c) for c in principal))

    @classmethod
    def from_fov(
        cls, position, look_at, up, fov: float, n_pixels, focal_length: float = 1.0
    ) -> PinholeCamera:
        """Camera with a horizontal field of view ``fov`` in degrees and square pixels.

        The sensor width is ``2 f tan(fov / 2)`` (m) and the height follows from the pixel
        counts so that pixels are square. Only the ratio sensor/focal length changes the
        rays, so ``focal_length`` (m) is just a scale.
        """
        if not 0.0 < fov < 180.0:
            raise ValueError(f"fov must be in (0, 180) degrees; got {fov!r}")
        nu, nv = n_pixels
        width = 2.0 * focal_length * np.tan(np.radians(fov) / 2.0)
        return cls(position, look_at, up, focal_length, (width, width * nv / nu), n_pixels)

    @property
    def forward(self) -> np.ndarray:
        """Unit optical axis, from the pinhole towards ``look_at``."""
        return _unit(self.look_at - self.position, "look_at - position")

    @property
    def right(self) -> np.ndarray:
        """Unit vector along increasing image column ``u``."""
        return _unit(np.cross(self.forward, self.up), "right")

    @property
    def image_up(self) -> np.ndarray:
        """Unit up vector of the image (``up`` made orthogonal to ``forward``)."""
        return np.cross(self.right, self.forward)

    @property
    def image_shape(self) -> tuple[int, int]:
        """Image array shape ``(nv, nu)`` (rows, columns)."""
        return (self.n_pixels[1], self.n_pixels[0])

    @property
    def n_rays(self) -> int:
        """Number of pixels ``nu * nv`` (one measured spectrum each)."""
        return self.n_pixels[0] * self.n_pixels[1]

    @property
    def fov(self) -> tuple[float, float]:
        """Full horizontal and vertical fields of view in degrees."""
        w, h = self.sensor_size
        return tuple(float(np.degrees(2 * np.arctan(s / (2 * self.focal_length)))) for s in (w, h))

    def rays(self, rays_per_pixel: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Rays through the pixels: ``rays_per_pixel`` stratified sub-rays per pixel.

        Parameters
        ----------
        rays_per_pixel : int, optional
            ``k²`` sub-rays per pixel through the centres of a ``k × k`` subdivision of the
            pixel (1, 4, 9, 16, ...); default 1, the pixel centre.

        Returns
        -------
        origins : ndarray, shape (nu * nv * rays_per_pixel, 3)
            The pinhole position in m, repeated.
        directions : ndarray, shape (nu * nv * rays_per_pixel, 3)
            Unit directions (into the scene), pixel-major: the sub-rays of pixel
            ``image[v, u]`` are rows ``p * rays_per_pixel ...`` to ``(p + 1) * rays_per_pixel
            - 1`` with ``p = v * nu + u``, row ``v = 0`` at the top of the image.
        """
        k = subdivisions(rays_per_pixel)
        nu, nv = self.n_pixels
        w, h = self.sensor_size
        cu, cv = self.principal_point
        sub = (np.arange(k) + 0.5) / k  # sub-ray offsets inside a pixel, in pixels
        x = ((np.arange(nu)[:, None] + sub).ravel() / nu - cu / nu) * w  # along right, m
        y = (cv / nv - (np.arange(nv)[:, None] + sub).ravel() / nv) * h  # along image_up, m
        yy, xx = np.meshgrid(y, x, indexing="ij")  # (nv k, nu k)
        # reorder (v, j, u, i) -> (v, u, j, i): the k x k sub-rays of a pixel are consecutive
        xx, yy = (a.reshape(nv, k, nu, k).transpose(0, 2, 1, 3).reshape(-1, 1) for a in (xx, yy))
        d = self.focal_length * self.forward + xx * self.right + yy * self.image_up
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        origins = np.broadcast_to(self.position, d.shape).copy()
        return origins, d

    def to_camera_frame(self, points) -> np.ndarray:
        """Coordinates of points (…, 3) in m along (right, image_up, forward), in m."""
        p = np.asarray(points, dtype=np.float64) - self.position
        return np.stack([p @ self.right, p @ self.image_up, p @ self.forward], axis=-1)

    def project(self, points) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Project points (…, 3) in m onto the image.

        Returns
        -------
        u, v : ndarray
            Continuous pixel coordinates (column from the left, row from the top) in
            pixels; the centre of pixel ``image[v, u]`` is at ``(u + 0.5, v + 0.5)``.
            NaN for points not in front of the camera.
        depth : ndarray
            Distance along the optical axis in m (≤ 0 behind the pinhole).
        """
        c = self.to_camera_frame(points)
        depth = c[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(depth > 0, self.focal_length / depth, np.nan)
        nu, nv = self.n_pixels
        cu, cv = self.principal_point
        w, h = self.sensor_size
        u = (c[..., 0] * scale / w + cu / nu) * nu
        v = (cv / nv - c[..., 1] * scale / h) * nv
        return u, v, depth


def subdivisions(rays_per_pixel: int) -> int:
    """Sub-rays per pixel side ``k`` for ``rays_per_pixel = k²``, with a clear error otherwise."""
    n = rays_per_pixel
    k = int(round(np.sqrt(n))) if isinstance(n, int | np.integer) and n > 0 else 0
    if isinstance(n, bool) or k < 1 or k * k != n:
        raise ValueError(f"rays_per_pixel must be a perfect square k*k >= 1 (1, 4, 9, 16, ...: "
                         f"k x k sub-rays per pixel); got {rays_per_pixel!r}")
    return k


def framing_sensor_size(
    position, look_at, up, focal_length: float, points, margin: float = 0.02
) -> tuple[float, float]:
    """Smallest sensor ``(width, height)`` in m, centred on the axis, that sees all points.

    Each half-size is the largest projected offset ``f · |x| / z`` of the points (camera
    frame, m) times ``1 + margin``. All points must lie in front of the camera.

    Parameters
    ----------
    position, look_at, up : array_like, shape (3,)
        Camera pose as in :class:`PinholeCamera` (m, m, unitless).
    focal_length : float
        Focal length in m.
    points : array_like, shape (n, 3)
        Points to frame in m, e.g. the corners of the domain box.
    margin : float, optional
        Relative margin added on each side (unitless, ≥ 0).
    """
    if margin < 0:
        raise ValueError(f"margin must be ≥ 0; got {margin!r}")
    probe = PinholeCamera(position, look_at, up, focal_length, (1.0, 1.0), (1, 1))
    c = probe.to_camera_frame(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    if np.any(c[:, 2] <= 0):
        raise ValueError("every point to frame must lie in front of the camera")
    half = np.max(np.abs(c[:, :2]) * focal_length / c[:, 2:3], axis=0) * (1.0 + margin)
    return float(2 * half[0]), float(2 * half[1])
