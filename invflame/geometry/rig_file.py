r"""Camera rigs as TOML: read, write, packaged presets, and checks against a grid.

A rig file lists its cameras as an array of tables; each camera states its pose and
intrinsics (lengths in m, pixel coordinates in pixels)::

    [[cameras]]
    position = [1.5, 0.5, 0.0]        # pinhole, m
    look_at = [0.0, 0.5, 0.0]         # a point on the optical axis, m ...
    up = [0.0, 1.0, 0.0]              # ... and the image's up direction
    focal_length = 0.59               # m
    sensor_size = [0.6018, 0.6018]    # (width, height) in m, or pixel_pitch = [pu, pv] in m
    pixels = [32, 32]                 # (columns nu, rows nv)
    principal_point = [16.0, 16.0]    # optional, (u, v) in pixels from the top-left corner

Orientation is given by exactly one of ``look_at`` with ``up``; ``rotation``, the 3 × 3
world-to-camera rotation matrix of the OpenCV and COLMAP convention (its rows are the camera's
right, down and forward axes in world coordinates, :math:`x_\mathrm{cam} = R\,(X - C)`); or
``quaternion`` = ``[w, x, y, z]``, the unit quaternion of that same rotation (COLMAP's
``qvec``). A camera may also state its spectrometer: ``resolution`` (cm⁻¹, 1/MOPD),
``apodization`` (``"triangular"``) and ``window`` (``[min, max]`` in cm⁻¹, ``0 < min < max``).
The window may differ per camera: a camera measures only the instrument's channels inside its
own (:mod:`invflame.measurement`), one without a window all of them. invflame models one
instrument lineshape for all cameras, so the cameras that state a resolution or an
apodization must agree with each other.

The same records form the inline ``[[rig.cameras]]`` of a run configuration. A file is written
with the camera's look-at point and up vector (:func:`write_rig`, from
:mod:`invflame.geometry.rig_writer`), every number as the shortest decimal that reads back to
the same float, so reading it gives the same rays bit for bit.
:data:`PRESETS` are rig files shipped with invflame: ``"paper"`` is the study's four cameras at
±1.5 m around the pool-fire box (:func:`invflame.geometry.paper_rig` on
:meth:`~invflame.geometry.VoxelGrid.poolfire`, 32 × 32 pixels).
"""

from __future__ import annotations

import difflib
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from invflame.errors import GeometryError, InputDataError
from invflame.geometry.camera import PinholeCamera
from invflame.geometry.grid import VoxelGrid
from invflame.geometry.rig import CameraRig
from invflame.geometry.rig_writer import rig_records, rig_toml, write_rig
from invflame.geometry.traversal import traverse

__all__ = ["APODIZATIONS", "CAMERA_KEYS", "INSTRUMENT_KEYS", "PRESETS", "RigSpec",
           "camera_from_record", "check_instrument", "check_rig_sees_grid", "parse_rig",
           "preset_path", "read_rig", "rig_records", "rig_toml", "write_rig"]

PRESETS = {"paper": "rig_paper.toml"}
"""Packaged rigs (in ``invflame/data/``): name → file."""

APODIZATIONS = ("triangular",)
"""Apodizations of the instrument lineshape invflame models (:mod:`operators.ils`)."""

CAMERA_KEYS = ("position", "look_at", "up", "rotation", "quaternion", "focal_length",
               "sensor_size", "pixel_pitch", "pixels", "principal_point", "resolution",
               "window", "apodization")
"""Keys a camera record may hold."""

INSTRUMENT_KEYS = ("resolution", "window", "apodization")
"""A camera record's spectrometer keys."""

_ROTATION_TOLERANCE = 1e-6
"""Largest deviation of ``R Rᵀ`` from the identity (and of ``det R`` from 1) accepted."""

_WINDOW_TOLERANCE = 1e-6
"""cm⁻¹ by which a camera's window may reach beyond the modelled window (round-off)."""


