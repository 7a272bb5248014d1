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
``parameter_bytes(theta)``. The neural ones live in :mod:`invflame.representations.neural`,
which imports torch: it is imported when a neural representation is first named, so that the
voxel representation runs without torch.
"""

from collections.abc import Iterator, Mapping
from importlib import import_module

from invflame.representations.protocol import Representation
from invflame.representations.voxel import VoxelRepresentation

_NEURAL = {"neural-field": "NeuralFieldRepresentation",
           "neural-centres": "NeuralCentresRepresentation"}
"""Class name of each neural representation by kind: their module imports torch, so it is
imported when one of them is first named (``invflame.representations.NeuralFieldRepresentation``
or ``REPRESENTATIONS["neural-field"]``), not with this package."""


def _neural(name: str) -> type[Representation]:
    """The neural representation class ``name``, importing its module (and torch)."""
    return getattr(import_module("invflame.representations.neural"), name)


def __getattr__(name: str):
    """The neural representation classes, imported when first named."""
    if name in _NEURAL.values():
        return _neural(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The package's names, the neural classes among them before they are imported."""
    return sorted(set(globals()) | set(_NEURAL.values()))


class _ByKind(Mapping):
    """Representation class by kind; the neural ones are imported when looked up."""

    def __getitem__(self, kind: str) -> type[Representation]:
        if kind == VoxelRepresentation.kind:
            return VoxelRepresentation
        return _neural(_NEURAL[kind])

    def __contains__(self, kind) -> bool:
        return kind == VoxelRepresentation.kind or kind in _NEURAL

    def __iter__(self) -> Iterator[str]:
        return iter((VoxelRepresentation.kind, *_NEURAL))

    def __len__(self) -> int:
        return 1 + len(_NEURAL)


REPRESENTATIONS: Mapping[str, type[Representation]] = _ByKind()
"""Representation class by kind."""

__all__ = ["REPRESENTATIONS", "NeuralCentresRepresentation", "NeuralFieldRepresentation",
           "Representation", "VoxelRepresentation"]
