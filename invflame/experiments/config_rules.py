"""Conditions between the keys of a configuration, every one checked and every error reported.

:func:`check_rules` runs, on a configuration whose keys each passed the schema
(:func:`invflame.experiments.config.validate`), one check per condition: where the data, the
truth and the rig come from, the grid, soot, the regularizer, the solver, the spectral window,
the files the configuration names (:mod:`invflame.experiments.config_files`), the memory its
arrays need (:mod:`invflame.experiments.config_memory`), the output grid, the cameras and the
noise file. Each check yields one message per error. A check is left out where a key it reads
was refused, and so is a check that builds arrays (the wavenumber grids, the rays) where the
memory check did not pass: its message would repeat another, or the arrays not fit. The memory
check itself always runs: a refused key's default is a size the run could take.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

from invflame.errors import ConfigError, GeometryError
from invflame.experiments.config_files import (
    camera_keys,
    check_data_file,
    check_named_files,
    check_nesr_file,
    check_rig_file,
    check_truth_file,
)
from invflame.experiments.config_memory import check_memory
from invflame.experiments.config_scene import (
    LINE_DATA_RANGE,
    line_by_line_grid,
    output_grid,
    reconstruction_grid,
)

GRID, WINDOW, CAMERAS = "(grid)", "(window)", "(cameras)"
ARRAYS, OUTPUT = "(arrays)", "(output grid)"
"""Marks of a check that did not pass, for the checks that need it to: the grid's box, the
spectral window's order and line data, the rig's cameras, the arrays' memory, the
instrument's output grid."""


