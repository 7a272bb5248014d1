r"""A learned multi-resolution feature grid: the position encoding of grid-based neural fields.

Level :math:`l` of :math:`L` is a grid of :math:`F` learned features per node over the
network's box, with :math:`n_a / 2^{L-1-l}` nodes along an axis of :math:`n_a` voxels (at least
2), its nodes at the centres of the level's own cells; a point's encoding is the trilinear
interpolation of every level's features, concatenated (:math:`L F` numbers), as in the dense
levels of Müller et al., "Instant neural graphics primitives with a multiresolution hash
encoding", ACM Trans. Graph. 41 (2022) 102. The finest level has the voxel grid's own
resolution, so at the voxel centres it holds one feature vector per voxel: the network can
resolve what the voxels resolve, while the coarse levels move whole regions at once.
"""

from __future__ import annotations

import torch

FEATURE_INIT = 1e-4
"""Half-width of the uniform distribution the features start from (as Müller et al.): the
encoding starts near zero and the network near its biases."""

FEATURES = 2
"""Features per node and level (Müller et al.'s choice)."""


def level_shapes(shape, levels: int) -> list[tuple[int, int, int]]:
    """Nodes per axis of each level, coarsest first: ``shape`` halved ``levels - 1 - l`` times
    (rounded, at least 2).

    Parameters
    ----------
    shape : tuple of int
        Voxels per axis of the finest level.
    levels : int
        Number of levels (>= 1).
    """
    if levels < 1:
        raise ValueError(f"a feature grid needs levels >= 1; got {levels}")
    return [tuple(max(2, int(round(n / 2 ** (levels - 1 - level)))) for n in shape)
            for level in range(levels)]


class FeatureGrid(torch.nn.Module):
    """Learned features on nested grids, interpolated trilinearly at points of :math:`[-1,1]^3`.

    Parameters
    ----------
    shape : tuple of int
        Voxels per axis of the finest level (the voxel grid's shape).
    levels : int
        Number of levels (>= 1), see :func:`level_shapes`.
    generator : torch.Generator
        CPU generator of the features' initial values (uniform in ±:data:`FEATURE_INIT`).
    dtype : torch.dtype
        float32 or float64.
    features : int, optional
        Features per node and level (>= 1; default :data:`FEATURES`).
    """

    def __init__(self, shape, levels: int, generator: torch.Generator, dtype,
                 features: int = FEATURES):
        super().__init__()
        if features < 1:
            raise ValueError(f"a feature grid needs features >= 1; got {features}")
        self.shapes = level_shapes(shape, levels)
        self.n_outputs = int(levels) * int(features)
        self.levels = torch.nn.ParameterList(
            torch.nn.Parameter(torch.empty((1, features, *s), dtype=dtype, device="cpu").uniform_(
                -FEATURE_INIT, FEATURE_INIT, generator=generator).to(torch.get_default_device()))
            for s in self.shapes)

    def forward(self, unit: torch.Tensor) -> torch.Tensor:
        """Encoding of points ``(N, 3)`` in :math:`[-1, 1]^3`: shape ``(N, levels × features)``."""
        return torch.cat([interpolate(level, unit) for level in self.levels], dim=-1)


def interpolate(values: torch.Tensor, unit: torch.Tensor) -> torch.Tensor:
    """Trilinear interpolation of node values at points of the box :math:`[-1, 1]^3`.

    Written with gathers rather than :func:`torch.nn.functional.grid_sample` (the same values)
    so that forward-mode derivatives (:func:`torch.func.jvp`, which Gauss–Newton and PDHG use)
    exist as well as reverse-mode ones.

    Parameters
    ----------
    values : torch.Tensor, shape (1, C, nx, ny, nz)
        C values per node; the nodes sit at the centres of ``nx × ny × nz`` cells dividing
        the box (beyond the outermost centres a point gets the border nodes' values).
    unit : torch.Tensor, shape (N, 3)
        Points in the box.

    Returns
    -------
    torch.Tensor, shape (N, C)
    """
    shape = values.shape[2:]
    size = torch.as_tensor(shape, dtype=unit.dtype, device=unit.device)
    position = torch.minimum(torch.clamp((unit + 1.0) * 0.5 * size - 0.5, min=0.0), size - 1.0)
    low = torch.minimum(position.floor(), torch.clamp(size - 2.0, min=0.0)).long()
    weight = position - low
    high = torch.minimum(low + 1, (size - 1.0).long())
    flat = values.reshape(values.shape[1], -1)
    out = 0.0
    for corner in range(8):
        bits = [(corner >> axis) & 1 for axis in range(3)]
        index = [h if b else lo for b, lo, h in zip(bits, low.unbind(-1), high.unbind(-1),
                                                    strict=True)]
        share = torch.prod(torch.stack([w if b else 1.0 - w for b, w in
                                        zip(bits, weight.unbind(-1), strict=True)]), dim=0)
        node = (index[0] * shape[1] + index[1]) * shape[2] + index[2]
        out = out + flat[:, node] * share
    return out.T
