"""Draw the example field figures of docs/figures.md from the packaged pool fire.

The rows other than the truth are cheap STAND-INS for reconstructions, made from the truth
itself without any data: the truth + 20 % noise (the paper's start) and the truth smoothed by
Gaussians of 1 and 2 voxels. They show what the figures look like, not how well any method
reconstructs the flame (for that, run ``invflame study``). Run from the repository root:

    .venv/bin/python scripts/example_figures.py [--grid 30] [--out docs/figures]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from invflame.experiments.figures import field_figures
from invflame.experiments.initialization import noisy_truth
from invflame.experiments.metrics import smoothed
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.phantoms import poolfire


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=30, help="voxels per axis (default 30)")
    parser.add_argument("--out", type=Path, default=Path("docs/figures"),
                        help="output folder (default docs/figures)")
    args = parser.parse_args()
    truth = poolfire(VoxelGrid.poolfire(args.grid))
    stand_ins = {
        "stand-in start:\ntruth + 20 % noise": noisy_truth(truth.values, 0.2, seed=0),
        "stand-in: truth\nsmoothed σ = 1 voxel": smoothed(truth.values, 1.0),
        "stand-in: truth\nsmoothed σ = 2 voxels": smoothed(truth.values, 2.0),
    }
    estimates = {label: Field(truth.grid, values) for label, values in stand_ins.items()}
    scratch = args.out / "stand-in"
    for path in field_figures(scratch, truth, estimates):
        target = args.out / f"example_standin_{path.name}"
        path.replace(target)
        print(f"wrote {target}")
    scratch.rmdir()


if __name__ == "__main__":
    main()
