"""Rig files written: the camera records of a rig as the TOML that
:mod:`invflame.geometry.rig_file` reads back to the same rays, bit for bit."""

from __future__ import annotations

from pathlib import Path

import tomli_w

from invflame.atomic_files import write_text
from invflame.geometry.rig import CameraRig


def rig_records(rig: CameraRig) -> list[dict]:
    """The camera records of a rig (look-at and up form), as
    :func:`~invflame.geometry.rig_file.parse_rig` reads them."""
    def floats(values):
        return [float(v) for v in values]

    return [{"position": floats(c.position), "look_at": floats(c.look_at), "up": floats(c.up),
             "focal_length": c.focal_length, "sensor_size": floats(c.sensor_size),
             "pixels": list(c.n_pixels), "principal_point": floats(c.principal_point)}
            for c in rig.cameras]


def rig_toml(rig: CameraRig, instrument=None) -> str:
    """A rig file's text: ``[[cameras]]`` tables of :func:`rig_records`.

    Parameters
    ----------
    rig : CameraRig
        The cameras (lengths in m, pixel coordinates in pixels).
    instrument : dict or sequence of dict, optional
        Spectrometer keys (:data:`~invflame.geometry.rig_file.INSTRUMENT_KEYS`) stated by
        every camera, or one dict per camera: ``[{"window": [668.0, 682.0]}, {}, {}]`` gives
        the first camera its own window in cm⁻¹.
    """
    lines = ["# invflame camera rig: lengths in m, pixel coordinates in pixels "
             "(see invflame.geometry.rig_file)"]
    each = ([instrument or {}] * rig.n_cameras if instrument is None or isinstance(
        instrument, dict) else list(instrument))
    for record, stated in zip(rig_records(rig), each, strict=True):
        lines += ["", "[[cameras]]"] + [f"{key} = {_toml(value)}" for key, value in
                                         {**record, **stated}.items()]
    return "\n".join(lines) + "\n"


def _toml(value) -> str:
    """A number, string or list as an inline TOML value; floats in their shortest exact form."""
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, str):
        return tomli_w.dumps({"v": value})[4:].strip()
    return repr(value)


def write_rig(rig: CameraRig, path, instrument=None) -> Path:
    """Write a rig file atomically (see :func:`rig_toml`, which takes ``instrument``); returns
    ``path``."""
    return write_text(path, rig_toml(rig, instrument))
