"""OpenFOAM files (ascii or binary, optionally gzipped) parsed by foamlib; errors name the file."""

from __future__ import annotations

import gzip
import re
from pathlib import Path

import numpy as np
from foamlib import FoamFile, FoamFileDecodeError

from invflame.errors import InputDataError


class FoamFormatError(InputDataError):
    """An OpenFOAM file or mesh that cannot be read or used (it does not parse, lacks an
    entry, or is not what it should be); the message names the file."""


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
    content = _parse(*_read_bytes(path))
    for keyword in keywords:
        content = content.get(keyword) if isinstance(content, dict) else None
    return content


def read_labels(path) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """A mesh's labels, ``polyMesh/owner`` or ``neighbour`` (or ``faces``), as int64.

    The label size of a binary file is its header's ``arch`` entry (``label=32`` or
    ``label=64``): foamlib reads a binary list of 64-bit labels as float64 numbers of the same
    bytes, which are taken back as the integers they are.

    Returns
    -------
    numpy.ndarray or tuple of numpy.ndarray
        The labels; for a face list, ``(offsets, labels)``: face ``i`` has the points
        ``labels[offsets[i]:offsets[i + 1]]``.

    Raises
    ------
    FoamFormatError
        If the file does not parse, or holds other than non-negative integers (e.g. labels
        of another size than its header says).
    """
    path, data = _read_bytes(path)
    content = _parse(path, data)
    bits = re.search(rb'arch\s+"[^"]*label\s*=\s*(\d+)', data[:4096])
    wide = bits is not None and bits.group(1) == b"64"
    if isinstance(content, list):  # faceList: one label array per face
        content = (np.cumsum([0] + [len(face) for face in content]),
                   np.concatenate(content) if content else np.zeros(0))
    parts = content if isinstance(content, tuple) else (content,)
    labels = []
    for part in parts:
        part = np.asarray(part)
        if part.dtype.kind == "f" and wide and part.dtype.itemsize == 8:
            part = part.view(np.int64)
        if part.dtype.kind not in "iuf" or part.ndim != 1 or (part.size and part.min() < 0) \
                or not np.array_equal(part, np.round(part)):
            raise FoamFormatError(f"{path}: not a list of mesh labels (non-negative "
                                  f"integers; found {part.dtype} of shape {part.shape}); check "
                                  "the 'arch' entry's label size")
        labels.append(part.astype(np.int64))
    return tuple(labels) if isinstance(content, tuple) else labels[0]


def _read_bytes(path) -> tuple[Path, bytes]:
    """The file ``path`` (or ``path.gz``) and its content, decompressed."""
    path = foam_path(path)
    if not path.is_file():
        raise FileNotFoundError(f"OpenFOAM file not found: {path} (nor {path.name}.gz)")
    data = path.read_bytes()
    return path, gzip.decompress(data) if path.suffix == ".gz" else data


def _parse(path: Path, data: bytes):
    """``data``, the content of the file ``path``, parsed by foamlib."""
    _check_closed(path, data)
    try:
        return FoamFile.loads(data)
    except FoamFileDecodeError as err:
        expected = str(err).rsplit("\n", 1)[-1]
        raise FoamFormatError(
            f"{path}: the data does not end where expected: parsing stopped at line {err.lineno}"
            f", column {err.colno} ({expected}); check that the file is complete, that each list"
            " holds as many items as its count says and, if binary, the 'arch' entry") from err


def _check_closed(path: Path, data: bytes) -> None:
    """Refuse an ascii file that leaves a ``(`` or ``{`` open (comments aside), naming where:
    a file cut short, which foamlib's parser would search for a very long time."""
    if re.search(rb"format\s+binary", data[:4096]):
        return  # binary lists may hold any byte
    text = re.sub(rb"//[^\n]*|/\*.*?\*/", lambda m: re.sub(rb"[^\n]", b" ", m.group()), data,
                  flags=re.DOTALL)  # comments blanked, lines kept
    for opening, closing in ((b"(", b")"), (b"{", b"}")):
        if text.count(opening) <= text.count(closing):
            continue
        unclosed = []
        for match in re.finditer(re.escape(opening) + b"|" + re.escape(closing), text):
            if match.group() == opening:
                unclosed.append(match.start())
            elif unclosed:
                unclosed.pop()
        at = unclosed[0]
        line, column = text.count(b"\n", 0, at) + 1, at - text.rfind(b"\n", 0, at)
        raise FoamFormatError(f"{path}: the '{opening.decode()}' at line {line}, column {column} "
                              "is never closed: the file is cut short (an interrupted write?); "
                              "write it again")


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
