"""Read one time of an OpenFOAM reacting-flow case as a :class:`~invflame.field.Field`."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from invflame.field import FIELD_NAMES, SPECIES, Field
from invflame.openfoam.foamfile import open_foam_file, read_internal_field
from invflame.openfoam.mesh import cell_centres, grid_from_centres, mesh_box
from invflame.phantoms.composition import MOLAR_MASS, mass_to_mole_fractions

_SPECIES_LIST = re.compile(r"\bspecies\s*\(([^)]*)\)")
_MOL_WEIGHT = r"\b{name}\s*\{{[^{{}}]*?\bspecie\s*\{{[^}}]*?\bmolWeight\s+([-+0-9.eE]+)\s*;"
_BANNER_VERSION = re.compile(rb"Version:\s*(v?\d[\w.+-]*)")
_LOG_BUILD = re.compile(r"^Build\s*:\s*(.+)$", flags=re.MULTILINE)


def time_directory(case, time) -> Path:
    """Folder of ``time`` (s) in a case, matched numerically (``0.9`` finds ``0.9``).

    Raises
    ------
    FileNotFoundError
        If no folder has that time; the message lists the times present and hints at
        ``reconstructPar`` when only ``processor*`` folders hold it.
    """
    case = Path(case)
    if not case.is_dir():
        raise FileNotFoundError(f"OpenFOAM case folder not found: {case}")
    times = {}
    for child in case.iterdir():
        try:
            times[float(child.name)] = child
        except ValueError:
            continue
    wanted = float(time)
    for t, path in times.items():
        if abs(t - wanted) <= 1e-9 * max(1.0, abs(wanted)):
            return path
    hint = ""
    if any(case.glob(f"processor*/{time}")):
        hint = f"; the case is decomposed: run 'reconstructPar -time {time}' in {case}"
    raise FileNotFoundError(
        f"time {time} not found in {case}; times present: {sorted(times)}{hint}"
    )


def case_species(case) -> list[str]:
    """Species of a case, from the ``species ( … )`` list in a ``constant/`` dictionary."""
    constant = Path(case) / "constant"
    for name in ("reactions", "thermophysicalProperties", "chemkin/reactions"):
        path = constant / name
        if path.is_file():
            match = _SPECIES_LIST.search(_strip_comments(path.read_text(errors="replace")))
            if match:
                return match.group(1).split()
    raise FileNotFoundError(
        f"no 'species ( ... )' list in {constant}/reactions or thermophysicalProperties; "
        "is this a reacting case?"
    )


def case_molar_masses(case, species: list[str]) -> dict[str, float]:
    """Molar mass in g/mol of each species: ``molWeight`` in ``constant/`` thermo files,
    else the :data:`~invflame.phantoms.composition.MOLAR_MASS` table."""
    texts = [
        _strip_comments(p.read_text(errors="replace"))
        for p in sorted((Path(case) / "constant").glob("*"))
        if p.is_file() and p.stat().st_size < 10_000_000
    ]
    masses = {}
    for s in species:
        pattern = re.compile(_MOL_WEIGHT.format(name=re.escape(s)))
        found = [m.group(1) for text in texts if (m := pattern.search(text))]
        if found:
            masses[s] = float(found[0])
        elif s in MOLAR_MASS:
            masses[s] = MOLAR_MASS[s]
        else:
            raise KeyError(
                f"no molWeight for species {s!r} in {case}/constant and none tabulated; "
                "add it to the case's thermo dictionary"
            )
    return masses


def case_up_axis(case) -> int:
    """Axis opposite to gravity, from ``constant/g`` (1, i.e. y, when there is no such file)."""
    path = Path(case) / "constant" / "g"
    if not path.is_file():
        return 1
    match = re.search(r"\bvalue\s*\(([^)]*)\)", _strip_comments(path.read_text()))
    if match is None:
        raise ValueError(f"{path}: no 'value (gx gy gz)' entry")
    g = np.array(match.group(1).split(), dtype=np.float64)
    return int(np.argmax(np.abs(g)))


def read_case(case, time) -> Field:
    """Temperature and mole fractions of CO2, H2O, CH4 at one time of an OpenFOAM case.

    Reads ``T`` and the mass fractions of every species of the case, converts them to mole
    fractions with the mean molar mass of the whole mixture (``1/W = Σ_i Y_i / W_i``, mass
    fractions clipped to [0, 1]), and maps the cells onto the regular grid they form.
    Species of :data:`~invflame.field.SPECIES` the case does not have are zero (listed in the
    metadata under ``absent_species``).

    Parameters
    ----------
    case : str or os.PathLike
        Case folder (reconstructed, not only ``processor*``).
    time : float or str
        Simulated time in s.

    Returns
    -------
    Field
        On the grid of the cells; metadata records the solver, OpenFOAM version, case, time,
        species and molar masses used.

    Raises
    ------
    FileNotFoundError
        Missing case, time, field or mesh.
    ValueError
        If the mesh is not a uniform box grid (see
        :func:`~invflame.openfoam.mesh.grid_from_centres`).
    """
    case = Path(case)
    tdir = time_directory(case, time)
    species = case_species(case)
    masses = case_molar_masses(case, species)
    centres = cell_centres(case, tdir.name)
    n_cells = len(centres)

    def cell_values(name: str) -> np.ndarray:
        path = tdir / name
        values = read_internal_field(path, "scalar")
        values = np.broadcast_to(np.asarray(values, dtype=np.float64), (n_cells,))
        if values.shape != (n_cells,):
            raise ValueError(f"{path} has {values.shape[0]} cells; the mesh has {n_cells}")
        return values

    missing = [s for s in species if not _exists(tdir / s)]
    if missing:
        raise FileNotFoundError(f"species {missing} are not written in {tdir}")
    mole = mass_to_mole_fractions({s: cell_values(s) for s in species}, masses)
    grid, flat = grid_from_centres(centres, case_up_axis(case), mesh_box(case))
    values = np.zeros((len(FIELD_NAMES), grid.n_voxels), dtype=np.float64)
    values[0, flat] = cell_values("T")
    for i, s in enumerate(SPECIES, start=1):
        if s in mole:
            values[i, flat] = mole[s]
    solver = _controldict_entry(case, "application")
    metadata = {
        "source": "OpenFOAM",
        "solver": solver,
        "version": _foam_version(case, solver, tdir / "T"),
        "case": case.resolve().name,
        "time": float(tdir.name),
        "species": species,
        "molar_masses_g_per_mol": masses,
        "absent_species": [s for s in SPECIES if s not in mole],
        "conversion": "X_i = (Y_i/W_i) / sum_j(Y_j/W_j) over all species of the case",
    }
    return Field(grid, values.reshape(len(FIELD_NAMES), *grid.shape), metadata)


def _exists(path: Path) -> bool:
    return path.exists() or path.with_name(path.name + ".gz").exists()


def _strip_comments(text: str) -> str:
    return re.sub(r"//[^\n]*|/\*.*?\*/", " ", text, flags=re.DOTALL)


def _controldict_entry(case: Path, key: str) -> str | None:
    path = case / "system" / "controlDict"
    if not path.is_file():
        return None
    match = re.search(rf"\b{key}\s+([^;\s]+)\s*;", _strip_comments(path.read_text()))
    return match.group(1) if match else None


def _foam_version(case: Path, solver: str | None, field_path: Path) -> str | None:
    """OpenFOAM build from the solver log (``Build : ...``), else the file banner."""
    log = case / f"log.{solver}"
    if solver and log.is_file():
        with open(log, errors="replace") as fh:
            match = _LOG_BUILD.search(fh.read(4096))
        if match:
            return match.group(1).strip()
    match = _BANNER_VERSION.search(open_foam_file(field_path).data[:2048])
    return match.group(1).decode() if match else None
