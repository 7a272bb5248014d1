"""How the cameras' viewing axes shape a reconstruction: the paper's rig against one as large
on more axes.

Usage: python studies/view_axes.py [--truth synthetic] [--lam 30] [--out results/view_axes]

Runs VG/TV of ``invflame study --preset quick`` (honest protocol: data rendered from the truth
on its own grid with 25 sub-rays and half the line-by-line step, NESR noise, band-tomography
start, L-BFGS) at a fixed λ twice: with the paper's four cameras, which look along two
horizontal axes (+x, −x, +z, −z: opposite cameras see the same line integrals), and with four
cameras of the same pixels at azimuths 0°, 45°, 90° and 135°, on four axes. Prints per rig the
coverage, χ²/M, MSE_T (domain and flame), the hot-volume ratio (volume above 500 K over the
truth's) of the start and of the result, and the flat-air baseline; writes
``cross_sections.png`` (T across the flame at three heights: truth, each start, each result).
"""

import argparse
import copy
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from invflame.experiments import config, reproduce, runner  # noqa: E402
from invflame.experiments.initialization import ambient  # noqa: E402
from invflame.experiments.metrics import field_scores  # noqa: E402
from invflame.field import Field  # noqa: E402
from invflame.geometry import ring_rig  # noqa: E402
from invflame.geometry.rig import PAPER_AZIMUTHS  # noqa: E402
from invflame.geometry.rig_file import rig_records  # noqa: E402

AZIMUTHS = {"paper rig: 2 axes": PAPER_AZIMUTHS, "4 axes": (0.0, 45.0, 90.0, 135.0)}
"""Camera azimuths in degrees (:func:`invflame.geometry.ring_rig`) per rig."""


def main():
    parser = argparse.ArgumentParser(prog="view_axes", description=__doc__.splitlines()[0])
    parser.add_argument("--truth", default="synthetic")
    parser.add_argument("--lam", type=float, default=30.0,
                        help="fixed TV weight (chi2 scaling); default: the honest protocol's "
                             "neural TV weight, chosen on the synthetic plume")
    parser.add_argument("--out", type=Path, default=Path("results/view_axes"))
    args = parser.parse_args()
    base = reproduce.method_config("quick", "VG/TV", 0, "honest", args.truth)
    grid = runner.build_scene(base).grid
    truth = runner.load_truth(base).resample(grid)
    air = field_scores(truth.values, ambient(grid.shape, base["init"]["ambient"]))
    print(f"truth {args.truth}, λ = {args.lam:g}; flat ambient air: MSE_T {air['mse']['T']:.5f}")
    print("| rig | voxels crossed | χ²/M | MSE_T | flame MSE_T | hot vol. | start MSE_T | "
          "start hot vol. |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    shown = {"truth": truth.values[0]}
    for label, azimuths in AZIMUTHS.items():
        cfg = copy.deepcopy(base)
        rig = base["rig"]
        cfg["rig"]["cameras"] = rig_records(ring_rig(grid, azimuths, rig["distance"],
                                                     rig["pixels"], rig["focal_length"]))
        cfg["regularizer"]["lambda"] = args.lam
        cfg = config.validate(cfg)
        folder = args.out / label.split(":")[0].replace(" ", "_")
        s = runner.run_experiment(cfg, folder, progress=False)
        print(f"| {label} | {s['coverage']['voxels']:.2%} | "
              f"{s['chi2_per_measurement']['final']:.3g} | {s['mse']['T']:.5f} | "
              f"{s['mse_flame']['T']:.4f} | {s['hot_volume_ratio']:.2f} | "
              f"{s['mse_initial']['T']:.5f} | {s['hot_volume_ratio_initial']:.2f} |", flush=True)
        shown[f"start, {label}"] = Field.load(folder / "initial.npz").values[0]
        shown[f"VG/TV, {label}"] = Field.load(folder / "reconstruction.npz").values[0]
    plot_cross_sections(shown, grid, args.out / "cross_sections.png")
    print(f"wrote {args.out / 'cross_sections.png'}")


def plot_cross_sections(temperatures: dict, grid, path: Path) -> None:
    """T (K) on horizontal planes through the truth's flame, cropped to it: one row per field,
    one column per height (a quarter, half and three quarters of the way up its hot region),
    one pixel per voxel."""
    up = grid.up_axis
    horizontal = tuple(a for a in range(3) if a != up)
    hot = np.flatnonzero((temperatures["truth"] > 500).any(axis=horizontal))
    layers = [int(hot[0] + f * (hot[-1] - hot[0])) for f in (0.25, 0.5, 0.75)]
    # crop to the flame: where any field is above 400 K, and three voxels around it
    warm = np.any([t > 400 for t in temperatures.values()], axis=0).any(axis=up)
    crop = tuple(slice(max(int(i.min()) - 3, 0), int(i.max()) + 4) for i in np.nonzero(warm))
    fig, axes = plt.subplots(len(temperatures), len(layers), figsize=(2.6 * len(layers),
                             2.3 * len(temperatures)), squeeze=False, constrained_layout=True)
    top = max(float(t.max()) for t in temperatures.values())
    for row, (name, temperature) in zip(axes, temperatures.items(), strict=True):
        for ax, layer in zip(row, layers, strict=True):
            plane = np.take(temperature, layer, axis=up)[crop].T
            image = ax.imshow(plane, origin="lower", vmin=300, vmax=top, cmap="inferno")
            ax.contour(plane, levels=[500], colors="cyan", linewidths=0.8)
            ax.contour(np.take(temperatures["truth"], layer, axis=up)[crop].T, levels=[500],
                       colors="white", linewidths=0.8, linestyles="--")
            ax.set_xticks([])
            ax.set_yticks([])
            height = grid.lower[up] + (layer + 0.5) * grid.spacing[up]
            ax.set_title(f"{name}\nat {height:.2f} m" if layer == layers[0] else
                         f"at {height:.2f} m", fontsize=8)
    fig.colorbar(image, ax=axes, shrink=0.6, label="T [K] (cyan: 500 K; dashed: truth's)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
