"""Parameterizations of the flame fields that solvers optimize.

``voxel``           normalized field values per voxel (:class:`VoxelRepresentation`)
``neural``          a NeRF-like neural field rendered along rays
                    (:class:`NeuralFieldRepresentation`)
``neural-centres``  a network evaluated at voxel centres, then the voxel forward map
                    (:class:`NeuralCentresRepresentation`)

All share the fixed normalization of :mod:`invflame.representations.normalization` and offer
``initial_parameters``, ``problem(data, regularizer, lam, x0, sigma)`` (misfit weighted by the
noise σ, :mod:`invflame.representations.whitening`), ``fields(theta)``,
``iterations_per_epoch`` (solver iterations per pass over all pixels) and
``parameter_bytes(theta)``.
"""

from invflame.representations.neural import NeuralFieldRepresentation
from invflame.representations.neural_centres import NeuralCentresRepresentation
from invflame.representations.voxel import VoxelRepresentation

__all__ = ["NeuralCentresRepresentation", "NeuralFieldRepresentation", "VoxelRepresentation"]
