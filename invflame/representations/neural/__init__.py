"""Neural representations: the flame fields as a network of position.

=================  ===================================================================
``network``        the field network (:class:`FieldNetwork`) and its pretraining
``sampling``       sample placement along rays (stratified, importance, Planck-mean opacity)
``renderer``       pixel spectra rendered from field functions (:class:`NeuralRenderer`)
``regularizers``   the voxel regularizer of a network at the voxel centres
``weights``        network weights as a representation's unknowns, and their start
``field``          the NeRF-like representation (:class:`NeuralFieldRepresentation`)
``centres``        the network at the voxel centres (:class:`NeuralCentresRepresentation`)
=================  ===================================================================
"""

from invflame.representations.neural.centres import NeuralCentresRepresentation
from invflame.representations.neural.field import NeuralFieldRepresentation, NeuralRendering
from invflame.representations.neural.network import FieldNetwork, centre_points, pretrain
from invflame.representations.neural.regularizers import CentreRegularizer, regularizer_after
from invflame.representations.neural.renderer import NeuralRenderer

__all__ = [
    "CentreRegularizer",
    "FieldNetwork",
    "NeuralCentresRepresentation",
    "NeuralFieldRepresentation",
    "NeuralRenderer",
    "NeuralRendering",
    "centre_points",
    "pretrain",
    "regularizer_after",
]
