r"""Sampling voxel fields onto ray segments: a gather whose adjoint is a scatter-add.

For fields :math:`f_{c,v}` on voxels (flat C-order index :math:`v` of ``[ix, iy, iz]``) and a
padded table of voxel indices :math:`v_{r,k}` (ray :math:`r`, segment :math:`k`),

.. math:: (P f)_{c,r,k} = f_{c, v_{r,k}}, \qquad
          (P^\mathsf{T} g)_{c,v} = \sum_{(r,k):\, v_{r,k} = v} g_{c,r,k}.

Padding entries carry index 0 (and zero length in the ray geometry); they are gathered like
any other entry, and the emission operator ignores them, so their cotangents are zero.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from operators.base import LinearOperator
from operators.interop import to_jax, to_numpy


def sample_voxels(fields, voxel):
    """Gather ``fields`` (n_fields, nx, ny, nz) at flat voxel indices: a JAX function.

    Parameters
    ----------
    fields : jax.Array, shape (n_fields, nx, ny, nz)
        Voxel values, any unit.
    voxel : jax.Array of int, shape (n_rays, n_seg)
        C-order flat voxel indices.

    Returns
    -------
    jax.Array, shape (n_fields, n_rays, n_seg)
        Values on the segments (same unit). Differentiable; its VJP is the scatter-add.
    """
    return fields.reshape(fields.shape[0], -1)[:, voxel]


class VoxelSampling(LinearOperator):
    """Voxel fields ``(n_fields, nx, ny, nz)`` → segment values ``(n_fields, n_rays, n_seg)``.

    A gather (forward) and a scatter-add (adjoint), see the module docstring; the operator
    is exact in the dot-product test.

    Parameters
    ----------
    voxel : array_like of int, shape (n_rays, n_seg)
        C-order flat voxel indices of the segments, padding 0.
    grid_shape : tuple of 3 int
        ``(nx, ny, nz)``.
    n_fields : int, optional
        Number of fields (default 4: T, CO2, H2O, CH4).
    dtype : numpy dtype, optional
        float32 or float64 (default).

    Attributes
    ----------
    voxel : ndarray of int64, shape (n_rays, n_seg)
    """

    def __init__(self, voxel, grid_shape, n_fields: int = 4, dtype=np.float64):
        voxel = np.asarray(voxel)
        grid_shape = tuple(int(n) for n in grid_shape)
        if len(grid_shape) != 3 or min(grid_shape) < 1:
            raise ValueError(f"grid_shape must be (nx, ny, nz) positive, got {grid_shape}")
        if voxel.ndim != 2 or not np.issubdtype(voxel.dtype, np.integer):
            raise ValueError(
                f"voxel must be an integer array (n_rays, n_seg), got {voxel.dtype} {voxel.shape}"
            )
        n_voxels = int(np.prod(grid_shape))
        if voxel.size and (voxel.min() < 0 or voxel.max() >= n_voxels):
            raise ValueError(
                f"voxel indices must lie in [0, {n_voxels}) for a grid {grid_shape}; got "
                f"[{voxel.min()}, {voxel.max()}]"
            )
        self.voxel = voxel.astype(np.int64)
        self._jvoxel = jnp.asarray(self.voxel)
        n_fields = int(n_fields)
        super().__init__((n_fields, *grid_shape), (n_fields, *voxel.shape), dtype=dtype,
                         name="VoxelSampling")
        self._gather = jax.jit(sample_voxels)
        self._scatter = jax.jit(
            lambda g, v: jnp.zeros((n_fields, n_voxels), g.dtype).at[:, v].add(g))

    def _forward(self, x):
        return to_numpy(self._gather(to_jax(x, dtype=self.dtype), self._jvoxel))

    def _adjoint(self, y):
        scattered = self._scatter(to_jax(y, dtype=self.dtype), self._jvoxel)
        return to_numpy(scattered).reshape(self.dims)
