"""One reconstruction from a configuration: scene, data, representation, solver, metrics, files.

:func:`run_experiment` writes into its output folder

``config.toml``        the complete configuration (defaults filled in) with its seed
``summary.json``       metrics (normalized MSE and PSNR per field, time per iteration, memory)
``history.csv``        per-iteration loss, data misfit, regularizer, gradient norm, wall time
``truth.npz``          ground truth on the reconstruction grid (:class:`invflame.field.Field`)
``initial.npz``        starting fields
``reconstruction.npz`` reconstructed fields
``data.npz``           measured and final simulated spectra, output wavenumbers
``checkpoint.npz``     solver state every few iterations (``resume=True`` continues from it)
``log.txt``            what happened, with timings

All files are written atomically. A finished run (``summary.json`` present) is not redone with
``resume=True``; an interrupted one continues from its checkpoint.

**Weighting.** The paper's loss is :math:`\\|H[f] - g\\|^2 + \\lambda \\Phi` with λ = 1e-3 and
Φ a mean over voxels; we read its data term as NeRF-style training does, the squared norm of
each pixel's spectrum averaged over the pixels (rays). Solvers minimize the plain sum of
squares :math:`\\|F(\\theta) - d\\|^2 + \\lambda R\\, \\Phi(\\theta)` over all R rays, which is R
times that objective (same minimizer; Adam and line searches are invariant to the factor), so
the problem's λ is ``regularizer.lambda × R``; losses in ``history.csv`` are on this scale.
(Averaging over every pixel *and* wavenumber instead weighs Φ 30 times more at the default
2 cm⁻¹ output sampling; on the quick preset that over-smooths: Tikhonov then does worse than no
regularizer.)
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import operators as op
import solvers
from invflame.atomic_files import read_json, write_csv, write_json, write_npz, write_text
from invflame.experiments import config as configuration
from invflame.experiments.initialization import add_noise, ambient, noisy_truth
from invflame.experiments.metrics import hot_volume_ratio, normalized_mse, peak_memory_mb, psnr
from invflame.field import Field
from invflame.geometry import VoxelGrid, paper_rig
from invflame.phantoms import make_phantom
from invflame.representations.neural import NeuralFieldRepresentation
from invflame.representations.neural_centres import NeuralCentresRepresentation
from invflame.representations.normalization import physical_bounds
from invflame.representations.voxel import VoxelRepresentation
from invflame.scene import Scene
from invflame.spectroscopy.absorption_table import AbsorptionTable, default_linelists

CHECKPOINT_EVERY = 10


class Log:
    """Appends timestamped lines to ``log.txt`` (and prints them when ``echo``)."""

    def __init__(self, path: Path, echo: bool = True):
        self.path, self.echo, self.start = path, echo, time.perf_counter()

    def __call__(self, message: str) -> None:
        line = f"[{time.perf_counter() - self.start:8.1f} s] {message}"
        with open(self.path, "a") as handle:
            handle.write(line + "\n")
        if self.echo:
            print(line, flush=True)


def absorption_table(cfg: dict) -> AbsorptionTable:
    """The absorption table for the configuration's spectral window (cached on disk)."""
    spectrum = cfg["spectrum"]
    n = int(round((spectrum["max"] - spectrum["min"]) / spectrum["step"])) + 1
    wavenumber = spectrum["min"] + spectrum["step"] * np.arange(n)
    return AbsorptionTable.cached(default_linelists(wavenumber), wavenumber=wavenumber,
                                  pressure=spectrum["pressure"])


def build_scene(cfg: dict, table: AbsorptionTable | None = None) -> Scene:
    """The measurement scene of a configuration: grid, rig, table and instrument."""
    grid = VoxelGrid.poolfire(cfg["truth"]["grid"])
    rig = paper_rig(grid, distance=cfg["rig"]["distance"], n_pixels=cfg["rig"]["pixels"],
                    focal_length=cfg["rig"]["focal_length"])
    table = absorption_table(cfg) if table is None else table
    instrument = cfg["instrument"]
    out = op.ils.default_output_grid(table.wavenumber, instrument["resolution"])
    out = np.arange(out[0], out[-1] + 1e-9, instrument["sampling"])
    return Scene(grid, rig, table, resolution=instrument["resolution"], out_wavenumber=out)


def load_truth(cfg: dict, grid: VoxelGrid) -> Field:
    """The ground truth named by ``truth.source`` on ``grid``: a phantom name or a .npz file."""
    source = cfg["truth"]["source"]
    if source in ("poolfire", "synthetic"):
        return make_phantom(source, grid=grid)
    path = Path(source)
    if not path.is_file():
        raise FileNotFoundError(
            f"truth.source {source!r} is neither 'poolfire', 'synthetic' nor an existing file"
        )
    return Field.load(path).resample(grid)


def initial_fields(cfg: dict, truth: Field) -> np.ndarray:
    """Starting fields: the paper's noisy truth, or ambient air."""
    init = cfg["init"]
    if init["kind"] == "ambient":
        return ambient(truth.grid.shape)
    return noisy_truth(truth.values, init["noise"], seed=cfg["seed"])


def make_representation(cfg: dict, scene: Scene):
    """The representation named by ``representation.kind`` on the scene."""
    settings, kind = cfg["representation"], cfg["representation"]["kind"]
    network = {"n_frequencies": settings["frequencies"], "hidden": settings["hidden"],
               "depth": settings["layers"], "seed": cfg["seed"]}
    if kind == "neural":
        return NeuralFieldRepresentation(scene, n_coarse=settings["coarse_samples"],
                                         n_fine=settings["fine_samples"],
                                         batch_rays=settings["rays_per_batch"], **network)
    if kind == "neural-centres":
        return NeuralCentresRepresentation(scene, **network)
    return VoxelRepresentation(scene.grid, scene.operator, temperature_range=_t_range(scene))


