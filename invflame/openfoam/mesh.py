"""Cell centres of an OpenFOAM mesh and their mapping onto a regular voxel grid."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from invflame.geometry import VoxelGrid
from invflame.openfoam.foamfile import FoamFormatError, read_foam, read_labels


def cell_centres(case) -> np.ndarray:
    """Cell centres in m, shape ``(n_cells, 3)``, of the mesh in ``case/constant/polyMesh``.

    Each is the mean of its cell's face centres (a face centre: the mean of its points), which
    is the centroid of the cuboid cells :func:`grid_from_centres` accepts. Binary meshes may
    have 32- or 64-bit labels (:func:`~invflame.openfoam.foamfile.read_labels`).

    Raises
    ------
    FileNotFoundError
        If a mesh file is missing.
    FoamFormatError
        If a mesh file cannot be parsed, or its faces, owners and neighbours do not fit
        together (naming the file or the mesh folder).
    """
    mesh = Path(case) / "constant" / "polyMesh"
    points = np.asarray(read_foam(mesh / "points"), dtype=np.float64)
    offsets, labels = read_labels(mesh / "faces")
    owner, neighbour = read_labels(mesh / "owner"), read_labels(mesh / "neighbour")
    if labels.size and labels.max() >= len(points):
        raise FoamFormatError(f"{mesh / 'faces'}: point label {labels.max()} in a mesh of "
                              f"{len(points)} points; check the 'arch' entry's label size")
    if len(owner) != len(offsets) - 1 or len(neighbour) > len(owner):
        raise FoamFormatError(f"{mesh}: {len(offsets) - 1} faces, {len(owner)} owners and "
                              f"{len(neighbour)} neighbours do not form a mesh (one owner per "
                              "face, a neighbour per internal face)")
    centres = np.add.reduceat(points[labels], offsets[:-1]) / np.diff(offsets)[:, None]
    cells = np.concatenate([owner, neighbour])
    centres = np.concatenate([centres, centres[: len(neighbour)]])
    sums = [np.bincount(cells, weights=centres[:, a]) for a in range(3)]
    return np.stack(sums, axis=1) / np.bincount(cells)[:, None]


def mesh_box(case) -> tuple[np.ndarray, np.ndarray]:
    """Bounds ``(lower, upper)`` in m of the points of ``case/constant/polyMesh``."""
    points = np.asarray(read_foam(Path(case) / "constant/polyMesh/points"), dtype=np.float64)
    lower, upper = points.min(axis=0), points.max(axis=0)
    # drop the last bits of blockMesh's arithmetic (0.5000000000000001 -> 0.5)
    decimals = 10 - int(np.floor(np.log10(np.max(upper - lower))))
    return np.round(lower, decimals) + 0.0, np.round(upper, decimals) + 0.0


def grid_from_centres(
    centres: np.ndarray, up_axis: int = 1, box: tuple | None = None
) -> tuple[VoxelGrid, np.ndarray]:
    """Regular grid whose voxel centres are exactly the given cell centres.

    Parameters
    ----------
    centres : numpy.ndarray, shape (n_cells, 3)
        Cell centres in m.
    up_axis : int, optional
        Vertical axis of the case (OpenFOAM's ``g`` points along ``-up_axis``).
    box : (lower, upper), optional
        Exact box of the mesh in m (e.g. :func:`mesh_box`), used instead of the box implied by
        the centres (which carries their write precision) if the two agree to 1 % of a cell.

    Returns
    -------
    grid : VoxelGrid
        Box spanning the cells (centres ± half a cell), shape = distinct centre coordinates.
    flat_index : numpy.ndarray of int64, shape (n_cells,)
        C-order voxel index of each cell: ``values.reshape(-1)[flat_index] = cell_values``.

    Raises
    ------
    ValueError
        If the cells are not one uniform, axis-aligned, complete box grid; names the axis.
    """
    centres = np.asarray(centres, dtype=np.float64)
    if centres.ndim != 2 or centres.shape[1] != 3 or len(centres) == 0:
        raise ValueError(f"cell centres must have shape (n_cells, 3); got {centres.shape}")
    size = float(np.ptp(centres, axis=0).max())
    axes, index = [], []
    for a, name in enumerate("xyz"):
        coords = np.sort(centres[:, a])
        levels = coords[np.concatenate([[True], np.diff(coords) > 1e-6 * size])]
        if len(levels) < 2:
            raise ValueError(f"a single layer of cells along {name} (a 2-D case?) has no "
                             "grid spacing; need at least two cells per axis")
        step, d = (levels[-1] - levels[0]) / (len(levels) - 1), np.diff(levels)
        if not np.allclose(d, step, rtol=1e-3, atol=0):
            raise ValueError(f"mesh is not a uniform grid along {name}: cell spacing varies from "
                             f"{d.min():.6g} to {d.max():.6g} m over {len(levels)} distinct cell-"
                             "centre coordinates. Map the case onto a uniform blockMesh box first "
                             "(e.g. OpenFOAM's mapFields)")
        axes.append((levels[0] - step / 2, step, len(levels)))
        index.append(np.rint((centres[:, a] - levels[0]) / step).astype(np.int64))
    lower, spacing, shape = (np.array(v) for v in zip(*axes, strict=True))
    flat = np.ravel_multi_index(tuple(index), shape)
    if len(centres) != np.prod(shape) or len(np.unique(flat)) != len(flat):
        raise ValueError(
            f"{len(centres)} cells do not fill a {shape[0]}×{shape[1]}×{shape[2]} box grid one "
            "to one (missing, refined or overlapping cells); only complete uniform box meshes"
        )
    upper = lower + spacing * shape
    if box is not None:
        box = np.asarray(box, dtype=np.float64)
        if np.any(np.abs(box - [lower, upper]) > 0.01 * spacing):
            raise ValueError(f"mesh box {box[0]} .. {box[1]} m disagrees with the cell "
                             f"centres' box {lower} .. {upper} m")
        lower, upper = box
    grid = VoxelGrid(lower, upper, shape, up_axis=up_axis)
    return grid, flat
