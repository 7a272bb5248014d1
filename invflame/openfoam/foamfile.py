"""OpenFOAM files (ascii or binary, optionally gzipped) parsed by foamlib; errors name the file."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
from foamlib import FoamFile, FoamFileDecodeError


class FoamFormatError(ValueError):
    """An OpenFOAM file that cannot be parsed or lacks an entry; the message names the file."""


def foam_path(path) -> Path:
    """``path``, or its ``.gz`` sibling when only that exists (``writeCompression on``)."""
    path = Path(path)
    gz = path.with_name(path.name + ".gz")
    return gz if not path.is_file() and gz.is_file() else path


def read_foam(path, *keywords):
    """Content of the OpenFOAM file ``path`` (or ``path.gz``), parsed by foamlib.

    Returns
    -------
    dict or numpy.ndarray or list or tuple or float or str or None
        The entries (numeric lists as arrays, no ``FoamFile`` header) or the one list of a
        file such as ``polyMesh/points``; with ``keywords``, the entry they name in nested
        dictionaries (``"O2", "specie", "molWeight"``), None if absent. FileNotFoundError if
        neither file exists, :class:`FoamFormatError` (line, column) if it cannot be parsed.
    """
    path = foam_path(path)
    if not path.is_file():
        raise FileNotFoundError(f"OpenFOAM file not found: {path} (nor {path.name}.gz)")
    data = path.read_bytes()
    try:
        content = FoamFile.loads(gzip.decompress(data) if path.suffix == ".gz" else data)
    except FoamFileDecodeError as err:
        expected = str(err).rsplit("\n", 1)[-1]
        raise FoamFormatError(
            f"{path}: the data does not end where expected: parsing stopped at line {err.lineno}"
            f", column {err.colno} ({expected}); check that the file is complete, that each list"
            " holds as many items as its count says and, if binary, the 'arch' entry") from err
    for keyword in keywords:
        content = content.get(keyword) if isinstance(content, dict) else None
    return content


def read_internal_field(path, n_cells: int | None = None) -> np.ndarray | float:
    """``internalField`` of an OpenFOAM scalar field file, e.g. ``case/0.9/T`` (or ``T.gz``).

    Parameters
    ----------
    path : str or os.PathLike
        Field file.
    n_cells : int, optional
        Cells of the mesh: the length is checked against it, a ``uniform`` value repeated.

    Returns
    -------
    numpy.ndarray or float
        Values in the field's units, float64, shape ``(n_cells,)`` (a float for a ``uniform``
        field without ``n_cells``); else :class:`FoamFormatError`.
    """
    value = read_foam(path, "internalField")
    if not isinstance(value, int | float | np.ndarray):
        raise FoamFormatError(f"{foam_path(path)}: no internalField of numbers (entry absent, "
                              "not numeric, or a list whose count disagrees with its items)")
    value = np.asarray(value, dtype=np.float64)
    if value.ndim > 1 or (n_cells is not None and value.ndim and len(value) != n_cells):
        found = f"{value.shape[1]}-component values" if value.ndim > 1 else f"{len(value)} values"
        raise FoamFormatError(f"{foam_path(path)}: internalField holds {found}, not "
                              f"{n_cells or 'per-cell'} scalars (one per cell of the mesh)")
    if n_cells is None:
        return float(value) if value.ndim == 0 else value
    return np.broadcast_to(value, (n_cells,))
