"""Ground-truth fields by name, for configurations and the command line."""

from __future__ import annotations

from collections.abc import Callable

from invflame.field import Field
from invflame.phantoms.plume import synthetic_plume
from invflame.phantoms.poolfire import poolfire

PHANTOMS: dict[str, Callable[..., Field]] = {
    "poolfire": poolfire,
    "synthetic": synthetic_plume,
}
"""Name → function returning a :class:`~invflame.field.Field`; each takes ``grid=`` (optional)."""


def make_phantom(name: str, **kwargs) -> Field:
    """The phantom registered under ``name``, built with ``kwargs``.

    Parameters
    ----------
    name : str
        A key of :data:`PHANTOMS` ("poolfire", "synthetic").
    **kwargs
        Passed on, e.g. ``grid=VoxelGrid.poolfire(30)``, ``seed=0``.
    """
    try:
        factory = PHANTOMS[name]
    except KeyError:
        raise KeyError(f"unknown phantom {name!r}; choose one of {sorted(PHANTOMS)}") from None
    return factory(**kwargs)
