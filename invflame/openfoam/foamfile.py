"""Minimal reader of OpenFOAM data files: header, lists and the ``internalField`` of a field.

Reads what the ground truth needs, in ``ascii`` and ``binary`` write formats, optionally
gzip-compressed (``writeCompression on``): ``volScalarField`` / ``volVectorField``
``internalField`` (``uniform`` or ``nonuniform List<…>``), plain lists of labels, scalars or
vectors (``constant/polyMesh/owner``, ``neighbour``, ``points``) and ``faceList`` /
``faceCompactList`` (``faces``). Format reference: OpenFOAM User Guide, section 4.2
("Basic input/output file format").
"""

from __future__ import annotations

import gzip
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

_HEADER = re.compile(rb"FoamFile\s*\{(?P<body>[^}]*)\}")
_ENTRY = re.compile(rb"(\w+)\s+(\"[^\"]*\"|[^;]*?)\s*;")
_COUNT = re.compile(rb"\s*(\d+)\s*([({])")
_COMPONENTS = {"scalar": 1, "label": 1, "vector": 3, "symmTensor": 6, "tensor": 9}


class FoamFormatError(ValueError):
    """An OpenFOAM file this reader cannot parse; the message names the file and the reason."""


@dataclass(frozen=True)
class FoamFile:
    """Raw bytes of an OpenFOAM file with its parsed ``FoamFile`` header.

    Attributes
    ----------
    path : pathlib.Path
        File read (``.gz`` when compressed).
    header : dict of str to str
        ``FoamFile`` entries (``format``, ``class``, ``object``, ``arch``, ...).
    data : bytes
        Decompressed content.
    body_start : int
        Offset of the first byte after the header.
    """

    path: Path
    header: dict
    data: bytes
    body_start: int

    @property
    def binary(self) -> bool:
        """Whether the file was written with ``format binary``."""
        return self.header.get("format", "ascii") == "binary"

    def _size(self, kind: str, default: int) -> int:
        match = re.search(rf"{kind}=(\d+)", self.header.get("arch", ""))
        return int(match.group(1)) // 8 if match else default

    @property
    def label_dtype(self) -> np.dtype:
        """Binary label type from ``arch`` (``label=32`` by default)."""
        return np.dtype(f"<i{self._size('label', 4)}")

    @property
    def scalar_dtype(self) -> np.dtype:
        """Binary scalar type from ``arch`` (``scalar=64`` by default)."""
        return np.dtype(f"<f{self._size('scalar', 8)}")

    def error(self, reason: str) -> FoamFormatError:
        """A :class:`FoamFormatError` naming this file."""
        return FoamFormatError(f"{self.path}: {reason}")


def open_foam_file(path) -> FoamFile:
    """Read an OpenFOAM file (or its ``.gz`` sibling) and parse its header.

    Parameters
    ----------
    path : str or os.PathLike
        File path, with or without ``.gz``.

    Raises
    ------
    FileNotFoundError
        If neither ``path`` nor ``path.gz`` exists.
    FoamFormatError
        If there is no ``FoamFile`` header.
    """
    path = Path(path)
    if not path.exists() and path.with_name(path.name + ".gz").exists():
        path = path.with_name(path.name + ".gz")
    if not path.exists():
        raise FileNotFoundError(f"OpenFOAM file not found: {path} (nor {path}.gz)")
    raw = path.read_bytes()
    data = gzip.decompress(raw) if path.suffix == ".gz" else raw
    match = _HEADER.search(data)
    if match is None:
        raise FoamFormatError(f"{path}: no FoamFile header; is this an OpenFOAM data file?")
    header = {
        k.decode(): v.decode().strip('"') for k, v in _ENTRY.findall(match.group("body"))
    }
    return FoamFile(path, header, data, match.end())


def read_list(foam: FoamFile, pos: int, kind: str) -> tuple[np.ndarray, int]:
    """Parse a counted list ``N ( … )`` (or ``N{value}``) starting at byte ``pos``.

    Parameters
    ----------
    foam : FoamFile
        Open file.
    pos : int
        Offset at or before the count ``N``.
    kind : {"scalar", "label", "vector", "symmTensor", "tensor"}
        Element type.

    Returns
    -------
    values : numpy.ndarray
        Shape ``(N,)`` for scalars and labels, ``(N, k)`` otherwise (float64 or int64).
    end : int
        Offset just past the list.
    """
    ncomp = _COMPONENTS[kind]
    out_dtype = np.int64 if kind == "label" else np.float64
    match = _COUNT.match(foam.data, pos)
    if match is None:
        raise foam.error(f"expected a counted list 'N (...)' at byte {pos}")
    n, bracket, start = int(match.group(1)), match.group(2), match.end()
    if bracket == b"{":  # N{value}: every element equal
        end = foam.data.index(b"}", start)
        value = _parse_ascii(foam, foam.data[start:end], ncomp, out_dtype)
        return np.repeat(value.reshape(1, -1), n, axis=0).reshape(_shape(n, ncomp)), end + 1
    if foam.binary:
        dtype = foam.label_dtype if kind == "label" else foam.scalar_dtype
        nbytes = n * ncomp * dtype.itemsize
        if foam.data[start + nbytes : start + nbytes + 1] != b")":
            raise foam.error(
                f"binary list of {n} {kind}s at byte {start} does not end where expected; "
                f"check the arch entry ({foam.header.get('arch', 'absent')})"
            )
        values = np.frombuffer(foam.data, dtype=dtype, count=n * ncomp, offset=start)
        return values.astype(out_dtype).reshape(_shape(n, ncomp)), start + nbytes + 1
    end = _ascii_list_end(foam, start, ncomp)
    values = _parse_ascii(foam, foam.data[start:end], ncomp, out_dtype)
    if values.size != n * ncomp:
        raise foam.error(f"list announces {n} {kind}s but holds {values.size // ncomp}")
    return values.reshape(_shape(n, ncomp)), end + 1


