"""Parameterizations of the flame fields that solvers optimize.

==================  ================================================================
``voxel``           normalized field values per voxel (:class:`VoxelRepresentation`)
``neural-field``    a NeRF-like neural field rendered along rays
                    (:class:`NeuralFieldRepresentation`)
``neural-centres``  a network evaluated at voxel centres, then the voxel forward map
                    (:class:`NeuralCentresRepresentation`)
==================  ================================================================

All share the fixed normalization of :mod:`invflame.representations.normalization` and are
instances of :class:`~invflame.representations.protocol.Representation`: ``kind`` (the name above, a
configuration's ``representation.kind``), ``initial_parameters``, ``problem(data, regularizer,
lam, x0, sigma)`` (misfit weighted by the noise σ, :mod:`invflame.representations.whitening`),
``fields(theta)``, ``iterations_per_epoch`` (solver iterations per pass over all pixels) and
``parameter_bytes(theta)``. The neural ones live in :mod:`invflame.representations.neural`.
"""

from invflame.representations.neural import NeuralCentresRepresentation, NeuralFieldRepresentation
from invflame.representations.protocol import Representation
from invflame.representations.voxel import VoxelRepresentation

REPRESENTATIONS = {cls.kind: cls for cls in (VoxelRepresentation, NeuralFieldRepresentation,
                                             NeuralCentresRepresentation)}
"""Representation class by kind."""

__all__ = ["REPRESENTATIONS", "NeuralCentresRepresentation", "NeuralFieldRepresentation",
           "Representation", "VoxelRepresentation"]
