"""Cell centres of an OpenFOAM mesh and their mapping onto a regular voxel grid."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from invflame.geometry import VoxelGrid
from invflame.openfoam.foamfile import (
    open_foam_file,
    read_face_list,
    read_internal_field,
    read_plain_list,
)


def cell_centres(case, time_dir: str | None = None) -> np.ndarray:
    """Cell centres of a case in m, shape ``(n_cells, 3)``.

    Uses the ``C`` field that ``postProcess -func writeCellCentres`` writes (looked for in
    ``time_dir``, then ``0``, then ``constant``); otherwise averages each cell's vertices from
    ``constant/polyMesh`` (``points``, ``faces``, ``owner``, ``neighbour``), which is exact for
    the parallelepiped cells of a ``blockMesh`` box.

    Parameters
    ----------
    case : str or os.PathLike
        Case folder.
    time_dir : str, optional
        Name of the time folder to look in first.
    """
    case = Path(case)
    for folder in ([time_dir] if time_dir else []) + ["0", "constant"]:
        path = case / folder / "C"
        if path.exists() or path.with_name("C.gz").exists():
            centres = read_internal_field(path, "vector")
            if np.ndim(centres) == 2:
                return centres
    return _vertex_average_centres(case / "constant" / "polyMesh")


def mesh_box(case) -> tuple[np.ndarray, np.ndarray] | None:
    """Bounds ``(lower, upper)`` in m of ``constant/polyMesh/points``, or None without a mesh."""
    path = Path(case) / "constant" / "polyMesh" / "points"
    if not (path.exists() or path.with_name("points.gz").exists()):
        return None
    points = read_plain_list(open_foam_file(path), "vector")
    lower, upper = points.min(axis=0), points.max(axis=0)
    # drop the last bits of blockMesh's arithmetic (0.5000000000000001 -> 0.5)
    decimals = 10 - int(np.floor(np.log10(np.max(upper - lower))))
    return np.round(lower, decimals) + 0.0, np.round(upper, decimals) + 0.0


def _vertex_average_centres(mesh: Path) -> np.ndarray:
    if not mesh.is_dir():
        raise FileNotFoundError(
            f"no cell centres: neither a C field nor a mesh folder {mesh}; run blockMesh, or "
            "'postProcess -func writeCellCentres'"
        )
    points = read_plain_list(open_foam_file(mesh / "points"), "vector")
    offsets, labels = read_face_list(open_foam_file(mesh / "faces"))
    owner = read_plain_list(open_foam_file(mesh / "owner"), "label")
    neighbour = read_plain_list(open_foam_file(mesh / "neighbour"), "label")
    n_cells = int(owner.max()) + 1
    # (cell, point) pairs from both sides of every face, then unique per cell
    face_of_label = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    cells = np.concatenate(
        [owner[face_of_label], neighbour[face_of_label[face_of_label < len(neighbour)]]]
    )
    pts = np.concatenate([labels, labels[face_of_label < len(neighbour)]])
    pairs = np.sort(cells * (len(points) + 1) + pts)
    pairs = pairs[np.concatenate([[True], np.diff(pairs) != 0])]  # unique, without hashing
    cell_of_pair, point_of_pair = np.divmod(pairs, len(points) + 1)
    count = np.bincount(cell_of_pair, minlength=n_cells)
    sums = np.stack(
        [np.bincount(cell_of_pair, weights=points[point_of_pair, a], minlength=n_cells)
         for a in range(3)],
        axis=1,
    )
    return sums / count[:, None]


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
        Exact box of the mesh in m (e.g. the bounds of ``polyMesh/points``); used instead of
        the box implied by the centres, which carries their write precision, after checking
        that the two agree to 1 % of a cell.

    Returns
    -------
    grid : VoxelGrid
        Box spanning the cells (centres ± half a cell), shape = distinct centre coordinates.
    flat_index : numpy.ndarray of int64, shape (n_cells,)
        C-order voxel index of each cell: ``values.reshape(-1)[flat_index] = cell_values``.

    Raises
    ------
    ValueError
        If the cells do not form one uniform, axis-aligned, complete box grid (graded,
        refined, rotated or unstructured meshes); the message says which axis failed.
    """
    centres = np.asarray(centres, dtype=np.float64)
    if centres.ndim != 2 or centres.shape[1] != 3 or len(centres) == 0:
        raise ValueError(f"cell centres must have shape (n_cells, 3); got {centres.shape}")
    size = float(np.ptp(centres, axis=0).max())
    lower, spacing, shape, index = [], [], [], []
    for a, name in enumerate("xyz"):
        coords = np.sort(centres[:, a])
        breaks = np.nonzero(np.diff(coords) > 1e-6 * size)[0]
        levels = np.concatenate([[coords[0]], coords[breaks + 1]])
        if len(levels) < 2:
            raise ValueError(
                f"a single layer of cells along {name} (a 2-D case?) has no grid spacing; "
                "need at least two cells per axis"
            )
        step = (levels[-1] - levels[0]) / (len(levels) - 1)
        if not np.allclose(np.diff(levels), step, rtol=1e-3, atol=0):
            d = np.diff(levels)
            raise ValueError(
                f"mesh is not a uniform grid along {name}: cell spacing varies from {d.min():.6g}"
                f" to {d.max():.6g} m over {len(levels)} distinct cell-centre coordinates. Map "
                "the case onto a uniform blockMesh box first (e.g. OpenFOAM's mapFields)"
            )
        lower.append(levels[0] - step / 2)
        spacing.append(step)
        shape.append(len(levels))
        index.append(np.rint((centres[:, a] - levels[0]) / step).astype(np.int64))
    if len(centres) != int(np.prod(shape)):
        raise ValueError(
            f"{len(centres)} cells do not fill a {shape[0]}×{shape[1]}×{shape[2]} box grid "
            "(missing or refined cells); only complete uniform box meshes can be mapped"
        )
    flat = np.ravel_multi_index(tuple(index), tuple(shape))
    if len(np.unique(flat)) != len(flat):
        raise ValueError("two cells map to one voxel; the mesh is not a uniform box grid")
    lower, spacing = np.array(lower), np.array(spacing)
    upper = lower + spacing * np.array(shape)
    if box is not None:
        box_lower, box_upper = (np.asarray(b, dtype=np.float64) for b in box)
        if np.any(np.abs(box_lower - lower) > 0.01 * spacing) or np.any(
            np.abs(box_upper - upper) > 0.01 * spacing
        ):
            raise ValueError(
                f"mesh box {box_lower} .. {box_upper} m disagrees with the cell centres' box "
                f"{lower} .. {upper} m"
            )
        lower, upper = box_lower, box_upper
    grid = VoxelGrid(lower, upper, tuple(shape), up_axis=up_axis)
    return grid, flat