def read_face_list(foam: FoamFile) -> tuple[np.ndarray, np.ndarray]:
    """Faces of a ``faceList`` (ascii) or ``faceCompactList`` file in compact form.

    Returns
    -------
    offsets : numpy.ndarray of int64, shape (n_faces + 1,)
        Face ``f`` has the point labels ``labels[offsets[f]:offsets[f + 1]]``.
    labels : numpy.ndarray of int64
        Point labels of all faces, concatenated.
    """
    start = foam.body_start + _skip_comments(foam)
    if foam.header.get("class") == "faceCompactList":
        offsets, end = read_list(foam, start, "label")
        labels, _ = read_list(foam, end, "label")
        return offsets, labels
    if foam.binary:
        raise foam.error("binary faces must be a faceCompactList")
    match = _COUNT.match(foam.data, start)
    if match is None or match.group(2) != b"(":
        raise foam.error("expected 'N (' before the faces")
    n = int(match.group(1))
    end = foam.data.rfind(b")")
    # "4(a b c d) 3(e f g) ..." -> sizes and labels interleaved
    tokens = np.array(
        foam.data[match.end() : end].replace(b"(", b" ").replace(b")", b" ").split(),
        dtype=np.int64,
    )
    offsets = np.zeros(n + 1, dtype=np.int64)
    keep = np.ones(len(tokens), dtype=bool)
    pos = 0
    for f in range(n):
        if pos >= len(tokens):
            raise foam.error(f"faces file announces {n} faces but holds {f}")
        keep[pos] = False
        offsets[f + 1] = offsets[f] + tokens[pos]
        pos += 1 + int(tokens[pos])
    if pos != len(tokens):
        raise foam.error(f"faces file holds more than the {n} faces it announces")
    return offsets, tokens[keep]


def read_plain_list(foam: FoamFile, kind: str) -> np.ndarray:
    """The one list that forms the body of e.g. ``points``, ``owner`` or ``neighbour``."""
    values, _ = read_list(foam, foam.body_start + _skip_comments(foam), kind)
    return values


def read_internal_field(path, kind: str = "scalar") -> np.ndarray | float:
    """``internalField`` of an OpenFOAM volume field file.

    Parameters
    ----------
    path : str or os.PathLike
        Field file, e.g. ``case/0.9/T``.
    kind : {"scalar", "vector", ...}
        Element type (``volScalarField`` → "scalar").

    Returns
    -------
    numpy.ndarray or float or tuple
        Per-cell values (``(N,)`` or ``(N, k)``), or the single value of a ``uniform`` field
        (float for scalars, array of k components otherwise).
    """
    foam = open_foam_file(path)
    at = foam.data.find(b"internalField", foam.body_start)
    if at < 0:
        raise foam.error("no internalField entry; is this a volume field?")
    pos = at + len(b"internalField")
    rest = foam.data[pos : pos + 200].lstrip()
    if rest.startswith(b"uniform"):
        text = rest[len(b"uniform") :].split(b";", 1)[0]
        value = _parse_ascii(foam, text, _COMPONENTS[kind], np.float64)
        return float(value[0]) if value.size == 1 else value
    match = re.match(rb"\s*nonuniform\s+List<(\w+)>", foam.data[pos:])
    if match is None:
        raise foam.error("internalField is neither 'uniform' nor 'nonuniform List<...>'")
    if match.group(1).decode() != kind:
        raise foam.error(f"internalField holds {match.group(1).decode()}s, not {kind}s")
    values, _ = read_list(foam, pos + match.end(), kind)
    return values


def _shape(n: int, ncomp: int) -> tuple[int, ...]:
    return (n,) if ncomp == 1 else (n, ncomp)


def _skip_comments(foam: FoamFile) -> int:
    """Bytes of comment lines and blanks right after the header."""
    body = foam.data[foam.body_start :]
    match = re.match(rb"(\s|//[^\n]*\n|/\*.*?\*/)*", body, flags=re.DOTALL)
    return match.end()


def _ascii_list_end(foam: FoamFile, start: int, ncomp: int) -> int:
    """Offset of the ``)`` closing an ascii list whose content starts at ``start``."""
    if ncomp == 1:
        end = foam.data.find(b")", start)
    else:  # elements are (a b c): the closing bracket follows another closing bracket
        match = re.compile(rb"\)\s*\)").search(foam.data, start)
        end = -1 if match is None else match.end() - 1
        if foam.data[start:end].strip() == b"":
            end = foam.data.find(b")", start)
    if end < 0:
        raise foam.error(f"unterminated list starting at byte {start}")
    return end


def _parse_ascii(foam: FoamFile, text: bytes, ncomp: int, dtype) -> np.ndarray:
    tokens = text.replace(b"(", b" ").replace(b")", b" ").split()
    try:
        values = np.array(tokens, dtype=np.float64)
    except ValueError as err:
        raise foam.error(f"non-numeric entry in list: {err}") from err
    if values.size % ncomp:
        raise foam.error(f"list of {values.size} numbers is not a multiple of {ncomp} components")
    return values.astype(dtype)