def _check_sources(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """Where the data, the truth and the rig come from. With ``data.source`` and no
    ``truth.source`` given, the run has no ground truth (``truth.source = "none"``), which
    needs a measurement file and a start that is not the truth's; a rig comes from
    ``rig.file`` or ``rig.cameras``, not both."""
    stated = raw.get("truth", {}) if isinstance(raw.get("truth"), dict) else {}
    if full["data"]["source"] and "source" not in stated:
        full["truth"]["source"] = "none"
    if full["truth"]["source"] == "none":
        if not full["data"]["source"]:
            yield ("'truth.source' = 'none' needs measured data: set 'data.source' to a "
                   "measurement file")
        if full["init"]["kind"] == "noisy-truth":
            yield ("'init.kind' = 'noisy-truth' needs a ground truth but 'truth.source' is "
                   "'none': start from the data ('band-tomography') or 'ambient', or give "
                   "'truth.source'")
    if full["rig"]["file"] and full["rig"]["cameras"]:
        yield "[rig] gives both 'file' and [[rig.cameras]]: give the cameras in one place"


def _check_grid(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    grid = full["grid"]
    lower, upper = grid["lower"], grid["upper"]
    if not all(lo < hi for lo, hi in zip(lower, upper, strict=True)):
        yield (f"'grid.upper' = {upper!r} m must exceed 'grid.lower' = {lower!r} m on every "
               "axis (x, y, z): swap the corners or widen the box")
    stated = raw.get("truth", {}) if isinstance(raw.get("truth"), dict) else {}
    if grid["cells"] and "grid" in stated:
        yield ("both 'truth.grid' and 'grid.cells' give the voxels of the reconstruction grid: "
               "give them in one place ('grid.cells' for [nx, ny, nz])")


def _check_soot(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    soot, truth = full["soot"], full["truth"]
    if not soot["reconstruct"]:
        return
    kind = full["representation"]["kind"]
    if kind != "voxel":
        yield (f"'soot.reconstruct' = true needs 'representation.kind' = 'voxel' (the networks "
               f"render gas only), got {kind!r}: use the voxel representation or set "
               "reconstruct = false")
    if truth["soot"] > soot["max"]:
        yield (f"'truth.soot' = {truth['soot']!r} exceeds 'soot.max' = {soot['max']!r}, the "
               "bound of the reconstructed soot volume fraction: raise soot.max to at least "
               "truth.soot")


def _check_regularizer(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    reg, kind = full["regularizer"], full["representation"]["kind"]
    if reg["lambda"] == "discrepancy" and reg["scaling"] != "chi2":
        yield ("'regularizer.lambda' = 'discrepancy' needs 'regularizer.scaling' = 'chi2' (the "
               "rule compares the noise-weighted misfit with the number of measurements): set "
               "scaling = \"chi2\" or give lambda a number")
    if full["solver"]["stop_chi2"] > 0 and reg["scaling"] != "chi2":
        yield (f"'solver.stop_chi2' = {full['solver']['stop_chi2']!r} stops at a noise-weighted "
               "misfit χ²/M, but 'regularizer.scaling' = 'paper' weights none: set scaling = "
               "\"chi2\" or stop_chi2 = 0")
    if reg["tv_smoothing"] == 0:
        return
    if reg["kind"] != "tv":
        yield (f"'regularizer.tv_smoothing' = {reg['tv_smoothing']!r} smooths total variation, "
               f"but 'regularizer.kind' = {reg['kind']!r}: set kind = 'tv' or tv_smoothing = 0")
    if kind != "voxel":
        yield (f"'regularizer.tv_smoothing' needs 'representation.kind' = 'voxel', got {kind!r} "
               "(the networks' regularizer is exact TV): set tv_smoothing = 0")


def _check_window(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """The window's order, its step against the resolution, and the line data it lies in
    (the built-in lists' :data:`LINE_DATA_RANGE`, unless both line files are given)."""
    spectrum, instrument = full["spectrum"], full["instrument"]
    lo, hi, step = spectrum["min"], spectrum["max"], spectrum["step"]
    if not lo < hi:
        yield (f"'spectrum.min' must be below 'spectrum.max', got {lo!r} and {hi!r} cm-1: swap "
               "them or widen the window")
        return
    if not step <= instrument["resolution"] / 2:
        yield (f"'spectrum.step' = {step!r} cm-1 must be at most half of "
               f"'instrument.resolution' = {instrument['resolution']!r} cm-1 (the lineshape "
               "needs several line-by-line points per resolution)")
    if spectrum["co2_lines"] and spectrum["h2o_lines"]:
        return  # the files' own range: read when the table is built
    first, last = LINE_DATA_RANGE
    covered = f"the built-in line data cover {first:g}-{last:g} cm-1"
    if hi < first or lo > last:
        yield (f"the window 'spectrum.min'..'spectrum.max' = {lo:g}-{hi:g} cm-1 holds no "
               f"absorption line: {covered}")
    elif lo < first or hi > last:
        yield (f"the window 'spectrum.min'..'spectrum.max' = {lo:g}-{hi:g} cm-1 reaches past "
               f"the line data: {covered}, so the spectra outside it would hold no line of the "
               f"built-in lists: keep the window within {first:g}-{last:g} cm-1, or give "
               "'spectrum.co2_lines' and 'spectrum.h2o_lines' files that cover it")


def _check_output_grid(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    spectrum, instrument = full["spectrum"], full["instrument"]
    n_out = output_grid(full, line_by_line_grid(spectrum)).size
    if n_out < 2:
        yield (f"'instrument.sampling' = {instrument['sampling']!r} cm-1 leaves {n_out} output "
               f"point in the window {spectrum['min']:g}-{spectrum['max']:g} cm-1 (less one "
               f"resolution {instrument['resolution']:g} cm-1 at each end): make it smaller or "
               "widen the window")


def _check_rig(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """The cameras against the reconstruction grid: the configured ones must see it, the
    paper's must stand outside it."""
    from invflame.geometry import paper_rig
    from invflame.geometry.rig_file import check_rig_sees_grid

    rig, spec = full["rig"], loaded["rig"]
    grid = reconstruction_grid(full)
    if spec is not None:
        try:
            check_rig_sees_grid(spec.rig, grid)
        except GeometryError as err:
            yield f"{camera_keys(full)}: {err}"
        return
    try:
        paper_rig(grid, distance=rig["distance"], n_pixels=rig["pixels"],
                  focal_length=rig["focal_length"])
    except GeometryError as err:
        yield f"'rig.distance' = {rig['distance']!r}: {err}"


def _check_solver(raw: dict, full: dict, loaded: dict) -> Iterator[str]:
    """The solver's name and options: the stopping rules' types here, the algorithm options by
    the solver's own ``Options`` dataclass (:mod:`solvers.options`)."""
    import solvers
    from solvers.options import STOPPING_RULES, OptionError

    solver = full["solver"]
    try:
        cls = solvers.get(solver["name"])
    except ValueError as err:
        yield f"'solver.name': {err}"
        return
    options = solver["options"]
    if "max_iter" in options:
        yield ("'solver.options.max_iter' clashes with 'solver.iterations' (the iteration "
               "limit): remove it from the options and set 'solver.iterations'")
        return
    for key in STOPPING_RULES:  # the algorithm options are checked by the solver's Options
        value = options.get(key)
        if isinstance(value, str | bool):
            yield (f"'solver.options.{key}' must be a number, got {value!r} (write "
                   f"{key} = {value} without quotes)")
            return
        if isinstance(value, float) and not math.isfinite(value):
            yield f"'solver.options.{key}' must be a finite number, got {value!r}"
            return
    try:
        cls(max_iter=solver["iterations"], **options)
    except OptionError as err:
        if err.allowed is None:  # an unknown name: the message lists the allowed ones
            yield f"'solver.options' = {options!r}: {err}"
            return
        unquote = (f" (write {err.option} = {err.value} without quotes)"
                   if isinstance(err.value, str) else "")
        yield (f"'solver.options' = {options!r}: 'solver.options.{err.option}' must be "
               f"{err.allowed}, got {err.value!r}{unquote} (an option of solver "
               f"{err.solver!r})")
    except (TypeError, ValueError, OverflowError) as err:  # the stopping rules
        yield f"'solver.options' = {options!r}: {err}"


Check = Callable[[dict, dict, dict], Iterator[str]]

WINDOW_KEYS = ("spectrum.min", "spectrum.max", "spectrum.step")
CAMERA_KEYS = ("rig.file", "rig.cameras")
RULES: tuple[tuple[Check, tuple[str, ...], str], ...] = (
    (_check_sources, ("truth.source", "data.source", "init.kind", *CAMERA_KEYS), ""),
    (_check_grid, ("grid", "truth.grid"), GRID),
    (_check_soot, ("soot", "truth.soot", "representation.kind"), ""),
    (_check_regularizer, ("regularizer", "representation.kind"), ""),
    (_check_solver, ("solver",), ""),
    (_check_window, (*WINDOW_KEYS, "spectrum.co2_lines", "spectrum.h2o_lines",
                     "instrument.resolution"), WINDOW),
    (check_truth_file, ("truth.source", "truth.soot"), ""),
    (check_rig_file, CAMERA_KEYS, CAMERAS),
    (check_data_file, ("data.source", *CAMERA_KEYS, CAMERAS), ""),
    (check_named_files, ("background", "spectrum.co2_lines", "spectrum.h2o_lines", "noise"),
     ""),
    (check_memory, (), ARRAYS),  # with a refused key's default: sizes the run could take
    (_check_output_grid, (*WINDOW_KEYS, "instrument", WINDOW, ARRAYS), OUTPUT),
    (_check_rig, ("rig", "grid", "truth.grid", GRID, CAMERAS, ARRAYS), ""),
    (check_nesr_file, ("noise", "data.source", *WINDOW_KEYS, "instrument", WINDOW, ARRAYS,
                       OUTPUT), ""),
)
"""Each check, the keys (a section: all of its keys) and marks it reads, and the mark it leaves
when it does not pass, in the order they run. A check takes the configuration as given, the
complete one and what the checks before it loaded (the truth, the cameras and the measurement,
:mod:`invflame.experiments.config_files`), and yields its errors' messages."""


def _overlap(refused: set[str], reads: tuple[str, ...]) -> bool:
    """Whether a refused key or mark is one of ``reads``, in one of its sections or holds one
    of them (a section given as a value)."""
    return any(a == b or a.startswith(f"{b}.") or b.startswith(f"{a}.")
               for a in refused for b in reads)


def check_rules(raw: dict, full: dict, refused: set[str]) -> list[str]:
    """Every condition between the keys of a configuration.

    Parameters
    ----------
    raw : dict
        The configuration as given (which keys it states).
    full : dict
        The complete configuration, keys checked; ``truth.source`` becomes ``"none"`` where
        measured data come without a truth.
    refused : set of str
        The dotted paths of the refused keys (their defaults stand in): the checks reading
        them are left out.

    Returns
    -------
    list of str
        One message per error, naming the keys and what to do; empty when all hold.
    """
    errors: list[str] = []
    left_out, loaded = set(refused), {}
    for check, reads, mark in RULES:
        if not _overlap(left_out, reads):
            try:
                found = list(check(raw, full, loaded))
            except ConfigError as err:
                found = err.messages
            errors += found
            if not found:
                continue
        if mark:
            left_out.add(mark)
    return errors
