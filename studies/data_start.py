"""Score the data-driven start against ambient air on the quick configuration.

Usage: python studies/data_start.py [--phantom synthetic poolfire] [--rise 1500]
       [--snr 1000] [--measurement]

For each phantom: the scene of ``runner.build_scene`` (30³ voxels, 4 × 16² pixels with their
sub-rays, 650–725 cm⁻¹ at 0.08 cm⁻¹), data ``scene.simulate(truth)`` plus Gaussian noise of
``peak / snr``, or with ``--measurement`` the runner's default measurement (truth on its native
grid, more sub-rays, finer line-by-line step, NESR noise). Prints the normalized MSE per field,
the MSE inside the flame and the hot-volume ratio of ambient air and of
:func:`invflame.experiments.data_start.band_tomography_start`, the channels it dropped, its
smoothing weight and its time. The start assumes the phantoms' ambient air (300 K, no CO2 or
H2O).
"""

import argparse
import time

import numpy as np

from invflame.experiments import config, data_start, runner
from invflame.experiments.initialization import ambient
from invflame.experiments.metrics import flame_mse, hot_volume_ratio, normalized_mse

DRY_AIR = np.array([300.0, 0.0, 0.0, 0.0])


def scores(truth, fields) -> str:
    mse = normalized_mse(truth, fields)
    flame = flame_mse(truth, fields)
    return (f"MSE T {mse['T']:.4f} CO2 {mse['CO2']:.4f} H2O {mse['H2O']:.4f} | flame MSE_T "
            f"{flame.get('T', float('nan')):.4f} | hot-volume ratio "
            f"{hot_volume_ratio(truth, fields):.2f} | T max {fields[0].max():.0f} K")


def main() -> None:
    parser = argparse.ArgumentParser(prog="data_start")
    parser.add_argument("--phantom", nargs="+", default=["synthetic", "poolfire"])
    parser.add_argument("--rise", type=float, default=data_start.DEFAULT_TEMPERATURE_RISE_ST)
    parser.add_argument("--snr", type=float, default=1000.0)
    parser.add_argument("--measurement", action="store_true")
    args = parser.parse_args()
    for phantom in args.phantom:
        cfg = config.validate({"truth": {"grid": 30, "source": phantom}, "rig": {"pixels": 16},
                               "spectrum": {"step": 0.08}})
        scene = runner.build_scene(cfg)
        truth = runner.load_truth(cfg, scene.grid).values.astype(np.float64)
        if args.measurement:
            measurement = runner.measure(cfg, scene, runner.load_truth(cfg))
            data, sigma = measurement.data, measurement.sigma
        else:
            clean = np.asarray(scene.simulate(truth), np.float64)
            sigma = np.abs(clean).max() / args.snr
            data = clean + sigma * np.random.default_rng(0).standard_normal(clean.shape)
        start_time = time.perf_counter()
        start = data_start.band_tomography_start(scene, data, sigma, args.rise,
                                                 ambient=DRY_AIR)
        seconds = time.perf_counter() - start_time
        print(f"{phantom} ({scene.n_rays} pixels x {scene.rays_per_pixel} sub-rays, "
              f"{'measurement' if args.measurement else f'peak SNR {args.snr:g}'})")
        print(f"  ambient air : {scores(truth, ambient(scene.grid.shape))}")
        print(f"  data start  : {scores(truth, start)}  [{seconds:.0f} s]")


if __name__ == "__main__":
    main()
