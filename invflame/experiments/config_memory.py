"""The memory a configuration's largest arrays need, estimated before any of them is made.

A number in a configuration can ask for more memory than a machine has: ``truth.grid = 100000``
asks for 10¹⁵ voxels, ``spectrum.step = 1e-7`` for 7.5·10⁸ line-by-line points. The run would
find out after minutes, or by exhausting the machine. :func:`estimates` sizes the arrays that
grow with the configuration, from the keys alone:

- the fields on the reconstruction grid: fields × voxels, float32;
- the voxel crossings of the sub-rays: pixels × sub-rays per pixel × (nx + ny + nz) voxels
  at most per ray, a voxel index (int64) and a path length (float64) each;
- the absorption table's temperature spline: 4 coefficients × (nodes − 1) temperature
  intervals × cross-section columns (species × self-fraction nodes) × spectral points (at
  least one per line-by-line point), float64;
- the instrument's lineshape matrix: output × line-by-line points, float32;
- the spectra of all pixels: pixels × output points, float32;
- for synthetic data made without the inverse crime, the same on the truth's native grid, with
  ``data.rays_per_pixel`` sub-rays and a step ``data.step_divisor`` times finer.

:func:`check_memory`, one of :data:`invflame.experiments.config_rules.RULES`, refuses each
estimate larger than the machine's physical memory (:func:`machine_memory`), naming the keys
and the estimate in GiB. The estimates are lower bounds: the solver and the derivatives hold
several arrays of these sizes at once.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from dataclasses import dataclass

from invflame.errors import ConfigError
from invflame.experiments.config_scene import grid_cells

GIB = 2.0**30
"""Bytes in a GiB."""


@dataclass(frozen=True)
class Estimate:
    """The size of one array a configuration asks for.

    Attributes
    ----------
    what : str
        The array, in words.
    keys : tuple of str
        The configuration keys its size grows with (dotted paths).
    shape : str
        How its size comes about (``"4 fields x 27000 voxels x 4 bytes"``).
    nbytes : float
        Its size in bytes.
    fix : str
        What makes it smaller.
    """

    what: str
    keys: tuple[str, ...]
    shape: str
    nbytes: float
    fix: str


def machine_memory() -> int | None:
    """The physical memory of this machine, bytes; None where the system does not say."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def _points(low: float, high: float, step: float) -> float:
    """Points from ``low`` to ``high`` every ``step`` (none for an empty range)."""
    return max(0.0, math.floor((high - low) / step + 1e-9) + 1.0)


def _table_columns(broadening: str) -> tuple[int, int]:
    """Temperature nodes and cross-section columns of a run's absorption table."""
    from invflame.spectroscopy.absorption_table import SPECIES
    from invflame.spectroscopy.table_inputs import (
        BROADENING,
        DEFAULT_TEMPERATURES,
        fraction_nodes,
    )

    nodes = fraction_nodes(SPECIES, BROADENING[broadening])
    return len(DEFAULT_TEMPERATURES), sum(len(n) for n in nodes)


def _rays(what: str, keys: tuple[str, ...], pixels: float, sub_rays: int,
          cells) -> Estimate:
    per_ray = sum(cells)
    return Estimate(f"the voxel crossings of {what}", keys,
                    f"{pixels:.4g} pixels x {sub_rays} sub-rays x {per_ray} voxels x 16 bytes",
                    16.0 * pixels * sub_rays * per_ray,
                    "use fewer pixels, sub-rays per pixel or voxels")


def _spectral(what: str, keys: tuple[str, ...], n_eta: float, n_out: float,
              broadening: str) -> list[Estimate]:
    n_t, columns = _table_columns(broadening)
    return [
        Estimate(f"the absorption table of {what}", keys,
                 f"4 x {n_t - 1} temperature intervals x {columns} columns x {n_eta:.4g} "
                 "points x 8 bytes", 32.0 * (n_t - 1) * columns * n_eta,
                 "narrow the window or take a coarser step"),
        Estimate(f"the instrument's lineshape matrix of {what}", (*keys, "instrument.sampling"),
                 f"{n_out:.4g} output x {n_eta:.4g} line-by-line points x 4 bytes",
                 4.0 * n_out * n_eta,
                 "narrow the window, or take a coarser step or output sampling"),
    ]


