"""``invflame reproduce``: the study's six-way comparison with one command."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(subparsers) -> None:
    """Register ``invflame reproduce``."""
    from invflame.experiments.reproduce import METHODS, PRESETS

    parser = subparsers.add_parser(
        "reproduce", help="run the paper's comparison (voxel vs neural, NR/Tikhonov/TV)",
        description="Runs VG/NR, VG/Tikh., VG/TV, NN/NR, NN/Tikh. and NN/TV on the packaged "
        "OpenFOAM pool fire and writes into --out: one folder per method, the table "
        "(table.md, .csv, .json) next to the paper's Table 1, figures (cutaways with "
        "isotherms every 100 K, loss curves, spectrum and camera image) and logs.")
    parser.add_argument("--preset", choices=sorted(PRESETS), default="quick",
                        help="quick: 30^3 voxels, 16^2 px, 0.08 cm-1, ~10 min on 2 CPU cores "
                        "(default); paper: 60^3, 32^2 px, 0.04 cm-1, 2000 epochs")
    parser.add_argument("--out", type=Path, default=Path("results/reproduce"),
                        help="output folder (default results/reproduce)")
    parser.add_argument("--resume", action="store_true",
                        help="keep finished methods, continue interrupted ones")
    parser.add_argument("--methods", nargs="+", choices=list(METHODS), metavar="METHOD",
                        help=f"subset of the methods: {', '.join(METHODS)}")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the initialization noise (default 0)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars or log echo")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the comparison."""
    from invflame.experiments.reproduce import reproduce

    reproduce(args.preset, args.out, resume=args.resume, progress=not args.quiet,
              methods=args.methods, seed=args.seed)
    print(f"results in {args.out}")
    return 0
