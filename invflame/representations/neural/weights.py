"""Network weights as the unknowns of a representation, and their start."""

from __future__ import annotations

import numpy as np

from invflame.representations.neural.network import FieldNetwork, pretrain
from invflame.representations.protocol import Representation


class NetworkWeights(Representation):
    """A representation whose parameters are the weights of its field networks: one flat
    vector of each network's weights (:meth:`FieldNetwork.parameter_vector`) in the order of
    :attr:`networks`.

    Attributes
    ----------
    networks : tuple of FieldNetwork
        The networks, set by the subclass.
    """

    networks: tuple[FieldNetwork, ...]

    @property
    def n_parameters(self) -> int:
        """Weights of all networks together."""
        return sum(network.n_parameters for network in self.networks)

    def initial_parameters(self, fields=None, iterations: int = 1000, lr: float = 1e-3,
                           seed: int = 0, progress: bool = True,
                           offset: bool = False) -> np.ndarray:
        """Starting weights: every network pretrained on ``fields``, or offset by them (or as
        initialized).

        Parameters
        ----------
        fields : Field or ndarray, shape (4, nx, ny, nz), optional
            Voxel fields on the scene's grid (T in K, mole fractions), e.g. the noisy initial
            field of the voxel run; None keeps the networks' current weights.
        iterations, lr, seed, progress
            Passed to :func:`~invflame.representations.neural.network.pretrain`.
        offset : bool, optional
            Start every network at ``fields`` exactly and let it learn the correction
            (:meth:`FieldNetwork.offset_by`) instead of pretraining it.

        Returns
        -------
        ndarray, shape (n_parameters,)
            The networks' weights, in the scene's dtype.
        """
        if fields is not None:
            for network in self.networks:
                if offset:
                    network.offset_by(fields)
                else:
                    pretrain(network, fields, iterations, lr, seed, progress=progress)
        return np.concatenate([network.parameter_vector() for network in self.networks])