def estimates(cfg: dict, loaded: dict) -> list[Estimate]:
    """The sizes of a configuration's largest arrays (see the module docstring).

    Parameters
    ----------
    cfg : dict
        A configuration whose keys passed the schema.
    loaded : dict
        What the file checks read (:mod:`invflame.experiments.config_files`): ``"rig"``, the
        configured cameras (None: the paper's rig), and where there are, ``"truth"`` (a field
        file's :class:`~invflame.field.Field`) and ``"measured"`` (the measurement file,
        whose channels widen the line-by-line window as the run does:
        :func:`invflame.experiments.inputs.widened_window`).

    Returns
    -------
    list of Estimate
    """
    from invflame.experiments.inputs import widened_window
    from invflame.geometry import VoxelGrid

    measured, spec = loaded.get("measured"), loaded.get("rig")
    try:  # the window the run models for a measurement file's channels
        cfg = widened_window(cfg, measured)[0]
    except ConfigError:  # a window past 0 cm-1: the run refuses it with its own message
        pass
    spectrum, instrument, data, rig = cfg["spectrum"], cfg["instrument"], cfg["data"], cfg["rig"]
    cells = grid_cells(cfg)
    grid_key = "grid.cells" if cfg["grid"]["cells"] else "truth.grid"
    cameras = spec.rig if spec else measured.rig if measured else None
    pixels = float(cameras.n_rays if cameras else 4 * rig["pixels"] ** 2)
    camera_keys = (("rig.file" if rig["file"] else "rig.cameras",) if spec else
                   ("data.source",) if measured else ("rig.pixels",))
    n_eta = _points(spectrum["min"], spectrum["max"], spectrum["step"])
    window = ("spectrum.min", "spectrum.max", "spectrum.step")
    if measured:
        n_out = float(measured.wavenumber.size)
    else:
        n_out = _points(spectrum["min"] + instrument["resolution"],
                        spectrum["max"] - instrument["resolution"], instrument["sampling"])
    fields = 5 if cfg["soot"]["reconstruct"] else 4
    out = [
        Estimate("the fields on the reconstruction grid", (grid_key,),
                 f"{fields} fields x {math.prod(cells)} voxels x 4 bytes",
                 4.0 * fields * math.prod(cells), "use fewer voxels"),
        _rays("the reconstruction's sub-rays", (*camera_keys, "rig.rays_per_pixel", grid_key),
              pixels, rig["rays_per_pixel"], cells),
        *_spectral("the reconstruction", window, n_eta, n_out, spectrum["broadening"]),
        Estimate("the spectra of all pixels", (*camera_keys, "instrument.sampling"),
                 f"{pixels:.4g} pixels x {n_out:.4g} output points x 4 bytes",
                 4.0 * pixels * n_out, "use fewer pixels or a coarser output sampling"),
    ]
    if measured or data["inverse_crime"] or cfg["truth"]["source"] == "none":
        return out
    truth = loaded.get("truth")
    native = truth.grid.shape if truth is not None else VoxelGrid.poolfire().shape  # phantoms
    divisor = data["step_divisor"]
    return out + [
        _rays("the synthetic measurement's sub-rays (on the truth's grid)",
              (*camera_keys, "data.rays_per_pixel"), pixels, data["rays_per_pixel"], native),
        *_spectral("the synthetic measurement", (*window, "data.step_divisor"),
                   _points(0.0, (n_eta - 1.0) * divisor, 1.0), n_out, spectrum["broadening"]),
    ]


def _value(cfg: dict, path: str) -> str:
    """``'path' = value``; the number of [[tables]] for a list of them."""
    section, _, name = path.rpartition(".")
    value = (cfg[section] if section else cfg)[name]
    return f"'{path}' ({len(value)} tables)" if isinstance(value, list) and value and isinstance(
        value[0], dict) else f"'{path}' = {value!r}"


def check_memory(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """Refuse each array of :func:`estimates` larger than the machine's memory.

    Yields
    ------
    str
        Per such array: the keys with their values, the array, its size in GiB and the
        machine's memory; an array whose keys include those of one refused before is left
        out (the synthetic measurement's table where the reconstruction's is refused).
    """
    memory = machine_memory()
    if memory is None:
        return
    refused: list[set[str]] = []
    for estimate in estimates(full, loaded):
        if estimate.nbytes > memory and not any(keys <= set(estimate.keys) for keys in refused):
            refused.append(set(estimate.keys))  # a larger array of the same keys: said once
            keys = ", ".join(_value(full, key) for key in estimate.keys)
            yield (f"{keys}: {estimate.what} would take about {estimate.nbytes / GIB:.3g} GiB "
                   f"({estimate.shape}), more than this machine's {memory / GIB:.3g} GiB of "
                   f"memory: {estimate.fix}")
