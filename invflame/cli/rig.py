"""``invflame rig plot``: a camera rig and the voxel grid in 3-D.

A rig is a TOML file of cameras or a packaged preset (:mod:`invflame.geometry.rig_file`).
"""

from __future__ import annotations

import argparse

from invflame.cli import arguments


def add_parser(subparsers) -> None:
    """Register ``invflame rig plot``."""
    parser = subparsers.add_parser(
        "rig", help="camera rigs: draw one with the grid",
        description="Camera rigs from TOML files (see invflame.geometry.rig_file).")
    commands = parser.add_subparsers(dest="rig_command", required=True, metavar="COMMAND")
    plot = commands.add_parser(
        "plot", help="draw cameras, frusta and the grid in 3-D (PNG)",
        description="Draw each camera's pinhole (with its index), optical axis and viewing "
        "frustum, and the voxel grid's box and cells, in metres; then check the rig against "
        "the grid (a camera inside it, looking away from it or seeing no voxel is an error "
        "naming the camera, exit status 2, after the figure is written).")
    plot.add_argument("rig", help="rig file (TOML) or preset name ('paper')")
    plot.add_argument("--grid", type=arguments.count, default=30,
                      help="voxels per axis (default 30)")
    plot.add_argument("--lower", type=float, nargs=3, default=(-0.5, 0.0, -0.5),
                      metavar=("X", "Y", "Z"),
                      help="lower corner of the grid in m (default: the pool fire's -0.5 0 -0.5)")
    plot.add_argument("--upper", type=float, nargs=3, default=(0.5, 1.0, 0.5),
                      metavar=("X", "Y", "Z"),
                      help="upper corner of the grid in m (default: the pool fire's 0.5 1 0.5)")
    plot.add_argument("--out", type=arguments.png, default="rig.png",
                      help="output image (default rig.png)")
    plot.set_defaults(func=plot_command)


def plot_command(args: argparse.Namespace) -> int:
    """``invflame rig plot``."""
    import matplotlib.pyplot as plt

    from invflame.errors import GeometryError
    from invflame.geometry import VoxelGrid
    from invflame.geometry.rig_file import check_rig_sees_grid, read_rig
    from invflame.plotting.rig import plot_rig

    spec = read_rig(args.rig)
    try:
        grid = VoxelGrid(args.lower, args.upper, (args.grid,) * 3)
    except ValueError as err:
        raise GeometryError(f"--lower/--upper: {err}") from err
    plt.close(plot_rig(spec.rig, grid, args.out, title=f"{args.rig}: {spec.rig.n_cameras} "
                       f"cameras, grid {args.grid}^3"))
    print(f"wrote {args.out}")
    check_rig_sees_grid(spec.rig, grid)
    return 0
