r"""One reconstruction from a configuration: scene, data, representation, solver, metrics, files.

:func:`run_experiment` writes into its output folder

====================== ======================================================================
``config.toml``        the complete configuration (defaults filled in) with its seed; with
                       ``data.source``, a comment on top gives the measurement file's
                       instrument, which the run uses in place of ``[instrument]``, and
                       ``[spectrum]`` the window widened for its channels (``widened_window``)
``summary.json``       metrics (normalized MSE and PSNR per field, time per iteration, memory),
                       the wall time of each stage (``stages``, s: inputs, tables and scene;
                       data; start; choice of λ; solve; outputs), the machine that computed
                       them (:func:`~invflame.experiments.machine.describe_machine`); with
                       ``data.source``, ``measured_instrument`` (the file's instrument)
``history.csv``        per-iteration loss, data misfit, regularizer, gradient norm, wall time
``truth.npz``          ground truth on the reconstruction grid (:class:`invflame.field.Field`)
``initial.npz``        starting fields (for a neural field: the pretrained network's)
``reconstruction.npz`` reconstructed fields
``data.npz``           measured and final simulated spectra, noise σ, output wavenumbers
``checkpoint.npz``     solver state every few iterations (``resume=True`` continues from it)
``fingerprint.json``   content hashes of the truth and the measured data, the package version
                       and the solver's options dataclass (:func:`run_fingerprint`)
``log.txt``            what happened, with timings
``*.vti``              ``truth.vti``, ``start.vti``, ``reconstruction.vti``: the three field
                       sets for ParaView (:mod:`invflame.export`)
``fields.nc``          the three field sets for xarray
====================== ======================================================================

All files are written atomically. A finished run (``summary.json`` present) is not redone with
``resume=True`` unless it stopped at its iteration limit and ``solver.iterations`` is now
higher (it then continues; a limit below the iterations done is refused,
:func:`continues_finished_run`); an interrupted one continues from its checkpoint, unless its
configuration, truth, data or code changed (:func:`check_resumable`, :func:`check_fingerprint`;
``force=True`` continues anyway and records it). While a run writes its folder, the folder is locked
(``.lock``, a second writer is refused) and holds ``INCOMPLETE``, removed when every output is
written (:mod:`invflame.experiments.run_folder`).

**Protocol.** By default the data are synthesized without the inverse crime and with FTIR
noise (:mod:`invflame.experiments.measurement`), the start knows nothing of the truth
(``init.kind = "band-tomography"``, :mod:`invflame.experiments.data_start`), and the summary
records which start, data, noise and λ made the result, with the ray coverage.

**Weighting** (``regularizer.scaling``). ``"chi2"`` (default): the objective is
:math:`\chi^2(\theta)/M + \lambda\,\Phi(\theta)` with the noise-whitened misfit
:math:`\chi^2 = \sum((F(\theta) - d)/\sigma)^2` over the :math:`M` measured values (≈ 1 per
value at the noise level) and :math:`\Phi` a mean over voxels, so λ keeps its meaning whatever
the numbers of pixels, wavenumbers or voxels; solvers minimize :math:`M` times it. ``"paper"``:
the study's reading, kept to reproduce it: the unweighted squared norm of each pixel's spectrum
averaged over the pixels, :math:`\frac{1}{R}\|F(\theta) - d\|^2 + \lambda \Phi`, i.e. the
problem's weight is λ·R for R pixels (its meaning then changes with the grid, the pixels and
the wavenumbers).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import solvers
from invflame.atomic_files import read_json, write_csv, write_json, write_npz, write_text
from invflame.background_file import background_from_config
from invflame.experiments import config as configuration
from invflame.experiments.inputs import (
    absorption_table,
    camera_windows,
    load_truth,
    read_data,
    scene_rig,
    widened_window,
)
from invflame.experiments.machine import describe_machine, in_words
from invflame.experiments.measurement import simulate_measurement, synthesis_scene
from invflame.experiments.metrics import peak_memory_mb
from invflame.experiments.parameters import (
    make_representation,
    physical_fields,
    predicted_spectra,
    starting_parameters,
)
from invflame.experiments.regularization import (
    choose_lambda,
    configured_problem,
    regularizer_weight,
    solver_options,
)
from invflame.experiments.resume import (
    FINGERPRINT,
    FORCE_HINT,
    check_fingerprint,
    check_resumable,
    checkpoint_of_this_run,
    continues_finished_run,
    resumed_from,
    run_fingerprint,
)
from invflame.experiments.run_folder import CHECKPOINT, SUMMARY, RunLock
from invflame.experiments.run_log import Log, StageClock
from invflame.experiments.start import initial_fields
from invflame.experiments.summaries import chi2_per_value, misfit_name, protocol, truth_scores
from invflame.export import export_run
from invflame.field import Field
from invflame.geometry import VoxelGrid, ray_coverage
from invflame.geometry.rig_file import check_instrument
from invflame.measurement import Measurement
from invflame.measurement_file import MeasurementFile
from invflame.scene import Scene
from invflame.spectroscopy.absorption_table import AbsorptionTable

__all__ = ["CHECKPOINT_EVERY", "CHECKPOINT_SECONDS", "FINGERPRINT", "FORCE_HINT", "Log",
           "absorption_table", "build_scene", "check_fingerprint", "check_resumable",
           "chi2_per_value", "choose_lambda", "configured_problem", "initial_fields",
           "load_truth", "make_representation", "measure", "physical_fields", "protocol",
           "read_data", "regularizer_weight", "run_experiment", "run_fingerprint",
           "starting_parameters", "truth_scores", "widened_window"]

CHECKPOINT_EVERY = 10
#: A checkpoint is written every :data:`CHECKPOINT_EVERY` iterations once this many seconds (wall
#: clock) have passed since the last: a killed run loses at most about that much work, and fast
#: iterations (a voxel epoch on a GPU takes under 50 ms) do not spend their time writing
#: checkpoints.
CHECKPOINT_SECONDS = 10.0


def build_scene(cfg: dict, table: AbsorptionTable | None = None,
                measured: MeasurementFile | None = None, progress: bool = True) -> Scene:
    """The reconstruction scene of a configuration: grid (``[grid]``,
    :func:`invflame.experiments.config.reconstruction_grid`), rig, sub-rays, table,
    instrument, background (``[background]``, :func:`.background_from_config`)
    and, with ``soot.reconstruct``, the soot volume fraction as a fifth input field.

    Parameters
    ----------
    cfg : dict
        Validated configuration.
    table : AbsorptionTable, optional
        Reuse an already loaded table (it must match ``cfg["spectrum"]``).
    measured : MeasurementFile, optional
        Measured data (:func:`read_data`): their wavenumbers (cm⁻¹) and resolution replace
        ``[instrument]``, and their cameras are the rig when the configuration names none.
    progress : bool, optional
        Show a progress bar while an absorption table is built.

    Raises
    ------
    InputDataError
        If the rig's cameras state another resolution or windows that do not fit the scene.
    """
    grid = configuration.reconstruction_grid(cfg)
    spec = configuration.rig_spec(cfg)
    rig = scene_rig(cfg, measured)
    table = absorption_table(cfg, progress=progress) if table is None else table
    if measured is None:
        resolution = cfg["instrument"]["resolution"]
        out_wavenumber = configuration.output_grid(cfg, table.wavenumber)
    else:
        resolution, out_wavenumber = measured.resolution, measured.wavenumber
        low, high = out_wavenumber.min(), out_wavenumber.max()
        if low < table.wavenumber[0] or high > table.wavenumber[-1]:
            raise configuration.ConfigError(f"'data.source' = {cfg['data']['source']!r} measures "
                              f"{low:g}-{high:g} cm-1, outside the window 'spectrum.min'.."
                              f"'spectrum.max' = {table.wavenumber[0]:g}-"
                              f"{table.wavenumber[-1]:g} cm-1: widen the window")
    if spec is not None:
        check_instrument(spec, resolution,
                         None if measured else (table.wavenumber[0], table.wavenumber[-1]),
                         "the measurement" if measured else "[instrument] and [spectrum]")
    return Scene(grid, rig, table, resolution=resolution, out_wavenumber=out_wavenumber,
                 rays_per_pixel=cfg["rig"]["rays_per_pixel"],
                 background=background_from_config(cfg["background"]),
                 soot_input=cfg["soot"]["reconstruct"],
                 camera_windows=camera_windows(spec, measured, out_wavenumber))


def measure(cfg: dict, scene: Scene, truth: Field, progress: bool = True) -> Measurement:
    """Synthetic measured spectra of the truth (see :mod:`invflame.experiments.measurement`).

    Parameters
    ----------
    cfg : dict
        Validated configuration (``[data]``, ``[noise]``, ``seed``).
    scene : Scene
        The reconstruction's scene.
    truth : Field
        Ground truth on its native grid (:func:`load_truth`); its soot, if any, is seen in the
        data, whether or not the reconstruction models soot.
    progress : bool, optional
        Show a progress bar while the data's absorption table is built.
    """
    data = cfg["data"]
    if data["inverse_crime"]:
        synthesis, truth = scene, truth.resample(scene.grid)
    else:
        table = absorption_table(cfg, cfg["spectrum"]["step"] / data["step_divisor"], progress)
        synthesis = synthesis_scene(scene, truth, table, data["rays_per_pixel"]
                                    ).with_background(scene.background)
    synthesis = synthesis.with_soot(None, soot_input=truth.soot is not None)
    soot = cfg["truth"]["soot"]
    background = None if scene.background is None else scene.background.describe()
    return simulate_measurement(synthesis, truth, cfg["noise"], seed=cfg["seed"] + 1,
                                provenance={"inverse_crime": data["inverse_crime"],
                                            "truth": str(cfg["truth"]["source"]),
                                            "background": background,
                                            "soot_peak_volume_fraction": soot})


def _on_grid(cfg: dict, truth: Field, grid: VoxelGrid) -> Field:
    """The truth resampled onto the reconstruction grid, or a ConfigError naming the box."""
    try:
        return truth.resample(grid)
    except ValueError as err:
        raise configuration.ConfigError(
            f"'grid.lower'..'grid.upper' = {list(grid.lower)}..{list(grid.upper)} m reaches "
            f"outside the truth {cfg['truth']['source']!r} ({err}): place the box inside "
            f"{list(truth.grid.lower)}..{list(truth.grid.upper)} m") from err


def run_experiment(cfg: dict, out_dir, resume: bool = False, progress: bool = True,
                   table: AbsorptionTable | None = None,
                   measurement: Measurement | None = None,
                   start: np.ndarray | None = None, force: bool = False) -> dict:
    """Run one reconstruction and write its outputs (see the module docstring).

    Parameters
    ----------
    cfg : dict
        Validated configuration (:func:`invflame.experiments.config.validate`).
    out_dir : str or Path
        Output folder (created).
    resume : bool, optional
        Continue an interrupted run from its checkpoint; a finished one is returned as is,
        or continued to a raised ``solver.iterations``.
    progress : bool, optional
        Show a progress bar and echo the log.
    table : AbsorptionTable, optional
        Reuse an already loaded table (it must match ``cfg["spectrum"]``).
    measurement : Measurement, optional
        Reuse measured data made by :func:`measure` for this configuration (a comparison
        shares one measurement between its methods).
    start : ndarray, shape (4, nx, ny, nz), optional
        Reuse starting fields made by :func:`initial_fields` for this configuration and
        measurement.
    force : bool, optional
        With ``resume``: continue even if the configuration, the truth, the measured data or
        the code changed since the folder was written (:func:`check_resumable`,
        :func:`check_fingerprint`); the log and the summary's ``resumed`` entry record what
        changed.

    Returns
    -------
    dict
        The summary (also in ``summary.json``); its ``resumed`` entry is None for a run done
        in one go, else the iteration it continued from, whether the solver resumes exactly,
        whether it was forced and what had changed.
    """
    solver = cfg["solver"]  # a bad solver name or option fails here, before any file is touched
    solvers.get(solver["name"])(max_iter=solver["iterations"], **solver["options"])
    out = Path(out_dir)
    with RunLock(out) as lock:  # one writer at a time; INCOMPLETE until every output is written
        summary = _write_run(cfg, out, resume, progress, table, measurement, start, force)
        lock.complete()
    return summary


def _write_run(cfg: dict, out: Path, resume: bool, progress: bool, table, measurement,
               start, force: bool = False) -> dict:
    """The body of :func:`run_experiment`, in its locked output folder."""
    solver = cfg["solver"]
    summary_path, checkpoint = out / SUMMARY, out / CHECKPOINT
    clock = StageClock()
    measured, native = read_data(cfg), load_truth(cfg)  # the files first: quick to refuse
    cfg, widened = widened_window(cfg, measured)
    changed = check_resumable(cfg, out, force) if resume else []
    scene = build_scene(cfg, None if widened else table, measured, progress)
    truth = None if native is None else _on_grid(cfg, native, scene.grid)
    if resume and summary_path.is_file():
        # finished: simulated data follow from the configuration, truth and code checked here
        given = measurement if measured is None else measured.measurement
        check_fingerprint(out, run_fingerprint(cfg, truth, given), force)
        if not continues_finished_run(cfg, out):
            return read_json(summary_path)
        summary_path.unlink()  # continued to the raised iteration limit
    if not resume:
        for stale in (summary_path, checkpoint, out / "log.txt", out / "lambda_choice.json",
                      out / FINGERPRINT):
            stale.unlink(missing_ok=True)
    log = Log(out / "log.txt", echo=progress)
    if widened:
        log(widened)
    source = cfg["data"]["source"]
    write_text(out / "config.toml", configuration.dumps(cfg) if measured is None
               else measured.instrument_comment(source) + configuration.dumps(cfg))
    log(f"scene: grid {scene.grid.shape}, {scene.n_rays} pixels x {scene.rays_per_pixel} "
        f"sub-rays, {scene.wavenumber.size} line-by-line points -> "
        f"{scene.out_wavenumber.size} output points; truth {cfg['truth']['source']}")
    clock.lap("inputs, tables and scene")
    if measurement is None:
        measurement = (measure(cfg, scene, native, progress) if measured is None
                       else measured.measurement)
        clock.lap("data")
    fingerprint = run_fingerprint(cfg, truth, measurement)
    if resume:
        changed += check_fingerprint(out, fingerprint, force)
    if changed:
        log("resumed with --force although what defines the run changed: " + "; ".join(changed))
    write_json(out / FINGERPRINT, fingerprint)
    described = protocol(cfg, measurement)
    log("; ".join(f"{k}: {v}" for k, v in described.items()))
    coverage = ray_coverage(scene.segments, scene.rig, None if truth is None else truth.values[0])
    if start is None:
        start = initial_fields(cfg, truth, scene, measurement, log)

    representation = make_representation(cfg, scene)
    machine = describe_machine(uses_torch=representation.kind != "voxel")
    log(f"computing on: {in_words(machine)}")
    x0 = starting_parameters(cfg, representation, start, progress)
    clock.lap("start")
    start = physical_fields(scene, representation.fields(x0))
    if truth is None:
        (out / "truth.npz").unlink(missing_ok=True)
    else:
        truth.save(out / "truth.npz")
    Field(scene.grid, start, {"source": "initial", "init": cfg["init"]}).save(out / "initial.npz")
    reg = dict(cfg["regularizer"])
    choice_file = out / "lambda_choice.json"
    if isinstance(reg["lambda"], str):  # a rule: chosen from the data, once
        chosen = (read_json(choice_file) if resume and choice_file.is_file() else
                  choose_lambda(cfg, scene, representation, measurement, x0, out,
                                log).as_dict())
        reg["lambda"] = float(chosen["lam"])
        described["lambda"] = (f"{reg['lambda']:.4g} from the discrepancy principle"
                               + ("" if chosen["reached"] else " (criterion not reached: "
                                  "smallest misfit tried)"))
        log(f"regularizer weight: lambda {described['lambda']}")
        clock.lap("choice of lambda")
    problem = configured_problem(cfg, scene, representation, measurement, reg["lambda"], x0)
    per_epoch = representation.iterations_per_epoch
    callbacks = [solvers.Checkpoint(checkpoint, every=CHECKPOINT_EVERY, seconds=CHECKPOINT_SECONDS)]
    if progress:
        callbacks.append(solvers.ProgressBar(desc=out.name))
    resume_from = checkpoint if resume and checkpoint.is_file() else None
    resumed = None if resume_from is None else resumed_from(cfg, out, per_epoch, changed)
    log(f"solver {solver['name']} for at most {solver['iterations']} epochs"
        + (f" ({per_epoch} iterations each)" if per_epoch > 1 else "")
        + (f", resuming from {checkpoint.name}" if resume_from else ""))
    with checkpoint_of_this_run(out):
        result = solvers.solve(problem, solver["name"], max_iter=solver["iterations"] * per_epoch,
                               callbacks=callbacks, seed=cfg["seed"], resume=resume_from,
                               **solver_options(cfg, measurement))
    clock.lap("solve")
    log(str(result))

    fields = physical_fields(scene, representation.fields(result.x))
    Field(scene.grid, fields,
          {"source": "reconstruction", "config": cfg}).save(out / "reconstruction.npz")
    simulated = predicted_spectra(scene, representation, result.x)
    write_npz(out / "data.npz", measured=measurement.data, simulated=simulated,
              sigma=measurement.sigma, out_wavenumber=scene.out_wavenumber)
    history = result.history.as_dict()
    write_csv(out / "history.csv", [dict(zip(history, row, strict=True))
                                    for row in zip(*history.values(), strict=True)])
    seconds = float(np.diff(history["time"]).mean()) if len(history["time"]) > 1 else None
    summary = {
        "config": cfg,
        "measured_instrument": None if measured is None else measured.instrument(source),
        "protocol": described,
        "resumed": resumed,
        "lambda": reg["lambda"],
        "coverage": coverage,
        "iterations": result.iterations,
        "epochs": result.iterations / per_epoch,
        "stop_reason": result.stop_reason,
        "converged": result.converged,
        "diverged": result.diverged,
        "loss": {"initial": history["loss"][0], "final": result.loss},
        "chi2_per_measurement": {
            "initial": chi2_per_value(predicted_spectra(scene, representation, x0), measurement),
            "final": chi2_per_value(simulated, measurement)},
        "noisy_data": measurement.noisy,
        "noise_weighted_misfit": reg["scaling"] == "chi2" and measurement.noisy,
        **({} if truth is None else truth_scores(truth.values, fields, start)),
        "seconds_per_iteration": seconds,
        "seconds_per_epoch": None if seconds is None else seconds * per_epoch,
        "parameter_memory_mb": representation.parameter_bytes(result.x) / 1e6,
        "peak_memory_mb": peak_memory_mb(),
        "machine": machine,
    }
    write_json(summary_path, summary)
    export_run(out)
    clock.lap("outputs")
    summary["stages"] = clock.seconds
    write_json(summary_path, summary)
    log(clock.table())
    scored = (f"MSE {summary['mse']} (start {summary['mse_initial']}); " if truth is not None
              else "no ground truth; ")
    log(f"{scored}{misfit_name(measurement.noisy)} "
        f"{summary['chi2_per_measurement']['final']:.3g}; "
        f"{result.iterations} iterations, "
        f"{'converged' if summary['converged'] else 'not converged'}")
    return summary
