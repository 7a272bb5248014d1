"""How much lineshape the model needs beyond a measured channel: the error of a cut window.

Usage: python studies/window_margin.py [--resolution 8] [--truth poolfire]

The instrument's lineshape (triangular apodization, sinc² tails, :mod:`operators.ils`) is cut
at the line-by-line window and renormalized. This prints, for channels 670-680 cm⁻¹ every
1 cm⁻¹ seen by the quick preset's four 16² cameras (one ray per pixel, the truth averaged onto
the 30³ grid), the largest difference from a window of 630-720 cm⁻¹ (the reference; itself
cut 5 resolutions away at 8 cm⁻¹) when the window reaches only ``margin`` resolutions beyond
the outermost channels: in units of the default NESR (1e-3 W/(m²·sr·cm⁻¹)) and of the peak
radiance. ``instrument.margin`` sets how far a run widens its window around a measurement
file's channels (:func:`invflame.experiments.inputs.widened_window`).
"""

import argparse
import copy

import numpy as np

from invflame.experiments import config, reproduce, runner
from invflame.experiments.inputs import absorption_table
from invflame.scene import Scene

CHANNELS = np.arange(670.0, 680.01, 1.0)
REFERENCE = (630.0, 720.0)
NESR = 1e-3

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="window_margin", description=__doc__.split("\n")[0])
    parser.add_argument("--resolution", type=float, default=8.0, help="cm⁻¹ (default 8)")
    parser.add_argument("--truth", default="poolfire")
    args = parser.parse_args()
    cfg = config.validate(reproduce.method_config("quick", "VG/NR", 0, "honest", args.truth))
    grid, rig = runner.build_scene(cfg).grid, runner.scene_rig(cfg)
    truth = runner.load_truth(cfg).resample(grid).values

    def spectra(low: float, high: float) -> np.ndarray:
        window = copy.deepcopy(cfg)
        window["spectrum"].update(min=low, max=high)
        scene = Scene(grid, rig, absorption_table(window, progress=False),
                      resolution=args.resolution, out_wavenumber=CHANNELS, rays_per_pixel=1)
        return scene.simulate(truth)

    reference = spectra(*REFERENCE)
    print(f"{args.truth}, resolution {args.resolution:g} cm-1, channels "
          f"{CHANNELS[0]:g}-{CHANNELS[-1]:g} cm-1, reference window "
          f"{REFERENCE[0]:g}-{REFERENCE[1]:g} cm-1")
    print("| margin (resolutions) | largest error / NESR | largest error / peak radiance |")
    print("|---:|---:|---:|")
    for margin in (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0):
        reach = margin * args.resolution
        error = np.abs(spectra(CHANNELS[0] - reach, CHANNELS[-1] + reach) - reference)
        print(f"| {margin:g} | {error.max() / NESR:.3g} | {error.max() / reference.max():.2g} |",
              flush=True)
