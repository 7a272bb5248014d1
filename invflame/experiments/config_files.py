"""The files a configuration names, read as the run reads them, before anything is written.

Each check is one of :data:`invflame.experiments.config_rules.RULES`: it reads a file with the
run's own reader (:func:`invflame.experiments.inputs.load_truth`, :func:`~invflame.experiments.
inputs.read_data`, :func:`invflame.background_file.read_background`,
:func:`invflame.experiments.measurement.read_nesr`), so ``invflame config`` and ``invflame run``
refuse a missing or unusable file with the reader's message, naming the key. What a check
loaded (the truth, the rig, the measurement) is left in ``loaded`` for the checks after it.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from invflame.errors import InputDataError
from invflame.experiments.config_scene import line_by_line_grid, output_grid, rig_spec

UNREADABLE = (InputDataError, ValueError, OSError)
"""What the readers raise for a file that is missing, damaged or of another layout (their
messages name the file)."""


def check_truth_file(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """A ``truth.source`` file: there, a field file, real, finite, in range; kept as
    ``loaded["truth"]``."""
    from invflame.experiments.inputs import load_truth

    if full["truth"]["source"] in ("none", "poolfire", "synthetic"):
        return
    try:
        loaded["truth"] = load_truth(full)
    except UNREADABLE as err:
        yield str(err)


def camera_keys(cfg: dict) -> str:
    """Where the configured cameras come from, for messages: ``'rig.file' = path`` or
    ``'rig.cameras'``."""
    source = cfg["rig"]["file"]
    return f"'rig.file' = {source!r}" if source else "'rig.cameras'"


def check_rig_file(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """The cameras of ``rig.file`` or ``rig.cameras``, kept as ``loaded["rig"]`` (None for the
    paper's rig)."""
    try:
        loaded["rig"] = rig_spec(full)
    except UNREADABLE as err:
        yield f"{camera_keys(full)}: {err}"


def check_data_file(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """A ``data.source`` measurement file, read and compared with the configured cameras;
    kept as ``loaded["measured"]``."""
    from invflame.experiments.inputs import read_data

    source = full["data"]["source"]
    if not source:
        return
    if not Path(source).is_file():
        yield (f"'data.source' = {source!r} is not an existing measurement file (.nc, see "
               "invflame.measurement_file)")
        return
    try:
        loaded["measured"] = read_data(full)
    except UNREADABLE as err:
        yield f"'data.source' = {source!r}: {err}"


def check_named_files(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """The background file, the line files and a noise file: there, and the background read."""
    from invflame.background_file import read_background

    background = full["background"]
    if background["kind"] == "file":
        if not Path(background["file"]).is_file():
            yield (f"'background.kind' = 'file' needs 'background.file' to be an existing "
                   "NetCDF file of background spectra (see invflame.background), got "
                   f"{background['file']!r}")
        else:
            try:
                read_background(background["file"])
            except UNREADABLE as err:
                yield f"'background.file' = {background['file']!r}: {err}"
    for species in ("co2", "h2o"):
        lines = full["spectrum"][f"{species}_lines"]
        if lines and not Path(lines).is_file():
            yield (f"'spectrum.{species}_lines' = {lines!r} is not an existing file: give a "
                   f"HITRAN or HITEMP .par file of {species.upper()} lines, or leave it empty "
                   "for the built-in lines")
    nesr = full["noise"]["nesr"]
    if full["noise"]["kind"] == "nesr" and isinstance(nesr, str) and not Path(nesr).is_file():
        yield (f"'noise.nesr' = {nesr!r} is neither a number nor an existing file of "
               "(wavenumber, NESR) rows")


def check_nesr_file(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """A ``noise.nesr`` file of (wavenumber, NESR) rows, read over the instrument's output
    grid (which it must cover)."""
    from invflame.experiments.measurement import read_nesr

    nesr = full["noise"]["nesr"]
    if (full["noise"]["kind"] != "nesr" or not isinstance(nesr, str) or full["data"]["source"]
            or not Path(nesr).is_file()):  # a missing file: said by check_named_files
        return
    try:
        read_nesr(nesr, output_grid(full, line_by_line_grid(full["spectrum"])))
    except UNREADABLE as err:
        yield f"'noise.nesr' = {nesr!r}: {err}"
