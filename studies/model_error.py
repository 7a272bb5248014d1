"""Print how far the reconstruction model is from the model that made the data (no inverse crime).

Usage: python studies/model_error.py [--truth poolfire|synthetic]

On the quick preset's reconstruction scene (30³ voxels, 4 × 16² pixels × 9 sub-rays, 0.08 cm⁻¹)
and the honest protocol's synthesis (the truth on its own 60³ grid, 25 sub-rays, 0.04 cm⁻¹),
prints the RMS difference of the noise-free spectra, W/(m²·sr·cm⁻¹), for each ingredient alone
and all together, beside the NESR, and χ²/M of the truth averaged onto the reconstruction grid
against noisy data.
"""

import argparse

import numpy as np

from invflame.experiments import reproduce, runner
from invflame.experiments.measurement import synthesis_scene

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="model_error")
    parser.add_argument("--truth", default="poolfire")
    args = parser.parse_args()
    cfg = reproduce.method_config("quick", "VG/NR", 0, "honest", args.truth)
    scene, native = runner.build_scene(cfg), runner.load_truth(cfg)
    truth = native.resample(scene.grid)
    model = scene.simulate(truth.values)
    fine = runner.absorption_table(cfg, cfg["spectrum"]["step"] / cfg["data"]["step_divisor"])
    rays = cfg["data"]["rays_per_pixel"]
    cases = {"grid (truth on its own grid)": (native, scene.table, scene.rays_per_pixel),
             "line-by-line step": (truth, fine, scene.rays_per_pixel),
             "sub-rays": (truth, scene.table, rays),
             "all of it": (native, fine, rays)}

    def rms(values):
        return float(np.sqrt(np.mean(np.square(values, dtype=np.float64))))

    print("| data made with | RMS difference [W/(m2 sr cm-1)] |")
    print("|---|---:|")
    for name, (field, table, per_pixel) in cases.items():
        data = synthesis_scene(scene, field, table, per_pixel).simulate(field.values)
        print(f"| {name} | {rms(data - model):.3g} |", flush=True)
    print(f"| noise (NESR) | {cfg['noise']['nesr']:g} |")
    measurement = runner.measure(cfg, scene, native)
    print(f"chi2/M of the truth on the reconstruction grid: "
          f"{runner.chi2_per_value(model, measurement):.4g}")
