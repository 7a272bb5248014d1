"""Where the model error at the truth comes from: the reconstruction grid or the rays.

Usage: python studies/grid_model_error.py [--truth poolfire] [--method VG/Tikh.]

On the honest quick problem of one voxel method (its data: the truth on its own grid, 25
sub-rays per pixel, half the line-by-line step, noise) prints χ²/M of the data against the
model's prediction of

- the truth averaged onto the reconstruction grid (the study's model: its grid, sub-rays and
  step);
- the truth on a grid twice as fine per axis, with the reconstruction's sub-rays and step (the
  error of the rays and the step alone; a 60³ truth is then on its own grid);
- the averaged field copied onto the fine grid (the same field: a check, equal to the first);
- the averaged field interpolated trilinearly onto the fine grid between voxel centres.

and the radiance that prediction sums to over every pixel and wavenumber against the data's
(below 1: the field emits less than the flame that made the data).

χ²/M near 1 would mean the model fits the truth to the noise. A large first value that the
second removes says the grid, not the rays, makes the model error; if interpolation does
not lower it, what the coarse grid misses is structure inside its voxels (emission is
nonlinear in temperature: a voxel's mean state emits otherwise than its parts), not the
steps between them.
"""

import argparse

import numpy as np
from scipy.ndimage import map_coordinates

from invflame.experiments import config, runner
from invflame.experiments.method_problem import method_problem

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="grid_model_error")
    parser.add_argument("--truth", default="poolfire")
    parser.add_argument("--method", default="VG/Tikh.")
    args = parser.parse_args()
    setup = method_problem(args.method, args.truth)
    measurement = setup.measurement
    sigma = np.broadcast_to(measurement.sigma, measurement.data.shape)

    def chi2(prediction) -> float:
        return float(np.mean(((prediction - measurement.data) / sigma) ** 2))

    coarse = setup.truth
    cells = setup.scene.grid.shape
    fine_cfg = {k: dict(v) if isinstance(v, dict) else v for k, v in setup.cfg.items()}
    if fine_cfg["grid"]["cells"]:
        fine_cfg["grid"]["cells"] = [2 * n for n in cells]
    else:  # the grid from truth.grid on every axis
        fine_cfg["truth"]["grid"] = 2 * fine_cfg["truth"]["grid"]
    fine_cfg = config.validate(fine_cfg)
    fine = runner.build_scene(fine_cfg)
    native = runner.load_truth(fine_cfg)
    copied = coarse.repeat(2, axis=1).repeat(2, axis=2).repeat(2, axis=3)
    centres = np.meshgrid(*[(np.arange(2 * n) + 0.5) / 2 - 0.5 for n in cells], indexing="ij")
    interpolated = np.stack([map_coordinates(f, centres, order=1, mode="nearest")
                             for f in coarse])
    print(f"{args.method} on {args.truth}: χ²/M of the data against the model of")
    print("| field | model grid | χ²/M | radiance / data's |")
    print("|---|---|---:|---:|")
    for label, grid, scene, field in (
            ("the truth averaged onto the grid", cells, setup.scene, coarse),
            ("the truth averaged onto the fine grid", fine.grid.shape, fine,
             native.resample(fine.grid).values),
            ("the averaged truth copied onto the fine grid", fine.grid.shape, fine, copied),
            ("the averaged truth interpolated trilinearly", fine.grid.shape, fine,
             interpolated)):
        prediction = scene.simulate(field)
        print(f"| {label} | {'×'.join(map(str, grid))} | {chi2(prediction):.4g} | "
              f"{prediction.sum() / measurement.data.sum():.4f} |", flush=True)
