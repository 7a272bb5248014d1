"""Field sets of a run as VTK image data (ParaView) and as a CF-style NetCDF file (xarray).

A run folder (:mod:`invflame.experiments.runner`) holds up to three field sets as ``.npz``
(:class:`invflame.field.Field`): the ground truth (``truth.npz``, when the run has one), the
start (``initial.npz``) and the reconstruction (``reconstruction.npz``). :func:`export_run`
writes beside them

``truth.vti``, ``start.vti``, ``reconstruction.vti``
    VTK XML image data, one file per field set: origin at the grid's lower corner and spacing
    in m, one cell per voxel, cell arrays ``T [K]``, ``X_CO2 [1]``, ``X_H2O [1]``,
    ``X_CH4 [1]`` (float32). Written with ``pyevtk`` (raw appended binary).
``fields.nc``
    NetCDF-4 through ``xarray`` (``netCDF4`` engine): dimensions ``x``, ``y``, ``z`` with the
    voxel centres in m as coordinates (CF ``axis`` X, Y, Z, and cell bounds), one variable
    per field set and quantity named ``<set>_<quantity>`` (``truth_T``, ``start_X_CO2``,
    ``reconstruction_X_H2O``, ...), each with ``units``, ``long_name`` and the CF
    ``standard_name``, stored in CF's recommended order ``(z, y, x)`` (x varies fastest, as
    the NetCDF readers of ParaView and VTK expect); global attributes say where the fields
    come from (configuration, protocol, date, ``history``, invflame version). No variable has
    a ``_FillValue``: no value is missing.

Every file is written beside its destination and then renamed over it, so a half-written
file never replaces a good one.
"""

from __future__ import annotations

import datetime
import json
import os
import tempfile
import tomllib
from pathlib import Path

import numpy as np
import xarray as xr
from pyevtk.hl import imageToVTK

from invflame import __version__
from invflame.atomic_files import read_json
from invflame.field import Field

FIELD_SETS = {"truth": "truth.npz", "start": "initial.npz", "reconstruction": "reconstruction.npz"}
"""Field set name → its ``.npz`` in a run folder, in the order they are exported."""

FORMATS = ("vti", "netcdf")
"""Formats :func:`export_run` writes."""

NETCDF_FILE = "fields.nc"
"""Name of the NetCDF file in a run folder."""

QUANTITIES = {
    # field name: (exported name, units, long name, CF standard name)
    "T": ("T", "K", "temperature", "air_temperature"),
    "CO2": ("X_CO2", "1", "mole fraction of CO2", "mole_fraction_of_carbon_dioxide_in_air"),
    "H2O": ("X_H2O", "1", "mole fraction of H2O", "mole_fraction_of_water_vapor_in_air"),
    "CH4": ("X_CH4", "1", "mole fraction of CH4", "mole_fraction_of_methane_in_air"),
    "soot": ("f_v", "1", "soot volume fraction", None),
}
"""Each field of :data:`invflame.field.SOOTY_FIELD_NAMES` as exported: name, units, long name
and CF standard name (CF calls any gas mixture "air"; it names no soot volume fraction, so
``f_v`` has none). A field set exports the fields it holds (:attr:`invflame.field.Field.names`)."""

_AXES = ("x", "y", "z")


def array_name(field_name: str) -> str:
    """Name of a field's array in a ``.vti`` file, with its unit: ``"T [K]"``, ``"X_CO2 [1]"``.

    Parameters
    ----------
    field_name : str
        One of :data:`invflame.field.SOOTY_FIELD_NAMES`.
    """
    name, units, _, _ = QUANTITIES[field_name]
    return f"{name} [{units}]"


