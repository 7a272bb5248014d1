"""Print why the start matters: the objective's gradient at ambient air, the data start, the truth.

Usage: python studies/start_gradient.py [--truth synthetic|poolfire]

On the honest protocol's quick-size data (truth on its native grid, 25 sub-rays per pixel, half
the line-by-line step, NESR noise) and the voxel problem without regularizer, prints χ²/M and
the norm of the gradient of the noise-weighted objective (per measured value) with respect to
the normalized temperature, CO2 and H2O, and of the temperature part over the truth's voxels
above 500 K, at three points: uniform ambient air, the band-tomography start, the truth.
"""

import argparse

import numpy as np

from invflame.experiments import reproduce, runner
from invflame.experiments.initialization import ambient

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="start_gradient")
    parser.add_argument("--truth", default="synthetic")
    args = parser.parse_args()
    cfg = reproduce.method_config("quick", "VG/NR", 0, "honest", args.truth)
    scene = runner.build_scene(cfg)
    native = runner.load_truth(cfg)
    truth = native.resample(scene.grid).values
    measurement = runner.measure(cfg, scene, native)
    start = runner.initial_fields(cfg, native.resample(scene.grid), scene, measurement)
    representation = runner.make_representation(cfg, scene)
    problem = representation.problem(measurement.data, sigma=measurement.sigma)
    m, hot = measurement.n_measurements, truth[0].ravel() > 500.0
    print("| point | chi2/M | grad T | grad CO2 | grad H2O | grad T, T > 500 K |")
    print("|---|---:|---:|---:|---:|---:|")
    points = {"ambient air": ambient(scene.grid.shape, cfg["init"]["ambient"]),
              "band-tomography start": start, "truth": truth}
    for name, fields in points.items():
        evaluation = problem.evaluate(representation.initial_parameters(fields))
        grad = np.asarray(evaluation.grad).reshape(4, -1) / m
        print(f"| {name} | {evaluation.misfit / m:.4g} | {np.linalg.norm(grad[0]):.3g} | "
              f"{np.linalg.norm(grad[1]):.3g} | {np.linalg.norm(grad[2]):.3g} | "
              f"{np.linalg.norm(grad[0][hot]):.3g} |", flush=True)
