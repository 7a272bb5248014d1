"""What a run reads: the absorption table of its spectral window, the measurement file of
``data.source``, the spectral window of each camera and the ground truth of
``truth.source``."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from invflame.errors import ConfigError, InputDataError
from invflame.experiments.config_scene import line_by_line_grid, reconstruction_grid, rig_spec
from invflame.field import Field
from invflame.geometry import CameraRig, VoxelGrid, paper_rig
from invflame.geometry.rig_file import RigSpec
from invflame.measurement import check_windows, stated
from invflame.measurement_file import MeasurementFile, read_measurement
from invflame.phantoms import make_phantom
from invflame.phantoms.plume import plume_soot
from invflame.spectroscopy.absorption_table import AbsorptionTable, default_linelists
from invflame.spectroscopy.table_inputs import BROADENING, DEFAULT_TEMPERATURES

TEMPERATURE_RANGE = (float(DEFAULT_TEMPERATURES[0]), float(DEFAULT_TEMPERATURES[-1]))
"""Lowest and highest temperature (K) of a run's absorption table, its temperature nodes'."""


def absorption_table(cfg: dict, step: float | None = None,
                     progress: bool = True) -> AbsorptionTable:
    """The absorption table for the configuration's spectral window, line lists, self
    broadening and spectral points (cached on disk).

    Parameters
    ----------
    cfg : dict
        Validated configuration.
    step : float, optional
        Line-by-line step in cm⁻¹ (default ``spectrum.step``).
    progress : bool, optional
        Show a progress bar while a table is built.
    """
    spectrum = cfg["spectrum"]
    wavenumber = line_by_line_grid(spectrum, step)
    files = {"CO2": spectrum["co2_lines"], "H2O": spectrum["h2o_lines"]}
    return AbsorptionTable.cached(default_linelists(wavenumber, files), wavenumber=wavenumber,
                                  pressure=spectrum["pressure"],
                                  self_fraction=BROADENING[spectrum["broadening"]],
                                  subdivision=spectrum["points_per_bin"], progress=progress)


def read_data(cfg: dict) -> MeasurementFile | None:
    """The measurement file of ``data.source`` (None when the data are simulated), checked
    against the configuration's rig when it names one (``rig.file`` or ``rig.cameras``); a
    camera's window there narrows the wavenumbers it measures
    (:func:`~invflame.measurement_file.read_measurement`)."""
    source = cfg["data"]["source"]
    if not source:
        return None
    spec = rig_spec(cfg)
    if spec is None:
        return read_measurement(source)
    where = f"the rig file {cfg['rig']['file']}" if cfg["rig"]["file"] else "rig.cameras"
    return read_measurement(source, rig=spec.rig, rig_source=where, windows=spec.windows)


def camera_windows(spec: RigSpec | None, measured: MeasurementFile | None, out_wavenumber):
    """The spectral window of each camera of a run (:mod:`invflame.measurement`).

    Parameters
    ----------
    spec : RigSpec or None
        The configuration's rig (``rig.file`` or ``rig.cameras``), None for the paper's.
    measured : MeasurementFile or None
        The run's measured data (:func:`read_data`): their windows, those of the file and of
        the rig together, already checked.
    out_wavenumber : array_like
        The channels the run models, cm⁻¹.

    Returns
    -------
    tuple of ((float, float) or None), or None
        One window ``(min, max)`` in cm⁻¹ per camera (None: every channel); None when no
        camera has one.

    Raises
    ------
    InputDataError
        For a camera window of the rig that holds none of the simulated channels (naming the
        rig, the camera and the key).
    """
    if measured is not None:
        return measured.windows
    if spec is None or not stated(spec.windows):
        return None
    check_windows(spec.windows, out_wavenumber, spec.source, "simulated")
    return spec.windows


def widened_window(cfg: dict, measured: MeasurementFile | None) -> tuple[dict, str]:
    """The configuration with its line-by-line window widened for a measurement file.

    A measured channel is the lineshape-weighted mean of the spectrum around it
    (:mod:`operators.ils`); the model knows the spectrum inside ``spectrum.min``..
    ``spectrum.max`` only and renormalizes the lineshape cut there. So that every channel
    has ``instrument.margin`` resolutions of its lineshape modelled on each side, the window
    is widened on its own step (``spectrum.step``), never narrowed.

    Parameters
    ----------
    cfg : dict
        Validated configuration.
    measured : MeasurementFile or None
        The run's measured data (:func:`read_data`); None (simulated data, whose output grid
        follows the window) changes nothing.

    Returns
    -------
    cfg : dict
        ``cfg`` itself when nothing changed, else a copy with the new ``[spectrum]``.
    note : str
        One line on the widening for the run's log; empty when nothing changed.

    Raises
    ------
    ConfigError
        If the widened window would reach down to 0 cm⁻¹ or below.
    """
    if measured is None:
        return cfg, ""
    spectrum = cfg["spectrum"]
    reach = cfg["instrument"]["margin"] * measured.resolution
    step, low, high = spectrum["step"], spectrum["min"], spectrum["max"]
    below = max(0.0, low - (float(measured.wavenumber.min()) - reach))
    above = max(0.0, float(measured.wavenumber.max()) + reach - high)
    if below == above == 0.0:
        return cfg, ""
    widened = {"min": low - step * np.ceil(below / step - 1e-9),
               "max": high + step * np.ceil(above / step - 1e-9)}
    if widened["min"] <= 0.0:
        raise ConfigError(f"the measured channels from {measured.wavenumber.min():g} cm-1 would "
                          f"need the window to reach {widened['min']:g} cm-1: lower "
                          "'instrument.margin'")
    note = (f"the line-by-line window {low:g}-{high:g} cm-1 widened to {widened['min']:g}-"
            f"{widened['max']:g} cm-1: the measured channels "
            f"{measured.wavenumber.min():g}-{measured.wavenumber.max():g} cm-1 at "
            f"{measured.resolution:g} cm-1 resolution need their lineshape "
            f"{cfg['instrument']['margin']:g} resolutions beyond them ('instrument.margin')")
    return {**cfg, "spectrum": {**spectrum, **widened}}, note


def scene_rig(cfg: dict, measured: MeasurementFile | None = None) -> CameraRig:
    """The cameras of a run: ``rig.file`` or ``rig.cameras``, else the cameras of the
    measurement file ``measured``, else the paper's rig (``rig.pixels``, ``rig.distance`` in m,
    ``rig.focal_length`` in m) around the reconstruction grid.

    Parameters
    ----------
    cfg : dict
        Validated configuration.
    measured : MeasurementFile, optional
        The run's measured data (:func:`read_data`).
    """
    spec = rig_spec(cfg)
    if spec is not None:
        return spec.rig
    if measured is not None:
        return measured.rig
    rig = cfg["rig"]
    return paper_rig(reconstruction_grid(cfg), distance=rig["distance"],
                     n_pixels=rig["pixels"], focal_length=rig["focal_length"])


def load_truth(cfg: dict, grid: VoxelGrid | None = None) -> Field | None:
    """The ground truth named by ``truth.source``: a phantom name or a field ``.npz`` file;
    None for ``"none"`` (measured data without a truth). With ``truth.soot`` > 0 a soot-free
    truth gains the soot layer of :func:`invflame.phantoms.plume.plume_soot` of that peak
    volume fraction, on its native grid, as its fifth field.

    Parameters
    ----------
    cfg : dict
        Validated configuration.
    grid : VoxelGrid, optional
        Resample onto this grid; default: the truth's native grid (the pool fire's 60³ cells,
        the synthetic plume's default 60³ grid, a file's own grid).

    Raises
    ------
    FileNotFoundError
        If ``truth.source`` is neither a phantom's name nor an existing file.
    InputDataError
        If the file is not a field file (:meth:`invflame.field.Field.load`: 4 or 5 fields on a
        3-D grid, finite, mole fractions in [0, 1]), stores complex numbers, or holds
        temperatures outside the absorption table's (:data:`TEMPERATURE_RANGE`, K); the
        message names the key and the file.
    """
    source = cfg["truth"]["source"]
    if source == "none":
        return None
    if source in ("poolfire", "synthetic"):
        field = make_phantom(source)
    else:
        field = _field_file(source)
    peak = cfg["truth"]["soot"]
    if peak > 0 and field.soot is None:
        field = field.with_soot(plume_soot(field, peak))
    return field if grid is None else field.resample(grid)


def _field_file(source: str) -> Field:
    """The field file of ``truth.source``, checked as :func:`load_truth` says."""
    path = Path(source)
    if not path.is_file():
        raise FileNotFoundError(
            f"'truth.source' = {source!r} is neither 'poolfire', 'synthetic', 'none' nor an "
            "existing field file (.npz, see invflame.field)")
    where = f"'truth.source' = {source!r}"
    try:
        with warnings.catch_warnings():  # a cast from complex would drop the imaginary parts
            warnings.simplefilter("error", np.exceptions.ComplexWarning)
            field = Field.load(path)
    except np.exceptions.ComplexWarning:
        raise InputDataError(f"{where} stores its fields as complex numbers: write them as real "
                             "ones (T in K, mole fractions)") from None
    except ValueError as err:  # a damaged file, another layout, values out of range
        raise InputDataError(f"{where}: {err}") from err
    low, high = TEMPERATURE_RANGE
    t_min, t_max = float(field.T.min()), float(field.T.max())
    if t_min < low or t_max > high:
        raise InputDataError(f"{where} holds temperatures {t_min:g}-{t_max:g} K, outside the "
                             f"absorption table's {low:g}-{high:g} K: give a truth within it")
    return field
