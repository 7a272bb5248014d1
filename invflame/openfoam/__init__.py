"""Reading OpenFOAM cases (ascii or binary, optionally gzipped; parsed by foamlib) onto regular
voxel grids. No OpenFOAM installation is needed; ``scripts/make_poolfire.sh`` runs the solver."""

from invflame.openfoam.case import read_case, time_directory
from invflame.openfoam.foamfile import FoamFormatError, read_internal_field
from invflame.openfoam.mesh import cell_centres, grid_from_centres

__all__ = ["FoamFormatError", "cell_centres", "grid_from_centres", "read_case",
           "read_internal_field", "time_directory"]
