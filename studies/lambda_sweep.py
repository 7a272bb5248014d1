"""Sweep the regularizer weight λ of one honest-protocol method and print what each rule picks.

Usage: python studies/lambda_sweep.py [--truth synthetic] [--method VG/TV]
       [--lambdas 3 10 30 100] [--model-error 6] [--tv-smoothing 0.1]
       [--parameters fields] [--no-calibrate] [--set SECTION.KEY=VALUE ...]
       [--out results/lambda_sweep]

Runs the method of ``invflame study --preset quick`` (same data, start, solver and stopping
rule; one measurement and one start shared by all λ) once per λ, then prints per λ the
noise-weighted misfit χ²/M (for a network, trained on a stochastic objective, that of its
final rendering of all pixels), the regularizer Φ (not recorded for a network: nan), the
normalized MSE of T over the domain and the
flame and the hot-volume ratio, and which λ the discrepancy principle (τ = 1, and with
``--model-error`` τ = 1 + the model error of prior flames) and the L-curve pick from those same
points, beside the best one against the truth. Choose λ on one truth and
report on another.
"""

import argparse
import csv
import json
import math
import warnings
from pathlib import Path

import solvers
from invflame.experiments import config, reproduce, runner
from invflame.experiments.config_text import parse_setting
from invflame.experiments.model_error import estimate_model_error

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="lambda_sweep")
    parser.add_argument("--truth", default="synthetic")
    parser.add_argument("--method", default="VG/TV", choices=list(reproduce.METHODS))
    parser.add_argument("--lambdas", type=float, nargs="+", default=[3.0, 10.0, 30.0, 100.0])
    parser.add_argument("--out", type=Path, default=Path("results/lambda_sweep"))
    parser.add_argument("--model-error", type=int, default=0, metavar="N",
                        help="also estimate the model error from N prior flames and print the "
                             "discrepancy principle's pick with tau = 1 + that error")
    parser.add_argument("--resolved", action="store_true",
                        help="make the data from the truth averaged onto the reconstruction grid "
                             "(as at the paper's size, where the truth's grid is the "
                             "reconstruction's): model error of sub-rays and step only")
    parser.add_argument("--tv-smoothing", type=float, default=0.0, metavar="EPS",
                        help="Huber smoothing of TV in 1/m (regularizer.tv_smoothing; 0: exact)")
    parser.add_argument("--parameters", choices=("state-relation", "fields"),
                        default="state-relation",
                        help="representation.parameters: the unknowns of each point")
    parser.add_argument("--no-calibrate", action="store_true",
                        help="init.calibrate = false: the band tomography as it comes")
    parser.add_argument("--set", nargs="+", default=[], metavar="SECTION.KEY=VALUE",
                        help="other settings of the method's configuration (VALUE in TOML)")
    args = parser.parse_args()
    cfg = reproduce.method_config("quick", args.method, 0, "honest", args.truth)
    for setting in args.set:
        try:
            section, key, value = parse_setting(setting)
        except ValueError as error:
            parser.error(f"--set: {error}")
        cfg[section][key] = value
    cfg["regularizer"]["tv_smoothing"] = args.tv_smoothing
    cfg["representation"]["parameters"] = args.parameters
    cfg["init"]["calibrate"] = not args.no_calibrate
    cfg = config.validate(cfg)  # a misspelt --set key or a bad value is named here
    scene, native = runner.build_scene(cfg), runner.load_truth(cfg)
    if args.resolved:
        native = native.resample(scene.grid)
    measurement = runner.measure(cfg, scene, native)
    start = runner.initial_fields(cfg, native.resample(scene.grid), scene, measurement)
    m = measurement.n_measurements
    points = []
    print("| λ | χ²/M | Φ | MSE_T | flame MSE_T | hot-volume ratio | iterations | gain | "
          "MSE_CO2 (start) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for lam in sorted(args.lambdas):
        trial = json.loads(json.dumps(cfg))
        trial["regularizer"]["lambda"] = lam
        folder = args.out / f"lambda_{lam:g}"
        summary = runner.run_experiment(trial, folder, progress=False, measurement=measurement,
                                        start=start)
        with open(folder / "history.csv") as handle:
            last = list(csv.DictReader(handle))[-1]
        chi2, phi = float(last["misfit"]), float(last["regularizer"])
        if not math.isfinite(chi2):  # a stochastic objective (networks) records no misfit
            chi2 = summary["chi2_per_measurement"]["final"] * m
        points.append((lam, chi2, phi, summary["mse"]["T"]))
        print(f"| {lam:g} | {chi2 / m:.4g} | {phi:.4g} | {summary['mse']['T']:.5f} | "
              f"{summary['mse_flame']['T']:.4f} | {summary['hot_volume_ratio']:.2f} | "
              f"{summary['iterations']} | {summary['mse_initial']['T'] / summary['mse']['T']:.2f}"
              f" | {summary['mse']['CO2']:.5f} ({summary['mse_initial']['CO2']:.5f}) |",
              flush=True)
    lams, chi2, phi, mse = zip(*points, strict=True)
    best = lams[mse.index(min(mse))]
    print(f"best against the truth: λ = {best:g}")

    def pick(tau):
        passing = [lam for lam, c in zip(lams, chi2, strict=True) if c <= tau * m]
        return (f"λ = {max(passing):g}" if passing else
                f"λ = {lams[chi2.index(min(chi2))]:g} (no λ reaches χ² <= τM: smallest misfit)")

    print(f"discrepancy principle (τ = 1): {pick(1.0)}")
    if args.model_error:
        error = estimate_model_error(cfg, scene, measurement, n_flames=args.model_error,
                                     seed=cfg["seed"], log=print)
        print(f"discrepancy principle (τ = 1 + model error = {error.tau:.4g}): "
              f"{pick(error.tau)}")
    if len(lams) >= 4:
        with warnings.catch_warnings(record=True):
            warnings.simplefilter("always")
            try:
                corner = solvers.l_curve(lams, chi2, phi, n_measurements=m)
            except ValueError as error:  # e.g. too few distinct points
                print(f"L-curve: none ({error})")
            else:
                print(f"L-curve: λ = {corner.lam:g} ({corner.message})")
