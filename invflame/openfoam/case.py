"""Read one time of an OpenFOAM reacting-flow case as a :class:`~invflame.field.Field`."""

from __future__ import annotations

import gzip
import re
from pathlib import Path

import numpy as np
from foamlib import FoamCase

from invflame.field import FIELD_NAMES, SPECIES, Field
from invflame.openfoam.foamfile import FoamFormatError, foam_path, read_foam, read_internal_field
from invflame.openfoam.mesh import cell_centres, grid_from_centres, mesh_box
from invflame.phantoms.composition import MOLAR_MASS, mass_to_mole_fractions


def time_directory(case, time) -> Path:
    """Folder of ``time`` (s) in a case, matched numerically (``0.90`` finds ``0.9``); else a
    FileNotFoundError lists the times present and hints at ``reconstructPar`` when only
    ``processor*`` folders hold it."""
    case = Path(case)
    times = FoamCase(case)  # FileNotFoundError naming the folder if it does not exist
    for t in times:
        if abs(t.time - float(time)) <= 1e-9 * max(1.0, abs(float(time))):
            return t.path
    hint = (f"; the case is decomposed: run 'reconstructPar -time {time}' in {case}"
            if any(case.glob(f"processor*/{time}")) else "")
    raise FileNotFoundError(
        f"time {time} not found in {case}; times present: {[t.time for t in times]}{hint}"
    )


def read_case(case, time) -> Field:
    """Temperature and mole fractions of CO2, H2O, CH4 at one time of an OpenFOAM case.

    Reads ``T`` and the mass fractions ``Y_i`` of all species (``species`` of
    ``constant/reactions`` or ``thermophysicalProperties``), converts them to mole fractions
    ``X_i = (Y_i/W_i) / Σ_j (Y_j/W_j)`` (``Y`` clipped to [0, 1]; ``W`` in g/mol: ``molWeight``
    in ``constant/thermo*``, else :data:`~invflame.phantoms.composition.MOLAR_MASS`) and maps
    the cells onto the grid they form. Species of :data:`~invflame.field.SPECIES` the case
    lacks are zero.

    Parameters
    ----------
    case : str or os.PathLike
        Case folder (reconstructed, not only ``processor*``).
    time : float or str
        Simulated time in s.

    Returns
    -------
    Field
        T in K and mole fractions on the cells' grid; metadata records the solver, OpenFOAM
        version, case, time, species, molar masses and ``absent_species``.

    Raises
    ------
    FileNotFoundError
        Missing case, time, species list, field or mesh file.
    FoamFormatError
        A file that cannot be parsed (cut short, or its counts or labels wrong); a field not
        scalar or of the wrong length; a species without molar mass; a mesh that is not a
        uniform box grid (naming the mesh folder).
    """
    case = Path(case)
    tdir = time_directory(case, time)
    masses = _molar_masses(case)
    if missing := [s for s in masses if not foam_path(tdir / s).is_file()]:
        raise FileNotFoundError(f"species {missing} are not written in {tdir}")
    centres = cell_centres(case)
    n = len(centres)
    mole = mass_to_mole_fractions({s: read_internal_field(tdir / s, n) for s in masses}, masses)
    try:
        grid, flat = grid_from_centres(centres, _up_axis(case), mesh_box(case))
    except ValueError as err:
        raise FoamFormatError(f"{case / 'constant' / 'polyMesh'}: {err}") from err
    cells = {"T": read_internal_field(tdir / "T", n), **mole}
    values = np.zeros((len(FIELD_NAMES), grid.n_voxels))
    values[:, flat] = [cells.get(name, np.zeros(n)) for name in FIELD_NAMES]
    control = case / "system" / "controlDict"
    solver = read_foam(control, "application") if control.is_file() else None
    metadata = {
        "source": "OpenFOAM",
        "solver": solver,
        "version": _foam_version(case, solver, foam_path(tdir / "T")),
        "case": case.resolve().name,
        "time": float(tdir.name),
        "species": list(masses),
        "molar_masses_g_per_mol": masses,
        "absent_species": [s for s in SPECIES if s not in mole],
        "conversion": "X_i = (Y_i/W_i) / sum_j(Y_j/W_j) over all species of the case",
    }
    return Field(grid, values.reshape(len(FIELD_NAMES), *grid.shape), metadata)


def _molar_masses(case: Path) -> dict[str, float]:
    """Species of the case in order, with molar masses in g/mol."""
    constant = case / "constant"
    files = [constant / "reactions", constant / "thermophysicalProperties"]
    lists = [read_foam(p, "species") for p in files if p.is_file()]
    species = next((list(s) for s in lists if s is not None), None)
    if species is None:
        raise FileNotFoundError(f"no 'species ( ... )' list in {constant}/reactions or "
                                "thermophysicalProperties; is this a reacting case?")
    thermo = sorted(p for p in constant.glob("thermo*") if p.is_file())
    masses = {}
    for s in species:
        found = [w for p in thermo if (w := read_foam(p, s, "specie", "molWeight")) is not None]
        masses[s] = float(next(iter(found), MOLAR_MASS.get(s, np.nan)))
        if np.isnan(masses[s]):
            raise FoamFormatError(f"no molWeight for species {s!r} in {constant}/thermo* and "
                                  "none tabulated; add it to the case's thermo dictionary")
    return masses


def _up_axis(case: Path) -> int:
    """Axis opposite to gravity, from ``constant/g`` (1, i.e. y, when there is no such file)."""
    path = case / "constant" / "g"
    g = np.asarray(read_foam(path, "value") if path.is_file() else [0, -1, 0], dtype=np.float64)
    if g.shape != (3,):
        raise FoamFormatError(f"{path}: no 'value (gx gy gz)' entry")
    return int(np.argmax(np.abs(g)))


def _foam_version(case: Path, solver: str | None, field_path: Path) -> str | None:
    """OpenFOAM build from the solver log (``Build : ...``), else the field file's banner."""
    logs = [(case / f"log.{solver}", rb"(?m)^Build\s*:\s*(.+)$")] if solver else []
    for path, pattern in [*logs, (field_path, rb"Version:\s*(v?\d[\w.+-]*)")]:
        if path.is_file():
            with (gzip.open if path.suffix == ".gz" else open)(path, "rb") as fh:
                if match := re.search(pattern, fh.read(4096)):
                    return match.group(1).decode(errors="replace").strip()
    return None
