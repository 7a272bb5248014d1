"""A tiny OpenFOAM case written from scratch (no OpenFOAM needed): box mesh, T and species."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

SPECIES = ("O2", "H2O", "CH4", "CO2", "N2")
MOLAR_MASSES = {"O2": 32.0, "H2O": 18.0, "CH4": 16.0, "CO2": 44.0, "N2": 28.0}

_BANNER = """/*--------------------------------*- C++ -*----------------------------------*\\
|  \\\\    /   O peration     | Version:  v1912                                 |
\\*---------------------------------------------------------------------------*/
"""


def _header(cls: str, obj: str, fmt: str, label_bits: int = 32) -> bytes:
    arch = f'    arch        "LSB;label={label_bits};scalar=64";\n' if fmt == "binary" else ""
    return (
        f"{_BANNER}FoamFile\n{{\n    version     2.0;\n    format      {fmt};\n{arch}"
        f"    class       {cls};\n    object      {obj};\n}}\n"
        "// * * * * * * * * * * * * * * * * * * * * * * * * * * * * * //\n\n"
    ).encode()


def _list(values: np.ndarray, fmt: str, kind: str, label_bits: int = 32) -> bytes:
    values = np.asarray(values)
    n = len(values)
    if fmt == "binary":
        dtype = f"<i{label_bits // 8}" if kind == "label" else "<f8"
        return f"{n}\n(".encode() + values.astype(dtype).tobytes() + b")\n"
    if values.ndim == 1:
        body = "\n".join(repr(v.item()) for v in values)
    else:
        body = "\n".join("(" + " ".join(repr(x) for x in row.tolist()) + ")" for row in values)
    return f"{n}\n(\n{body}\n)\n".encode()


def _write(path: Path, content: bytes, compress: bool) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if compress:
        path.with_name(path.name + ".gz").write_bytes(gzip.compress(content))
    else:
        path.write_bytes(content)


def _box_mesh(edges):
    """Points, faces (vertex labels), owner, neighbour of a structured hex mesh."""
    nx, ny, nz = (len(e) - 1 for e in edges)
    pts = np.stack(np.meshgrid(*edges, indexing="ij"), axis=-1).reshape(-1, 3)

    def pid(i, j, k):
        return (i * (ny + 1) + j) * (nz + 1) + k

    def cid(i, j, k):
        return (i * ny + j) * nz + k

    def quad(axis, i, j, k):  # face normal to axis at lattice point (i, j, k)
        d = [(0, 1, 0), (0, 0, 1)] if axis == 0 else [(1, 0, 0), (0, 0, 1)] if axis == 1 else [
            (1, 0, 0), (0, 1, 0)]
        a, b = d
        corners = [(0, 0, 0), a, tuple(x + y for x, y in zip(a, b, strict=True)), b]
        return [pid(i + c[0], j + c[1], k + c[2]) for c in corners]

    internal, boundary = [], []
    n = (nx, ny, nz)
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                idx = (i, j, k)
                for axis in range(3):
                    up = list(idx)
                    up[axis] += 1
                    if up[axis] < n[axis]:
                        internal.append((quad(axis, *up), cid(*idx), cid(*up)))
                    else:
                        boundary.append((quad(axis, *up), cid(*idx)))
                    if idx[axis] == 0:
                        boundary.append((quad(axis, *idx), cid(*idx)))
    faces = [f for f, _, _ in internal] + [f for f, _ in boundary]
    owner = [o for _, o, _ in internal] + [o for _, o in boundary]
    neighbour = [nb for _, _, nb in internal]
    return pts, faces, np.array(owner), np.array(neighbour)


def write_case(
    root: Path,
    edges=None,
    fmt: str = "ascii",
    compress: bool = False,
    with_centres: bool = False,
    time: str = "0.5",
    label_bits: int = 32,
) -> dict:
    """Write a case; return the expected per-cell T and mass fractions (C order over ix, iy, iz).

    ``edges``: cell edges per axis (default a 3×4×2 box over x ∈ [−0.3, 0.3], y ∈ [0, 1],
    z ∈ [−0.1, 0.1]). T = 300 + 1000 y + 10 x; CO2 and H2O grow with T, CH4 with x, O2
    uniform, N2 the rest. ``label_bits``: the size of a binary mesh's labels (32 or 64).
    """
    if edges is None:
        edges = (np.linspace(-0.3, 0.3, 4), np.linspace(0.0, 1.0, 5), np.linspace(-0.1, 0.1, 3))
    edges = [np.asarray(e, dtype=np.float64) for e in edges]
    pts, faces, owner, neighbour = _box_mesh(edges)
    mesh = root / "constant" / "polyMesh"
    _write(mesh / "points", _header("vectorField", "points", fmt) + _list(pts, fmt, "v"),
           compress)
    bits = {"label_bits": label_bits}
    if fmt == "binary":
        offsets = np.concatenate([[0], np.cumsum([len(f) for f in faces])])
        body = (_list(offsets, fmt, "label", **bits)
                + _list(np.concatenate(faces), fmt, "label", **bits))
        _write(mesh / "faces", _header("faceCompactList", "faces", fmt, **bits) + body, compress)
    else:
        body = f"{len(faces)}\n(\n" + "\n".join(
            f"{len(f)}(" + " ".join(map(str, f)) + ")" for f in faces) + "\n)\n"
        _write(mesh / "faces", _header("faceList", "faces", fmt) + body.encode(), compress)
    for name, labels in (("owner", owner), ("neighbour", neighbour)):
        _write(mesh / name, _header("labelList", name, fmt, **bits)
               + _list(labels, fmt, "label", **bits), compress)

    constant = root / "constant"
    (constant / "reactions").write_text(
        "// species of the mixture\nspecies\n(\n    " + "\n    ".join(SPECIES) + "\n);\n"
    )
    (constant / "thermo.compressibleGas").write_text("".join(
        f"{s}\n{{\n    specie\n    {{\n        molWeight       {w};\n    }}\n}}\n"
        for s, w in MOLAR_MASSES.items()
    ))
    (constant / "g").write_text("dimensions [0 1 -2 0 0 0 0];\nvalue (0 -9.81 0);\n")
    (root / "system").mkdir(parents=True, exist_ok=True)
    (root / "system" / "controlDict").write_text("application     fireFoam;\nendTime 0.5;\n")

    centres = np.stack(
        np.meshgrid(*[(e[1:] + e[:-1]) / 2 for e in edges], indexing="ij"), axis=-1
    ).reshape(-1, 3)
    x, y = centres[:, 0], centres[:, 1]
    temperature = 300 + 1000 * y + 10 * x
    mass = {
        "CO2": 0.1 * (temperature - 290) / 1300,
        "H2O": 0.08 * (temperature - 290) / 1300,
        "CH4": 0.2 * (x - x.min()) / np.ptp(x),
        "O2": np.full_like(x, 0.15),
    }
    mass["N2"] = 1 - sum(mass.values())
    tdir = root / time
    fields = {"T": temperature, **mass}
    for name, values in fields.items():
        content = (_header("volScalarField", name, fmt)
                   + b"dimensions [0 0 0 0 0 0 0];\n\ninternalField   nonuniform List<scalar> "
                   + _list(values, fmt, "scalar")
                   + b";\n\nboundaryField\n{\n    walls { type zeroGradient; }\n}\n")
        _write(tdir / name, content, compress)
    if with_centres:
        content = (_header("volVectorField", "C", fmt)
                   + b"dimensions [0 1 0 0 0 0 0];\ninternalField   nonuniform List<vector> "
                   + _list(centres, fmt, "vector") + b";\nboundaryField\n{\n}\n")
        _write(tdir / "C", content, compress)
    return {"centres": centres, "shape": tuple(len(e) - 1 for e in edges), **fields}


@pytest.fixture
def tiny_case(tmp_path):
    """Factory: ``tiny_case(**write_case kwargs) -> (case_path, expected)``."""

    def make(**kwargs):
        case = tmp_path / f"case{len(list(tmp_path.iterdir()))}"
        return case, write_case(case, **kwargs)

    return make
