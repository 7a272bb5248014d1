"""``invflame run``, ``invflame simulate`` and ``invflame plot``: one configuration at a time."""

from __future__ import annotations

import argparse
from pathlib import Path

from invflame.cli import arguments
from invflame.errors import ConfigError

CONFIG_HELP = ("experiment configuration (TOML); every key has a default, see "
               "invflame.experiments.config for the sections and allowed values")


def add_parser(subparsers) -> None:
    """Register ``run``, ``simulate`` and ``plot``."""
    run = subparsers.add_parser(
        "run", help="reconstruct the fields of one configuration",
        description="Simulate the measurement of the configured ground truth, reconstruct it "
        "with the configured representation, regularizer and solver, and write the fields, "
        "history, metrics (summary.json), figures and a log into --out.")
    run.add_argument("config", type=Path, help=CONFIG_HELP)
    run.add_argument("--out", type=arguments.folder, default="results/run",
                     help="output folder (default results/run)")
    again = run.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true",
                       help="continue an interrupted run from its checkpoint, or a finished "
                       "one to a raised solver.iterations; refused if the configuration (but "
                       "for a higher solver.iterations), the truth, the measured data or the "
                       "code changed since, or if solver.iterations is below the iterations "
                       "done")
    again.add_argument("--overwrite", action="store_true",
                       help="replace the run in --out (its results are deleted once the new "
                       "run's inputs have loaded), or write into a folder holding other files; "
                       "without it, a folder that is neither new nor empty is refused")
    run.add_argument("--force", action="store_true",
                     help="with --resume: continue even if something changed, recording what "
                     "in log.txt and summary.json")
    run.add_argument("--quiet", action="store_true", help="no progress bars or log echo")
    run.set_defaults(func=run_command)

    simulate = subparsers.add_parser(
        "simulate", help="forward only: spectra and camera images of the ground truth",
        description="Compute the FTIR spectra of every pixel for the configured ground truth, "
        "as a run measures them (sections [data] and [noise]: by default on the truth's own "
        "grid with more sub-rays and a finer line-by-line step, plus NESR noise), and write "
        "them as a measurement file (NetCDF: radiance (camera, v, u, wavenumber) "
        "[W/(m2 sr cm-1)], wavenumbers [cm-1], cameras, instrument, noise, mask, each "
        "camera's own spectral window where the rig gives one, and provenance; "
        "see invflame.measurement_file; '[data] source' of 'invflame run' reads it) with a "
        "figure of one spectrum and the band-integrated camera images. --out FOLDER writes "
        "measurement.nc, spectra.npz and simulated.png into it; --out FILE.nc writes that "
        "file and FILE.png beside it.")
    simulate.add_argument("config", type=Path, help=CONFIG_HELP)
    simulate.add_argument("--out", type=simulation_output, default="results/simulate",
                          help="output folder, or a measurement file ending in .nc (default "
                          "results/simulate)")
    simulate.set_defaults(func=simulate_command)

    plot = subparsers.add_parser(
        "plot", help="figures of a finished run or comparison folder",
        description="Redraw the figures of a folder written by 'invflame run' (cutaways, loss "
        "curve, spectrum and image) or 'invflame reproduce' (all methods).")
    plot.add_argument("folder", type=Path, help="a run or reproduce output folder")
    plot.set_defaults(func=plot_command)


def simulation_output(text: str) -> Path:
    """``invflame simulate --out``: a measurement file ``*.nc`` (in a folder that can be
    written) or an output folder."""
    path = Path(text)
    if path.suffix == ".nc":
        if path.is_dir():
            raise argparse.ArgumentTypeError(f"{path} is a folder: give a file name ending in "
                                             ".nc or a folder without the suffix")
        arguments.folder(str(path.parent))
        return path
    return arguments.folder(text)


def run_command(args: argparse.Namespace) -> int:
    """``invflame run``."""
    from invflame.experiments import config as configuration
    from invflame.experiments.figures import comparison_figures
    from invflame.experiments.run_folder import check_run_target
    from invflame.experiments.runner import run_experiment
    from invflame.experiments.summaries import misfit_name

    if args.force and not args.resume:
        raise ConfigError("--force only applies to --resume (continue a changed run anyway): "
                          "add --resume, or drop --force")
    check_run_target(args.out, resume=args.resume, overwrite=args.overwrite)
    summary = run_experiment(configuration.load(args.config), args.out, resume=args.resume,
                             progress=not args.quiet, force=args.force)
    if summary.get("diverged"):  # the reason says what to do
        kept = "the start" if summary["iterations"] == 0 else "the iterate before"
        print(f"the solver stopped ({summary['stop_reason']}): the results hold {kept}")
    if "mse" in summary:  # scored against a ground truth
        comparison_figures(args.out, {"reconstruction": args.out})
        print(f"normalized MSE: {summary['mse']}; results in {args.out}")
    else:
        print(f"{misfit_name(summary['noisy_data'])} "
              f"{summary['chi2_per_measurement']['final']:.4g} (no ground truth); "
              f"results in {args.out}")
    return 0


def simulate_command(args: argparse.Namespace) -> int:
    """``invflame simulate``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from invflame.atomic_files import write_atomic, write_npz
    from invflame.experiments import config as configuration
    from invflame.experiments.runner import build_scene, load_truth, measure
    from invflame.measurement_file import MeasurementFile, write_measurement
    from invflame.plotting.spectra import plot_spectrum_and_images

    cfg = configuration.load(args.config)
    if cfg["data"]["source"]:
        raise ConfigError(f"{args.config}: 'data.source' names measured data; invflame simulate "
                          "makes data from the [truth]: remove 'data.source'")
    scene = build_scene(cfg)
    measurement = measure(cfg, scene, load_truth(cfg))
    spectra = measurement.data
    if args.out.suffix == ".nc":
        written = [args.out, args.out.with_suffix(".png")]
    else:
        written = [args.out / "measurement.nc", args.out / "simulated.png",
                   write_npz(args.out / "spectra.npz", radiance=spectra, sigma=measurement.sigma,
                             out_wavenumber=scene.out_wavenumber)]
    write_measurement(MeasurementFile(measurement, scene.rig, scene.out_wavenumber,
                                      scene.resolution, windows=scene.camera_windows),
                      written[0])
    fig = plot_spectrum_and_images(scene.out_wavenumber, spectra, None, scene.rig,
                                   channels=measurement.measured)
    write_atomic(written[1], lambda handle: fig.savefig(handle, format="png", dpi=130,
                                                        bbox_inches="tight"))
    plt.close(fig)
    print(f"{spectra.shape[0]} spectra of {spectra.shape[1]} points "
          f"({'noisy' if measurement.noisy else 'noise-free'}: {measurement.provenance}); wrote "
          + ", ".join(map(str, written)))
    return 0


def plot_command(args: argparse.Namespace) -> int:
    """``invflame plot``."""
    from invflame.experiments.figures import comparison_figures
    from invflame.experiments.reproduce import METHODS, folder_name
    from invflame.experiments.run_folder import finished_runs

    found = finished_runs(args.folder)
    if found == [args.folder]:
        runs = {"reconstruction": args.folder}
    else:
        runs = {m: args.folder / folder_name(m) for m in METHODS
                if args.folder / folder_name(m) in found}
    if not runs:
        raise FileNotFoundError(f"{args.folder} holds no comparison of 'invflame reproduce' "
                                f"(sub-folders {', '.join(folder_name(m) for m in METHODS)}): "
                                "give its output folder, or one run's")
    for path in comparison_figures(args.folder, runs):
        print(f"wrote {path}")
    return 0
