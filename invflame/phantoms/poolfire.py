"""The packaged OpenFOAM pool fire at t = 0.9 s, the default ground truth."""

from __future__ import annotations

from importlib import resources

from invflame.field import Field
from invflame.geometry import VoxelGrid

POOLFIRE_FILE = "poolfire_t0.9.npz"
"""Name of the snapshot in ``invflame/data`` (made by ``scripts/make_poolfire.sh``)."""


def poolfire(grid: VoxelGrid | None = None) -> Field:
    """OpenFOAM fireFoam ``smallPoolFire3D`` at t = 0.9 s: 60³ cells, 1 m cube, y up.

    Parameters
    ----------
    grid : VoxelGrid, optional
        Resample onto this grid (molar-density-weighted cell averaging, see
        :meth:`invflame.field.Field.resample`); default: the native 60³ grid.

    Returns
    -------
    Field
        ``T`` [K] and mole fractions of CO2, H2O, CH4, with the simulation's provenance.
    """
    with resources.as_file(resources.files("invflame") / "data" / POOLFIRE_FILE) as path:
        if not path.is_file():
            raise FileNotFoundError(
                f"packaged pool fire missing at {path}; regenerate it with "
                "scripts/make_poolfire.sh"
            )
        field = Field.load(path)
    return field if grid is None else field.resample(grid)
