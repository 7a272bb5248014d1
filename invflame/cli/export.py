"""``invflame export``: a finished run's fields as VTK image data (ParaView) or NetCDF (xarray).

Runs write these files themselves; the command writes them for a folder made before they did,
or again. See :mod:`invflame.export` and ``docs/paraview.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(subparsers) -> None:
    """Register ``invflame export``."""
    parser = subparsers.add_parser(
        "export", help="write a run's truth, start and reconstruction for ParaView or xarray",
        description="Write the ground truth (when the run has one), the start and the "
        "reconstruction of a finished run folder as VTK image data (truth.vti, start.vti, "
        "reconstruction.vti: cell arrays 'T [K]', 'X_CO2 [1]', 'X_H2O [1]', 'X_CH4 [1]', origin "
        "and spacing in m) and/or one CF-style NetCDF file (fields.nc: variables truth_T, "
        "start_X_CO2, ... on voxel-centre coordinates x, y, z in m, with the run's "
        "configuration and protocol as global attributes). A comparison folder ('invflame "
        "study' / 'reproduce') gets every method's run exported.")
    parser.add_argument("folder", type=Path,
                        help="a run folder (holding reconstruction.npz) or a comparison folder")
    parser.add_argument("--format", choices=("vti", "netcdf", "all"), default="all",
                        help="vti: one .vti per field set; netcdf: fields.nc; all: both "
                        "(default)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``invflame export``."""
    from invflame.experiments.run_folder import finished_runs
    from invflame.export import FIELD_SETS, FORMATS, export_run

    formats = FORMATS if args.format == "all" else (args.format,)
    for folder in finished_runs(args.folder, FIELD_SETS["reconstruction"]):
        for path in export_run(folder, formats):
            print(f"wrote {path}")
    return 0