def _replace_from_temporary(path: Path, write) -> Path:
    """Let ``write(temporary_path)`` create a file in ``path``'s folder and return the path it
    wrote; rename that file over ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=path.parent, prefix=f".{path.name}.") as folder:
        os.replace(write(Path(folder) / path.name), path)
    return path


def write_vti(field: Field, path) -> Path:
    """Write a field set as VTK XML image data (``.vti``), one cell per voxel.

    Parameters
    ----------
    field : Field
        Temperature [K] and mole fractions [1] on a voxel grid (m).
    path : str or os.PathLike
        Destination ending in ``.vti``; parent folders are created.

    Returns
    -------
    pathlib.Path
        The path written. The image's origin is the grid's lower corner and its spacing the
        voxel size, both in m; its cell arrays are named by :func:`array_name`.
    """
    path = Path(path)
    if path.suffix != ".vti":
        raise ValueError(f"VTK image data files end in .vti; got {path}")
    grid = field.grid
    cells = {array_name(name): np.asfortranarray(field[name]) for name in field.names}

    def write(temporary: Path) -> str:
        # plain floats: pyevtk prints numpy scalars with their repr, which VTK cannot read
        return imageToVTK(str(temporary.with_suffix("")),
                          origin=tuple(float(v) for v in grid.lower),
                          spacing=tuple(float(v) for v in grid.spacing), cellData=cells)

    return _replace_from_temporary(path, write)


def voxel_variable(values: np.ndarray, attrs: dict) -> xr.Variable:
    """A voxel array ``[ix, iy, iz]`` as a float32 variable over ``(z, y, x)``.

    The storage order stays ``(z, y, x)`` whichever axis is up: ParaView's NetCDF CF reader
    lays out its image in storage order, so x, y and z land where they belong. CF recommends
    its vertical axis first; with the y axis up that order is (CF) Y, Z, X, which a CF checker
    notes as a warning.

    Parameters
    ----------
    values : ndarray, shape (nx, ny, nz)
        One value per voxel.
    attrs : dict
        The variable's attributes.
    """
    return xr.Variable(_AXES[::-1], np.asarray(values).T.astype(np.float32), attrs)


def _coordinates(field: Field) -> dict[str, xr.Variable]:
    """Voxel centres along x, y, z (m), each with its CF ``axis`` and its cell bounds.

    CF's axis Z is the vertical (the grid's up axis, ``positive = "up"``); its X and Y are the
    first and second horizontal axes, named as projection coordinates (a laboratory frame has
    no latitude or longitude). Each centre's ``bounds`` is in its encoding, where xarray
    writes it as the attribute and keeps the bounds variable out of a global ``coordinates``
    attribute.
    """
    grid, centres = field.grid, field.grid.axes()
    first, second = (_AXES[a] for a in range(3) if a != grid.up_axis)
    vertical = _AXES[grid.up_axis]
    roles = {first: ("X", {"standard_name": "projection_x_coordinate"}),
             second: ("Y", {"standard_name": "projection_y_coordinate"}),
             vertical: ("Z", {"positive": "up"})}
    coords = {}
    for a, axis in enumerate(_AXES):
        edges = np.linspace(grid.lower[a], grid.upper[a], grid.shape[a] + 1)
        cf_axis, extra = roles[axis]
        attrs = {"units": "m", "long_name": f"{axis} of the voxel centre", "axis": cf_axis,
                 **extra}
        coords[axis] = xr.Variable(axis, centres[a], attrs, {"bounds": f"{axis}_bounds"})
        coords[f"{axis}_bounds"] = xr.Variable((axis, "bounds"),
                                               np.stack([edges[:-1], edges[1:]], axis=1))
    return coords


def fields_dataset(fields: dict[str, Field], attributes: dict | None = None) -> xr.Dataset:
    """Field sets on one grid as a CF-style ``xarray.Dataset``.

    Parameters
    ----------
    fields : dict of str to Field
        Field set name (e.g. "truth", "start", "reconstruction") → its fields; every field on
        the same grid.
    attributes : dict, optional
        Global attributes (str or numbers), added to ``Conventions``, ``source``,
        ``invflame_version``, ``up_axis``, ``field_sets``, ``date_created`` (ISO 8601, UTC)
        and ``history`` (when and by what the dataset was made).

    Returns
    -------
    xarray.Dataset
        Dimensions ``x``, ``y``, ``z`` (voxel centres in m, with their CF ``axis``: "Z" the
        up axis, "X" and "Y" the others, see :func:`_coordinates`; cell bounds ``x_bounds``,
        ...), a variable ``<set>_<quantity>`` per field set and quantity (``truth_T`` [K],
        ``start_X_CO2`` [1], ...) over ``(z, y, x)`` (:func:`voxel_variable`) with ``units``,
        ``long_name``, ``standard_name`` and ``field_set`` (``variable.transpose("x", "y",
        "z")`` is the field's ``[ix, iy, iz]`` array).
    """
    if not fields:
        raise ValueError("fields_dataset needs at least one field set; got none")
    (first_name, first), *others = fields.items()
    for name, field in others:
        if field.grid != first.grid:
            raise ValueError(
                f"field set {name!r} lies on grid {field.grid.shape} over {field.grid.lower} .. "
                f"{field.grid.upper} m, {first_name!r} on {first.grid.shape} over "
                f"{first.grid.lower} .. {first.grid.upper} m; resample them onto one grid "
                "(Field.resample) first")
    variables = {}
    for set_name, field in fields.items():
        for field_name in field.names:
            name, units, long_name, standard_name = QUANTITIES[field_name]
            attrs = {"units": units, "long_name": f"{long_name} ({set_name})",
                     "standard_name": standard_name, "field_set": set_name}
            variables[f"{set_name}_{name}"] = voxel_variable(
                field[field_name], {k: v for k, v in attrs.items() if v is not None})
    now = datetime.datetime.now(datetime.UTC).replace(microsecond=0).isoformat()
    attrs = {"Conventions": "CF-1.10",
             "source": f"invflame {__version__}",
             "invflame_version": __version__,
             "up_axis": _AXES[first.grid.up_axis],
             "field_sets": " ".join(fields),
             "date_created": now,
             "history": f"{now}: written by invflame {__version__} (invflame.export)",
             **(attributes or {})}
    return xr.Dataset(variables, coords=_coordinates(first), attrs=attrs)


def write_netcdf(fields: dict[str, Field], path, attributes: dict | None = None) -> Path:
    """Write field sets to a NetCDF-4 file (see :func:`fields_dataset` for its layout).

    Parameters
    ----------
    fields : dict of str to Field
        Field set name → its fields, all on one grid.
    path : str or os.PathLike
        Destination (``.nc``); parent folders are created.
    attributes : dict, optional
        Further global attributes (provenance).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    return write_dataset(fields_dataset(fields, attributes), path)


def write_dataset(dataset: xr.Dataset, path) -> Path:
    """Write a dataset of voxel variables (as from :func:`fields_dataset`) to a NetCDF-4 file,
    atomically: variables compressed, none with a ``_FillValue``.

    Parameters
    ----------
    dataset : xarray.Dataset
        Variables over ``(z, y, x)`` and the coordinates of :func:`fields_dataset`.
    path : str or os.PathLike
        Destination (``.nc``); parent folders are created.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    def write(temporary: Path) -> Path:
        # compressed fields; no value is missing anywhere, coordinates and bounds included
        encoding = {name: {"zlib": True, "complevel": 4, "_FillValue": None}
                    for name in dataset.data_vars}
        encoding.update({name: {**dataset[name].encoding, "_FillValue": None}
                         for name in dataset.coords})
        dataset.to_netcdf(temporary, engine="netcdf4", format="NETCDF4", encoding=encoding)
        return temporary

    return _replace_from_temporary(Path(path), write)


def read_run_fields(folder) -> dict[str, Field]:
    """The field sets of a run folder, in the order of :data:`FIELD_SETS`.

    Parameters
    ----------
    folder : str or os.PathLike
        A folder written by :func:`invflame.experiments.runner.run_experiment`.

    Returns
    -------
    dict of str to Field
        ``"truth"`` (when the run has one), ``"start"`` (when present) and
        ``"reconstruction"``.

    Raises
    ------
    FileNotFoundError
        If the folder holds no ``reconstruction.npz`` (no finished run).
    """
    folder = Path(folder)
    if not (folder / FIELD_SETS["reconstruction"]).is_file():
        raise FileNotFoundError(
            f"{folder} holds no {FIELD_SETS['reconstruction']}: it is not the folder of a "
            "finished run (invflame run / study / reproduce write one per method); give a "
            "run folder")
    return {name: Field.load(folder / file) for name, file in FIELD_SETS.items()
            if (folder / file).is_file()}


def run_attributes(folder) -> dict[str, str]:
    """Provenance of a run folder as NetCDF global attributes.

    ``title``; ``invflame_config`` (the run's ``config.toml``) and ``config_summary`` (its
    truth, representation, regularizer, solver, start, noise and seed in one line) when the
    folder has a configuration; ``protocol_start``, ``protocol_data``, ``protocol_noise`` and
    ``protocol_lambda`` (what made the result, in words) and ``mse`` (normalized MSE per
    field, JSON) when it has a ``summary.json``.

    Parameters
    ----------
    folder : str or os.PathLike
        A run folder.
    """
    folder = Path(folder)
    attrs = {"title": f"invflame fields of the run {folder.resolve().name}"}
    config_file, summary_file = folder / "config.toml", folder / "summary.json"
    if config_file.is_file():
        text = config_file.read_text()
        cfg = tomllib.loads(text)
        attrs["invflame_config"] = text
        attrs["config_summary"] = config_summary(cfg)
    if summary_file.is_file():
        summary = read_json(summary_file)
        attrs.update({f"protocol_{k}": str(v) for k, v in summary.get("protocol", {}).items()})
        if "mse" in summary:
            attrs["mse"] = json.dumps(summary["mse"])
    return attrs


def config_summary(cfg: dict) -> str:
    """A run's configuration in one line: truth, representation, regularizer and λ, solver,
    start, noise, seed (keys a configuration lacks are left out).

    Parameters
    ----------
    cfg : dict
        A run configuration (:mod:`invflame.experiments.config`), as read from its TOML.
    """
    def get(section, key):
        return cfg.get(section, {}).get(key)

    parts = [("truth", get("truth", "source")), ("grid", get("truth", "grid")),
             ("representation", get("representation", "kind")),
             ("regularizer", get("regularizer", "kind")),
             ("lambda", get("regularizer", "lambda")), ("solver", get("solver", "name")),
             ("iterations", get("solver", "iterations")), ("start", get("init", "kind")),
             ("noise", get("noise", "kind")), ("seed", cfg.get("seed"))]
    return "; ".join(f"{key} {value}" for key, value in parts if value is not None)


def export_run(folder, formats=FORMATS) -> list[Path]:
    """Write a run folder's field sets as ``<set>.vti`` and/or ``fields.nc`` into the folder.

    Parameters
    ----------
    folder : str or os.PathLike
        A run folder (holding at least ``reconstruction.npz``).
    formats : sequence of {"vti", "netcdf"}, optional
        What to write; default both.

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    ValueError
        If a format is unknown.
    FileNotFoundError
        If the folder holds no finished run.
    """
    unknown = sorted(set(formats) - set(FORMATS))
    if unknown:
        raise ValueError(f"unknown export format(s) {unknown}; choose from {list(FORMATS)}")
    folder = Path(folder)
    fields = read_run_fields(folder)
    written = []
    if "vti" in formats:
        written += [write_vti(field, folder / f"{name}.vti") for name, field in fields.items()]
    if "netcdf" in formats:
        written.append(write_netcdf(fields, folder / NETCDF_FILE, run_attributes(folder)))
    return written
