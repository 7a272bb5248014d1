"""``invflame uncertainty``: error bars of a finished voxel run, σ per voxel and field.

See :mod:`invflame.experiments.uncertainty` and ``docs/uncertainty.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from invflame.cli.arguments import count, positive

TRUNCATION_NOTE = 0.1
"""A last kept eigenvalue's share d/(1 + d) above which the command says that σ is an upper
bound."""


def add_parser(subparsers) -> None:
    """Register ``invflame uncertainty``."""
    parser = subparsers.add_parser(
        "uncertainty", help="posterior standard deviation per voxel of a finished voxel run",
        description="Rebuild the problem of a finished voxel run from its folder (config.toml, "
        "data.npz, summary.json, checkpoint.npz) and compute the standard deviation of "
        "temperature and mole fractions per voxel from the linearized (Laplace) posterior: "
        "the Gauss-Newton Hessian of the noise-weighted misfit, low rank, plus the "
        "regularizer's Gaussian prior. Writes uncertainty.nc (sigma_T in K, sigma_X_* beside "
        "the fields), uncertainty.png (cutaways of sigma_T beside T) and uncertainty.json "
        "(settings, eigenvalues, cost; with a truth the share of voxels whose truth lies "
        "within 1 and 2 sigma, and uncertainty_z.png). A comparison folder gets every voxel "
        "run done.")
    parser.add_argument("folder", type=Path,
                        help="a finished run folder (holding summary.json), or a comparison "
                        "folder of runs")
    parser.add_argument("--rank", type=count, default=100,
                        help="eigenpairs of the prior-preconditioned misfit Hessian kept "
                        "(default 100); the cost is about (power iterations + 2) x (rank + "
                        "oversampling) Hessian products, each like one solver iteration")
    parser.add_argument("--oversampling", type=count, default=10,
                        help="extra random probes of the randomized eigendecomposition "
                        "(default 10)")
    parser.add_argument("--power-iterations", type=int, choices=range(6), default=1,
                        metavar="Q", help="subspace iterations, 0-5 (default 1)")
    parser.add_argument("--prior-std", type=positive, default=1.0,
                        help="standard deviation of the prior floor on every parameter, in "
                        "the parameters' units (default 1)")
    parser.add_argument("--seed", type=int, default=0, help="of the random probes (default 0)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``invflame uncertainty``."""
    from invflame.errors import ConfigError
    from invflame.experiments.run_folder import finished_runs
    from invflame.experiments.uncertainty import NETCDF, REPORT, run_uncertainty

    runs = finished_runs(args.folder)
    done = 0
    for folder in runs:
        try:
            report = run_uncertainty(folder, args.rank, args.oversampling,
                                     args.power_iterations, args.prior_std, args.seed,
                                     progress=not args.quiet)
        except ConfigError as err:
            if len(runs) == 1:
                raise
            print(f"invflame uncertainty: skipped {folder}: {err}", file=sys.stderr)
            continue
        done += 1
        median = report["sigma_T_K"]["q50"]
        print(f"wrote {folder / NETCDF}, {folder / REPORT} and figures: median sigma_T "
              f"{median:.3g} K, {report['seconds']:.1f} s")
        if report["truncation"] > TRUNCATION_NOTE:
            print(f"  the last eigenpair kept still removes {report['truncation']:.0%} of its "
                  "prior variance: the data inform more directions than --rank "
                  f"{args.rank}, and sigma is an upper bound (raise --rank to tighten it)")
        for label, shares in report.get("calibration", {}).get("T", {}).items():
            if shares["voxels"]:
                print(f"  T, {label} voxels ({shares['voxels']}): truth within 1 sigma "
                      f"{shares['within_1sigma']:.1%}, within 2 sigma "
                      f"{shares['within_2sigma']:.1%}")
    if not done:
        print(f"invflame uncertainty: error: no voxel run of {args.folder} could be done "
              "(see above)", file=sys.stderr)
        return 2
    return 0
