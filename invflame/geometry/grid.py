"""Axis-aligned regular voxel grid: the spatial domain of the reconstruction."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class VoxelGrid:
    """Regular axis-aligned grid of ``nx × ny × nz`` box voxels.

    Voxel ``[ix, iy, iz]`` covers ``lower + spacing * [ix, iy, iz]`` to
    ``lower + spacing * [ix + 1, iy + 1, iz + 1]``. Field arrays on the grid have
    shape ``(nx, ny, nz)`` (index order ``[ix, iy, iz]``) and flatten in C order, so the
    flat index is ``np.ravel_multi_index((ix, iy, iz), shape)``.

    Parameters
    ----------
    lower : array_like, shape (3,)
        Lower corner of the box in m.
    upper : array_like, shape (3,)
        Upper corner of the box in m; every component strictly greater than ``lower``.
    shape : tuple of int, length 3
        Number of voxels ``(nx, ny, nz)`` along x, y, z; positive integers.
    up_axis : int, optional
        Index of the vertical axis (against gravity): 0, 1 or 2. The OpenFOAM pool fire is
        y-up, hence the default 1.
    """

    lower: np.ndarray
    upper: np.ndarray
    shape: tuple[int, int, int]
    up_axis: int = 1

    def __post_init__(self) -> None:
        lower = np.asarray(self.lower, dtype=np.float64)
        upper = np.asarray(self.upper, dtype=np.float64)
        if lower.shape != (3,) or upper.shape != (3,):
            raise ValueError(
                f"lower and upper must be 3-vectors in m; got shapes {lower.shape} and "
                f"{upper.shape}"
            )
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise ValueError(f"lower {lower} and upper {upper} must be finite (m)")
        if np.any(upper <= lower):
            raise ValueError(
                f"upper {upper} must exceed lower {lower} on every axis (m); swap or widen them"
            )
        shape = tuple(self.shape)
        if len(shape) != 3 or not all(
            isinstance(n, int | np.integer) and not isinstance(n, bool) and n > 0 for n in shape
        ):
            raise ValueError(
                f"shape must be three positive integers (nx, ny, nz); got {self.shape!r}"
            )
        if self.up_axis not in (0, 1, 2):
            raise ValueError(f"up_axis must be 0, 1 or 2; got {self.up_axis!r}")
        lower.setflags(write=False)
        upper.setflags(write=False)
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)
        object.__setattr__(self, "shape", tuple(int(n) for n in shape))

    def _key(self) -> tuple:
        return (tuple(self.lower), tuple(self.upper), self.shape, self.up_axis)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, VoxelGrid):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    @classmethod
    def cube(cls, n: int, size: float = 1.0, centre=(0.0, 0.0, 0.0), up_axis: int = 1):
        """Cubic grid of ``n³`` voxels.

        Parameters
        ----------
        n : int
            Voxels per axis.
        size : float, optional
            Edge length of the cube in m.
        centre : array_like, shape (3,), optional
            Centre of the cube in m.
        up_axis : int, optional
            Vertical axis (0, 1 or 2).
        """
        if size <= 0:
            raise ValueError(f"size must be positive (m); got {size}")
        c = np.asarray(centre, dtype=np.float64)
        return cls(c - 0.5 * size, c + 0.5 * size, (n, n, n), up_axis)

    @classmethod
    def poolfire(cls, n: int = 60) -> VoxelGrid:
        """Domain of the OpenFOAM pool fire: x, z ∈ [−0.5, 0.5] m, y ∈ [0, 1] m, y up.

        Parameters
        ----------
        n : int, optional
            Voxels per axis (the simulation has 60³ cells).
        """
        return cls((-0.5, 0.0, -0.5), (0.5, 1.0, 0.5), (n, n, n), up_axis=1)

    @property
    def spacing(self) -> np.ndarray:
        """Voxel edge lengths ``(dx, dy, dz)`` in m, shape (3,)."""
        return (self.upper - self.lower) / np.asarray(self.shape, dtype=np.float64)

    @property
    def n_voxels(self) -> int:
        """Total number of voxels ``nx * ny * nz``."""
        return int(np.prod(self.shape))

    @property
    def extent(self) -> np.ndarray:
        """Box edge lengths ``upper - lower`` in m, shape (3,)."""
        return self.upper - self.lower

    @property
    def centre(self) -> np.ndarray:
        """Centre of the box in m, shape (3,)."""
        return 0.5 * (self.lower + self.upper)

    def corners(self) -> np.ndarray:
        """The 8 corners of the box in m, shape (8, 3); corner ``k`` takes ``upper`` on
        axis ``a`` where bit ``2 - a`` of ``k`` is set."""
        bits = (np.arange(8)[:, None] >> np.array([2, 1, 0])) & 1
        return np.where(bits == 1, self.upper, self.lower)

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Voxel-centre coordinates along x, y and z in m (three 1-D arrays)."""
        h = self.spacing
        return tuple(self.lower[a] + h[a] * (np.arange(self.shape[a]) + 0.5) for a in range(3))

    def centres(self) -> np.ndarray:
        """Voxel centres in m, shape ``(nx, ny, nz, 3)``, indexed ``[ix, iy, iz]``."""
        return np.stack(np.meshgrid(*self.axes(), indexing="ij"), axis=-1)

    def flat_index(self, ix, iy, iz) -> np.ndarray:
        """C-order flat voxel index, same as ``np.ravel_multi_index((ix, iy, iz), shape)``.

        Raises ``ValueError`` for indices outside the grid.
        """
        return np.ravel_multi_index((ix, iy, iz), self.shape)

    def contains(self, points) -> np.ndarray:
        """Whether points (…, 3) in m lie in the closed box ``[lower, upper]``.

        Returns a boolean array of shape ``points.shape[:-1]``.
        """
        p = np.asarray(points, dtype=np.float64)
        if p.shape[-1:] != (3,):
            raise ValueError(f"points must have a last axis of length 3 (x, y, z); got {p.shape}")
        return np.all((p >= self.lower) & (p <= self.upper), axis=-1)