@dataclass(frozen=True)
class RigSpec:
    """A rig read from records: its cameras and the spectrometer settings they state.

    Attributes
    ----------
    rig : CameraRig
        The cameras.
    instrument : dict
        The lineshape settings common to the cameras that state them: ``resolution``
        (cm⁻¹), ``apodization``; empty when no camera states either.
    windows : tuple of ((float, float) or None), or None
        Each camera's own spectral window ``(min, max)`` in cm⁻¹ (None for a camera without
        one); None when no camera states one.
    source : str
        What the records came from (a file name, ``"rig.cameras"``), for messages.
    """

    rig: CameraRig
    instrument: dict = field(default_factory=dict)
    windows: tuple | None = None
    source: str = "the rig"


def _vector(record: dict, key: str, where: str, length: int) -> np.ndarray:
    value = record[key]
    if not (isinstance(value, list) and len(value) == length
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
            and all(np.isfinite(value))):
        raise InputDataError(f"{where}: {key!r} must be a list of {length} finite numbers, got "
                             f"{value!r}")
    return np.asarray(value, dtype=np.float64)


def _positive(record: dict, key: str, where: str, unit: str) -> float:
    value = record[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not (
            np.isfinite(value) and value > 0):
        raise InputDataError(f"{where}: {key!r} must be a positive number in {unit}, got "
                             f"{value!r}")
    return float(value)


def _one_of(record: dict, keys: tuple[str, ...], where: str, what: str) -> str:
    given = [k for k in keys if k in record]
    if len(given) != 1:
        raise InputDataError(f"{where}: give exactly one of {', '.join(map(repr, keys))} for "
                             f"the {what}, got {', '.join(map(repr, given)) or 'none'}")
    return given[0]


def _rotation(record: dict, key: str, where: str) -> np.ndarray:
    """The world-to-camera rotation of a ``rotation`` or ``quaternion`` key."""
    if key == "quaternion":
        q = _vector(record, key, where, 4)
        norm = np.linalg.norm(q)
        if abs(norm - 1.0) > _ROTATION_TOLERANCE:
            raise InputDataError(f"{where}: 'quaternion' [w, x, y, z] must have unit norm, got "
                                 f"norm {norm:.9g}")
        w, x, y, z = q / norm
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    rows = record[key]
    if not (isinstance(rows, list) and len(rows) == 3):
        raise InputDataError(f"{where}: 'rotation' must be a 3 x 3 matrix (three rows of three "
                             f"numbers), got {rows!r}")
    matrix = np.stack([_vector({key: row}, key, where, 3) for row in rows])
    if (np.abs(matrix @ matrix.T - np.eye(3)).max() > _ROTATION_TOLERANCE
            or abs(np.linalg.det(matrix) - 1.0) > _ROTATION_TOLERANCE):
        raise InputDataError(f"{where}: 'rotation' must be a proper rotation (orthonormal rows, "
                             f"determinant +1), got {rows!r}")
    return matrix


def camera_from_record(record: dict, where: str) -> PinholeCamera:
    """A camera from its record (see the module docstring).

    Parameters
    ----------
    record : dict
        The camera's keys as read from TOML.
    where : str
        The record's place for messages, e.g. ``"rig.toml: camera 2"``.

    Raises
    ------
    InputDataError
        For an unknown or missing key, a value of the wrong kind, or a pose the camera refuses;
        the message starts with ``where`` and names the key.
    """
    if not isinstance(record, dict):
        raise InputDataError(f"{where}: a camera must be a table of keys, got {record!r}")
    for key in record:
        if key not in CAMERA_KEYS:
            close = difflib.get_close_matches(key, CAMERA_KEYS, n=1)
            raise InputDataError(f"{where}: unknown key {key!r}"
                                 + (f" (did you mean {close[0]!r}?)" if close else "")
                                 + f"; allowed: {', '.join(CAMERA_KEYS)}")
    for key in ("position", "focal_length", "pixels"):
        if key not in record:
            raise InputDataError(f"{where}: missing key {key!r}")
    position = _vector(record, "position", where, 3)
    focal_length = _positive(record, "focal_length", where, "m")
    pixels = record["pixels"]
    if not (isinstance(pixels, list) and len(pixels) == 2 and all(
            isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in pixels)):
        raise InputDataError(f"{where}: 'pixels' must be two positive integers [nu, nv] "
                             f"(columns, rows), got {pixels!r}")
    orientation = _one_of(record, ("look_at", "rotation", "quaternion"), where, "orientation")
    if orientation == "look_at":
        if "up" not in record:
            raise InputDataError(f"{where}: 'look_at' needs 'up' (the image's up direction)")
        look_at, up = _vector(record, "look_at", where, 3), _vector(record, "up", where, 3)
    else:
        if "up" in record:
            raise InputDataError(f"{where}: 'up' goes with 'look_at' only; {orientation!r} "
                                 "already gives the orientation")
        right, down, forward = _rotation(record, orientation, where)
        look_at, up = position + forward, -down
    sizing = _one_of(record, ("sensor_size", "pixel_pitch"), where, "sensor")
    size = _vector(record, sizing, where, 2)
    if not np.all(size > 0):
        raise InputDataError(f"{where}: {sizing!r} must be positive (m), got {record[sizing]!r}")
    sensor = size if sizing == "sensor_size" else size * np.asarray(pixels)
    principal = (None if "principal_point" not in record
                 else _vector(record, "principal_point", where, 2))
    try:
        return PinholeCamera(position, look_at, up, focal_length, tuple(sensor), tuple(pixels),
                             None if principal is None else tuple(principal))
    except ValueError as err:
        raise InputDataError(f"{where}: {err}") from err


def _instrument(record: dict, where: str) -> dict:
    """The spectrometer keys of a camera record, checked."""
    out = {}
    if "resolution" in record:
        out["resolution"] = _positive(record, "resolution", where, "cm-1")
    if "window" in record:
        low, high = _vector(record, "window", where, 2)
        if not 0 < low < high:
            raise InputDataError(f"{where}: 'window' must be [min, max] in cm-1 with "
                                 f"0 < min < max, got {record['window']!r}")
        out["window"] = (float(low), float(high))
    if "apodization" in record:
        if record["apodization"] not in APODIZATIONS:
            raise InputDataError(f"{where}: 'apodization' = {record['apodization']!r} is not "
                                 f"modelled; allowed: {', '.join(APODIZATIONS)}")
        out["apodization"] = record["apodization"]
    return out


def parse_rig(records, where: str) -> RigSpec:
    """A rig from camera records (a rig file's ``cameras`` or a configuration's
    ``rig.cameras``).

    Parameters
    ----------
    records : list of dict
        One record per camera, in ray order.
    where : str
        What holds the records, for messages (a file name, ``"rig.cameras"``).

    Raises
    ------
    InputDataError
        For no cameras, a malformed record (the message names the camera index and key) or
        cameras whose resolutions or apodizations differ (their windows may differ).
    """
    if not isinstance(records, list) or not records:
        raise InputDataError(f"{where}: no cameras; list them as [[cameras]] tables (see "
                             "invflame.geometry.rig_file)")
    cameras, common, stated_by, windows = [], {}, {}, []
    for index, record in enumerate(records):
        at = f"{where}: camera {index}"
        cameras.append(camera_from_record(record, at))
        instrument = _instrument(record, at)
        windows.append(instrument.pop("window", None))
        for key, value in instrument.items():
            if key in common and common[key] != value:
                raise InputDataError(
                    f"{at}: {key!r} = {value!r} differs from camera {stated_by[key]}'s "
                    f"{common[key]!r}; invflame models one instrument lineshape for all "
                    "cameras, so every camera must have the same resolution and apodization "
                    "(the spectral window may differ per camera)")
            common.setdefault(key, value)
            stated_by.setdefault(key, index)
    own = tuple(windows) if any(window is not None for window in windows) else None
    return RigSpec(CameraRig(tuple(cameras)), common, own, where)


def preset_path(name: str) -> Path:
    """The packaged rig file of a preset in :data:`PRESETS`."""
    if name not in PRESETS:
        raise InputDataError(f"no rig preset {name!r}; presets: {', '.join(PRESETS)}")
    return Path(str(resources.files("invflame") / "data" / PRESETS[name]))


def read_rig(source) -> RigSpec:
    """Read a rig file, or a preset by name (:data:`PRESETS`).

    Parameters
    ----------
    source : str or os.PathLike
        A TOML rig file (see the module docstring) or a preset name.

    Raises
    ------
    FileNotFoundError
        If ``source`` is neither a file nor a preset.
    InputDataError
        For malformed TOML or records; the message names the file, camera and key.
    """
    path = preset_path(source) if str(source) in PRESETS else Path(source)
    if not path.is_file():
        raise FileNotFoundError(f"rig file not found: {path} (give a TOML rig file or a preset: "
                                f"{', '.join(PRESETS)})")
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as err:
        raise InputDataError(f"{path}: not a TOML rig file: {err}") from err
    extra = sorted(set(raw) - {"cameras"})
    if extra:
        raise InputDataError(f"{path}: unknown top-level key(s) {extra}; a rig file holds only "
                             "[[cameras]] tables")
    return parse_rig(raw.get("cameras"), str(path))


def check_instrument(spec: RigSpec, resolution: float, window, where: str) -> None:
    """Refuse a rig whose cameras state another spectrometer than the one modelled.

    Parameters
    ----------
    spec : RigSpec
        The rig and its stated settings.
    resolution : float
        The modelled resolution in cm⁻¹.
    window : (float, float) or None
        The modelled line-by-line window in cm⁻¹, which each camera's own window must lie
        inside; None: not checked (measured data, whose channels set the window).
    where : str
        What configures the model, for the message.

    Raises
    ------
    InputDataError
        For another resolution, or a camera window reaching outside ``window`` (the message
        names the rig, the camera and the key).
    """
    stated = spec.instrument
    if "resolution" in stated and not np.isclose(stated["resolution"], resolution):
        raise InputDataError(f"the rig's cameras have resolution {stated['resolution']:g} cm-1 "
                             f"but {where} models {resolution:g} cm-1; make them agree (one "
                             "resolution for all cameras)")
    for camera, own in enumerate(spec.windows or ()):
        if window is not None and own is not None and (
                own[0] < window[0] - _WINDOW_TOLERANCE or own[1] > window[1] + _WINDOW_TOLERANCE):
            raise InputDataError(f"{spec.source}: camera {camera}: 'window' = {own[0]:g}-"
                                 f"{own[1]:g} cm-1 reaches outside the window {window[0]:g}-"
                                 f"{window[1]:g} cm-1 that {where} models: narrow the camera's "
                                 "window or widen [spectrum]")


def check_rig_sees_grid(rig: CameraRig, grid: VoxelGrid, rays_per_pixel: int = 1) -> None:
    """Refuse cameras that cannot measure the grid.

    Parameters
    ----------
    rig : CameraRig
        The cameras.
    grid : VoxelGrid
        The reconstruction grid (m).
    rays_per_pixel : int, optional
        Sub-rays per pixel traced to look for a crossed voxel.

    Raises
    ------
    GeometryError
        Naming the first camera (by index, with its position in m) that sits inside the grid,
        faces away from it (every corner of the box behind it) or whose rays cross no voxel.
    """
    corners = grid.corners()
    box = f"the grid {grid.lower.tolist()}-{grid.upper.tolist()} m"
    for index, camera in enumerate(rig.cameras):
        at = f"camera {index} at {camera.position.tolist()} m"
        if grid.contains(camera.position):
            raise GeometryError(f"{at} is inside {box}: place it outside the grid")
        if np.all(camera.to_camera_frame(corners)[:, 2] <= 0):
            axis = camera.forward.round(6).tolist()
            raise GeometryError(f"{at} looks away from {box} (along {axis}): point it at the "
                                f"grid, e.g. look_at its centre {grid.centre.tolist()}")
        if not traverse(grid, *camera.rays(rays_per_pixel)).hit.any():
            raise GeometryError(f"{at} sees no voxel of {box}: none of its rays crosses the "
                                "grid; aim it at the grid or widen its sensor")
