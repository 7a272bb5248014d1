"""What a validated configuration describes: its wavenumber grids, reconstruction grid and cameras.

:mod:`invflame.experiments.config` re-exports these names; the run
(:mod:`invflame.experiments.inputs`, :mod:`invflame.experiments.runner`) and the checks between
keys (:mod:`invflame.experiments.config_rules`) compute them here, in one place.
"""

from __future__ import annotations

import numpy as np

from invflame.errors import ConfigError

LINE_DATA_RANGE = (600.0, 800.0)
"""cm⁻¹ covered by the built-in line lists (packaged H2O, generated CO2)."""


def line_by_line_grid(spectrum: dict, step: float | None = None) -> np.ndarray:
    """The line-by-line wavenumbers of a ``[spectrum]`` section, cm⁻¹.

    Parameters
    ----------
    spectrum : dict
        ``min``, ``max`` and ``step`` in cm⁻¹.
    step : float, optional
        Step in cm⁻¹ instead of ``spectrum["step"]`` (the finer grid of a measurement).
    """
    step = spectrum["step"] if step is None else step
    n = int(round((spectrum["max"] - spectrum["min"]) / step)) + 1
    return spectrum["min"] + step * np.arange(n)


def output_grid(cfg: dict, wavenumber) -> np.ndarray:
    """The instrument's output wavenumbers (cm⁻¹) over a line-by-line grid: from one
    ``instrument.resolution`` inside the window, every ``instrument.sampling``.

    Raises
    ------
    ConfigError
        If the window is narrower than two resolutions (no output point).
    """
    from operators.ils import default_output_grid

    instrument = cfg["instrument"]
    try:
        out = default_output_grid(np.asarray(wavenumber), instrument["resolution"])
    except ValueError as err:
        raise ConfigError(f"'spectrum.min'..'spectrum.max' and 'instrument.resolution': {err}"
                          ) from err
    return np.arange(out[0], out[-1] + 1e-9, instrument["sampling"])


def grid_cells(cfg: dict) -> tuple[int, int, int]:
    """Voxels of the reconstruction grid along x, y, z: ``grid.cells``, or ``truth.grid`` on
    every axis."""
    return tuple(cfg["grid"]["cells"]) or (cfg["truth"]["grid"],) * 3


def reconstruction_grid(cfg: dict):
    """The reconstruction grid of a configuration: the box ``grid.lower``..``grid.upper``
    (m, y up) with :func:`grid_cells` voxels.

    Parameters
    ----------
    cfg : dict
        Validated configuration.

    Returns
    -------
    invflame.geometry.VoxelGrid
    """
    from invflame.geometry import VoxelGrid

    grid = cfg["grid"]
    return VoxelGrid(grid["lower"], grid["upper"], grid_cells(cfg), up_axis=1)


def rig_spec(cfg: dict):
    """The cameras of ``rig.file`` or ``rig.cameras`` as a
    :class:`invflame.geometry.rig_file.RigSpec`; None for the paper's rig
    (``rig.pixels``, ``rig.distance``, ``rig.focal_length``)."""
    from invflame.geometry.rig_file import parse_rig, read_rig

    rig = cfg["rig"]
    if rig["file"]:
        return read_rig(rig["file"])
    return parse_rig(rig["cameras"], "rig.cameras") if rig["cameras"] else None
