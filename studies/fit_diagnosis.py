"""Why a fit moves away from the truth: the split between temperature and products.

Usage: python studies/fit_diagnosis.py [--truth poolfire] [--method VG/NR] [--lambda 0]
       [--out results/fit_diagnosis]

On the quick honest scene (data rendered on the truth's own grid with 25 sub-rays and half
the line-by-line step, NESR 1e-3 W/(m²·sr·cm⁻¹)) it runs one voxel method three ways: the four
fields free from the band-tomography start as it comes; the state relation's progress and
temperature factor (:mod:`invflame.representations.state_relation`) from the same start; and
the state relation from the start calibrated to the spectra
(:mod:`invflame.experiments.calibration`). For the truth, each start and each fit it prints
the normalized MSE of T and CO2, the hot-volume ratio, the sum over voxels of CO2 + H2O and of
the temperature rise (relative to the truth's), and the median temperature factor h of the gas
holding over 1 % of products (the truth's own, from the relation's inverse): a fit that
matches the emission with too many products and too little heat per product shows as a
products sum above 1 with a temperature-rise sum near 1 and h below the truth's.
"""

import argparse
from pathlib import Path

import numpy as np

from invflame.experiments import reproduce, runner
from invflame.experiments.metrics import field_scores
from invflame.representations.state_relation import StateRelation


def describe(label: str, fields: np.ndarray, truth: np.ndarray, ambient) -> str:
    """One Markdown row: scores, sums relative to the truth's, median h of the gas."""
    scores = field_scores(truth, fields)
    relation = StateRelation(ambient, factor_range=(1e-3, 1e3))
    gas = fields[1] + fields[2] > 0.01
    factor = np.median(relation.invert(fields)[1][gas]) if gas.any() else float("nan")

    def total(f):
        return (f[1] + f[2]).sum(), (f[0] - ambient[0]).sum()

    products, rise = (a / b for a, b in zip(total(fields), total(truth), strict=True))
    return (f"| {label} | {scores['mse']['T']:.5f} | {scores['mse']['CO2']:.5f} | "
            f"{scores['hot_volume_ratio']:.2f} | {products:.2f} | {rise:.2f} | {factor:.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(prog="fit_diagnosis", description=__doc__.split("\n")[0])
    parser.add_argument("--truth", default="poolfire")
    parser.add_argument("--method", default="VG/NR",
                        choices=[m for m in reproduce.METHODS if m.startswith("VG")])
    parser.add_argument("--lambda", dest="lam", type=float, default=0.0)
    parser.add_argument("--out", type=Path, default=Path("results/fit_diagnosis"))
    args = parser.parse_args()
    cfg = reproduce.method_config("quick", args.method, 0, "honest", args.truth)
    cfg["regularizer"]["lambda"] = args.lam
    scene, native = runner.build_scene(cfg), runner.load_truth(cfg)
    truth = native.resample(scene.grid).values.astype(np.float64)
    measurement = runner.measure(cfg, scene, native)
    air = cfg["init"]["ambient"]
    print("| fields | MSE_T | MSE_CO2 | hot vol. | CO2 + H2O sum / truth's | T rise sum / "
          "truth's | median h |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    print(describe("truth", truth, truth, air), flush=True)
    starts = {}
    for calibrate in (False, True):
        cfg["init"]["calibrate"] = calibrate
        starts[calibrate] = runner.initial_fields(cfg, None, scene, measurement)
        print(describe(f"start, {'calibrated' if calibrate else 'band tomography'}",
                       starts[calibrate], truth, air), flush=True)
    for parameters, calibrate in (("fields", False), ("state-relation", False),
                                  ("state-relation", True)):
        cfg["representation"]["parameters"] = parameters
        label = f"{args.method} λ {args.lam:g}, {parameters}, from the " + (
            "calibrated start" if calibrate else "band tomography")
        folder = args.out / f"{parameters}_{'calibrated' if calibrate else 'raw'}"
        runner.run_experiment(cfg, folder, progress=False, measurement=measurement,
                              start=starts[calibrate])
        fields = np.load(folder / "reconstruction.npz")["values"].astype(np.float64)
        print(describe(label, fields, truth, air), flush=True)


if __name__ == "__main__":
    main()
