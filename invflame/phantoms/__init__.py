"""Ground-truth flames: the packaged OpenFOAM pool fire and an analytic synthetic plume."""

from invflame.phantoms.plume import synthetic_plume
from invflame.phantoms.poolfire import poolfire
from invflame.phantoms.registry import PHANTOMS, make_phantom

__all__ = ["PHANTOMS", "make_phantom", "poolfire", "synthetic_plume"]