def starting_parameters(cfg: dict, representation, start: np.ndarray, progress: bool):
    """Parameters of the starting fields: normalized voxels, or networks pretrained on them."""
    if representation.kind == "voxel":
        return representation.initial_parameters(start)
    return representation.initial_parameters(
        start, iterations=cfg["representation"]["pretrain_iterations"], seed=cfg["seed"],
        progress=progress)


def _t_range(scene: Scene) -> tuple[float, float]:
    return float(scene.table.temperatures[0]), float(scene.table.temperatures[-1])


def run_experiment(cfg: dict, out_dir, resume: bool = False, progress: bool = True,
                   table: AbsorptionTable | None = None) -> dict:
    """Run one reconstruction and write its outputs (see the module docstring).

    Parameters
    ----------
    cfg : dict
        Validated configuration (:func:`invflame.experiments.config.validate`).
    out_dir : str or Path
        Output folder (created).
    resume : bool, optional
        Continue an interrupted run from its checkpoint; a finished one is returned as is.
    progress : bool, optional
        Show a progress bar and echo the log.
    table : AbsorptionTable, optional
        Reuse an already loaded table (it must match ``cfg["spectrum"]``).

    Returns
    -------
    dict
        The summary (also in ``summary.json``).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary_path, checkpoint = out / "summary.json", out / "checkpoint.npz"
    if resume and summary_path.is_file():
        return read_json(summary_path)
    if not resume:
        for stale in (summary_path, checkpoint, out / "log.txt"):
            stale.unlink(missing_ok=True)
    log = Log(out / "log.txt", echo=progress)
    write_text(out / "config.toml", configuration.dumps(cfg))

    scene = build_scene(cfg, table)
    truth = load_truth(cfg, scene.grid)
    log(f"scene: grid {scene.grid.shape}, {scene.n_rays} rays, {scene.wavenumber.size} "
        f"line-by-line points -> {scene.out_wavenumber.size} output points; truth "
        f"{cfg['truth']['source']}")
    data = scene.simulate(truth.values)
    if cfg["noise"]["kind"] == "gaussian":
        data = add_noise(data, cfg["noise"]["snr"], seed=cfg["seed"] + 1)
    start = initial_fields(cfg, truth)
    truth.save(out / "truth.npz")
    Field(scene.grid, start, {"source": "initial", "init": cfg["init"]}).save(
        out / "initial.npz")

    representation = make_representation(cfg, scene)
    x0 = starting_parameters(cfg, representation, start, progress)
    problem = representation.problem(data, regularizer=cfg["regularizer"]["kind"],
                                     lam=cfg["regularizer"]["lambda"] * scene.n_rays, x0=x0)
    solver = cfg["solver"]
    callbacks = [solvers.Checkpoint(checkpoint, every=CHECKPOINT_EVERY)]
    if progress:
        callbacks.append(solvers.ProgressBar(desc=out.name))
    resume_from = checkpoint if resume and checkpoint.is_file() else None
    log(f"solver {solver['name']} for {solver['iterations']} iterations"
        + (f", resuming from {checkpoint.name}" if resume_from else ""))
    result = solvers.solve(problem, solver["name"], max_iter=solver["iterations"],
                           callbacks=callbacks, seed=cfg["seed"], resume=resume_from,
                           **solver["options"])
    log(str(result))

    fields = representation.fields(result.x)
    lower, upper = physical_bounds(*_t_range(scene))
    fields = np.clip(fields, lower.reshape(4, 1, 1, 1), upper.reshape(4, 1, 1, 1))
    fields[1:] /= np.maximum(fields[1:].sum(axis=0), 1.0)  # a network may exceed sum(X) = 1
    Field(scene.grid, fields,
          {"source": "reconstruction", "config": cfg}).save(out / "reconstruction.npz")
    simulated = scene.simulate(fields)
    write_npz(out / "data.npz", measured=data, simulated=simulated,
              out_wavenumber=scene.out_wavenumber)
    history = result.history.as_dict()
    write_csv(out / "history.csv",
              [dict(zip(history, row, strict=True)) for row in zip(*history.values(),
                                                                   strict=True)])
    times = np.asarray(history["time"])
    seconds = float(np.diff(times).mean()) if times.size > 1 else None
    batches = (scene.n_rays / cfg["representation"]["rays_per_batch"]
               if representation.kind == "neural-field" else 1.0)
    summary = {
        "config": cfg,
        "iterations": result.iterations,
        "stop_reason": result.stop_reason,
        "loss": {"initial": history["loss"][0], "final": result.loss},
        "mse": normalized_mse(truth.values, fields),
        "mse_initial": normalized_mse(truth.values, start),
        "psnr_db": psnr(truth.values, fields),
        # a truth with no flame (a user's cold field) has no hot volume to compare
        "hot_volume_ratio": (hot_volume_ratio(truth.values, fields)
                             if np.any(truth.values[0] > 500.0) else None),
        "seconds_per_iteration": seconds,
        "seconds_per_epoch": None if seconds is None else seconds * batches,
        "parameter_memory_mb": representation.parameter_bytes(result.x) / 1e6,
        "peak_memory_mb": peak_memory_mb(),
    }
    write_json(summary_path, summary)
    log(f"MSE {summary['mse']} (initial {summary['mse_initial']}); "
        f"{summary['seconds_per_iteration']} s/iteration")
    return summary
