r"""The voxel regularizer of a neural field: over all voxel centres, or estimated on a few.

:math:`\Phi` of a network is the voxel regularizer
(:func:`~invflame.representations.voxel.regularizer_for`) of its normalized fields at the voxel
centres, so that λ means the same for networks and voxels. :func:`regularizer_after` builds it
after any operator from parameters to normalized fields; :class:`CentreRegularizer` estimates
it without bias from a random set of voxel centres (the training objective's).
"""

from __future__ import annotations

import numpy as np
import torch

import solvers
from invflame.geometry import VoxelGrid
from invflame.representations.neural.network import centre_points
from invflame.representations.voxel import regularizer_for
from operators import Operator


class CentreRegularizer:
    r"""Tikhonov or TV of a field function from forward differences between voxel centres.

    For voxel centres :math:`c_v`, :math:`v \in \mathcal{V}` (a set of :math:`B` distinct
    voxels) and a function :math:`u` of position giving normalized fields,

    .. math:: \hat\Phi = \frac{1}{n_f B} \sum_{v \in \mathcal{V}} \sum_{d, c}
              h\Big(\frac{u_c(c_{v + e_d}) - u_c(c_v)}{\Delta_d}\Big),

    :math:`h(x) = x^2` (Tikhonov) or :math:`|x|` (TV), with :math:`v + e_d` the next voxel
    along axis :math:`d` (:math:`v` itself on the last layer: the difference is zero). Over all
    voxels this is :func:`operators.tikhonov` / :func:`operators.total_variation` of the
    fields sampled at the centres; over a uniformly random set of voxels it is an unbiased
    estimate of it.

    Parameters
    ----------
    kind : {"tikhonov", "tv"}
        The regularizer.
    grid : VoxelGrid
        Voxel centres and spacing (m).
    dtype : torch.dtype, optional
        Of the centres (default float32).
    """

    def __init__(self, kind: str, grid: VoxelGrid, dtype=torch.float32):
        if kind not in ("tikhonov", "tv"):
            raise ValueError(f"CentreRegularizer is 'tikhonov' or 'tv'; got {kind!r}")
        self.kind = kind
        self.points = centre_points(grid, dtype).reshape(-1, 3)
        self.spacing = torch.tensor(grid.spacing, dtype=dtype)
        index = np.indices(grid.shape).reshape(3, -1)
        neighbours = []
        for axis, n in enumerate(grid.shape):
            shifted = index.copy()
            shifted[axis] = np.minimum(shifted[axis] + 1, n - 1)
            neighbours.append(np.ravel_multi_index(tuple(shifted), grid.shape))
        self.neighbours = torch.as_tensor(np.stack(neighbours))

    @property
    def n_centres(self) -> int:
        """Number of voxel centres."""
        return self.points.shape[0]

    def __call__(self, u, index: torch.Tensor) -> torch.Tensor:
        r""":math:`\hat\Phi` over the voxels ``index`` (1/m² for Tikhonov, 1/m for TV).

        Parameters
        ----------
        u : callable
            Points ``(..., 3)`` in m to normalized fields ``(n_f, ...)`` (dimensionless),
            differentiable if a gradient is wanted.
        index : torch.Tensor of int, shape (B,)
            Distinct C-order flat voxel indices.

        Returns
        -------
        torch.Tensor, scalar
        """
        points = self.points[torch.cat([index[None], self.neighbours[:, index]])]  # (4, B, 3)
        values = u(points)  # (n_f, 4, B): the centre, then its neighbours along x, y, z
        differences = (values[:, 1:] - values[:, :1]) / self.spacing[:, None]
        terms = differences**2 if self.kind == "tikhonov" else differences.abs()
        return terms.sum() / (values.shape[0] * index.numel())



def regularizer_after(kind: str, grid: VoxelGrid,
                      normalized: Operator) -> solvers.Regularizer | None:
    r"""The voxel regularizer of the normalized fields an operator produces.

    :math:`\Phi(\theta) = g(D\,u(\theta))`, with the forward-difference gradient :math:`D`
    (1/m) and outer functional :math:`g` of
    :func:`~invflame.representations.voxel.regularizer_for`, after ``normalized``
    (:math:`\theta \mapsto u`, e.g. a network at the voxel centres): the voxel regularizer of
    :math:`u(\theta)`.

    Parameters
    ----------
    kind : {"none", "tikhonov", "tv"}
        Regularizer; None is returned for "none".
    grid : VoxelGrid
        Grid of the fields (shape and spacing in m).
    normalized : operators.Operator
        Parameters to normalized fields ``(4, nx, ny, nz)`` (:math:`u = f/s`, dimensionless).

    Returns
    -------
    solvers.Regularizer or None
    """
    composite = regularizer_for(kind, grid)
    if composite is None:
        return None
    return solvers.Regularizer(composite.functional, composite.op @ normalized)

