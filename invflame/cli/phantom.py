"""``invflame phantom``: ground-truth fields: convert OpenFOAM output, write, inspect, plot."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from invflame.cli import arguments

if TYPE_CHECKING:
    from invflame.field import Field


def _phantom_names() -> list[str]:
    """The registered phantoms' names, sorted."""
    from invflame.phantoms import PHANTOMS

    return sorted(PHANTOMS)


_SOURCE_HELP = ("a field .npz file or a phantom name (as 'invflame phantom write' takes); names "
                "build the default phantom on its default grid")


def add_parser(subparsers) -> None:
    """Register ``phantom from-openfoam``, ``phantom write``, ``phantom info``, ``phantom plot``."""
    parser = subparsers.add_parser(
        "phantom",
        help="ground-truth flames: OpenFOAM conversion, synthetic plume, figures",
        description="Build, convert, inspect and plot flame fields (T in K and mole fractions "
        "of CO2, H2O, CH4 on a voxel grid).",
    )
    sub = parser.add_subparsers(dest="phantom_command", required=True, metavar="ACTION")

    foam = sub.add_parser(
        "from-openfoam",
        help="convert one time of an OpenFOAM case to a field .npz",
        description="Read T and all species mass fractions of a reconstructed OpenFOAM case "
        "(ascii or binary) at one time, convert to mole fractions and map the cells onto the "
        "uniform box grid they form. Fails with a message for non-uniform meshes.",
    )
    foam.add_argument("case", type=Path, help="OpenFOAM case folder (reconstructed)")
    foam.add_argument("--time", required=True, help="simulated time to read, s (e.g. 0.9)")
    foam.add_argument("--out", type=Path, required=True, help="output field .npz (overwritten)")
    foam.set_defaults(func=run_from_openfoam)

    write = sub.add_parser(
        "write",
        help="write a named phantom, optionally on an n^3 pool-fire grid, to a .npz",
        description="Build a registered phantom and save it. --n resamples the pool fire or "
        "sets the synthetic plume's resolution on the pool-fire box (x, z in [-0.5, 0.5] m, "
        "y in [0, 1] m, y up).",
    )
    write.add_argument("name", choices=arguments.Choices(_phantom_names), metavar="NAME",
                       help="phantom name: %(choices)s")
    write.add_argument("--out", type=Path, required=True, help="output field .npz (overwritten)")
    write.add_argument("--n", type=arguments.count, default=None,
                       help="voxels per axis (default: native)")
    write.add_argument(
        "--seed", type=int, default=None, help="seed of the synthetic plume's perturbation"
    )
    write.add_argument(
        "--perturbation",
        type=arguments.amplitude,
        default=None,
        help="relative puffing/turbulence amplitude of the synthetic plume in [0, 1) "
        "(needs --seed; default 0, the smooth plume)",
    )
    write.add_argument(
        "--sheet-rise",
        type=arguments.positive,
        default=None,
        help="temperature rise in K of the synthetic plume's flame sheet (e.g. 1950, adiabatic "
        "methane-air): the gas holds that sheet's state part of the time and air otherwise, "
        "keeping McCaffrey's mean temperature (default: the mean flame rise itself)",
    )
    write.set_defaults(func=run_write)

    info = sub.add_parser(
        "info",
        help="print grid, min/max/mean of each field and the T > 500 K extent",
        description="Summarise a field file or named phantom, with its metadata.",
    )
    info.add_argument("source", help=_SOURCE_HELP)
    info.set_defaults(func=run_info)

    plot = sub.add_parser(
        "plot",
        help="PNG of mid-plane cutaways with isotherms (500-1500 K every 100 K)",
        description="One row per quantity (T, X_CO2, X_H2O, X_CH4), two vertical mid-planes "
        "per field, shared colour scales; several sources are shown side by side.",
    )
    plot.add_argument("sources", nargs="+", help=_SOURCE_HELP + "; several compare side by side")
    plot.add_argument("--out", type=Path, required=True, help="output PNG (overwritten)")
    plot.add_argument(
        "--labels", nargs="+", default=None, help="column titles, one per source (default: names)"
    )
    plot.set_defaults(func=run_plot)


def load_source(source: str) -> Field:
    """A field from a registered phantom name or a ``.npz`` path."""
    from invflame.field import Field
    from invflame.phantoms import PHANTOMS, make_phantom

    if source in PHANTOMS:
        return make_phantom(source)
    path = Path(source)
    if not path.is_file():
        raise SystemExit(
            f"error: {source!r} is neither a field file nor a phantom name "
            f"({', '.join(sorted(PHANTOMS))})"
        )
    return Field.load(path)


def run_from_openfoam(args: argparse.Namespace) -> int:
    """Convert and save; print the summary."""
    from invflame.openfoam import read_case

    field = read_case(args.case, args.time)
    field.save(args.out)
    print(field.summary())
    print(f"wrote {args.out}")
    return 0


def run_write(args: argparse.Namespace) -> int:
    """Build the phantom and save it; print the summary."""
    from invflame.geometry import VoxelGrid
    from invflame.phantoms import make_phantom

    kwargs = {}
    if args.n is not None:
        kwargs["grid"] = VoxelGrid.poolfire(args.n)
    if args.name == "synthetic":
        kwargs.update(seed=args.seed, perturbation=args.perturbation or 0.0,
                      sheet_rise=args.sheet_rise)
    elif args.seed is not None or args.perturbation is not None or args.sheet_rise is not None:
        raise SystemExit("error: --seed, --perturbation and --sheet-rise apply to 'synthetic', "
                         f"not {args.name}")
    try:
        field = make_phantom(args.name, **kwargs)
    except ValueError as err:  # a parameter out of its range: the message says which
        raise SystemExit(f"error: {err}") from None
    field.save(args.out)
    print(field.summary())
    print(f"wrote {args.out}")
    return 0


def run_info(args: argparse.Namespace) -> int:
    """Print the summary and metadata."""
    field = load_source(args.source)
    print(field.summary())
    for key, value in field.metadata.items():
        print(f"{key}: {value}")
    return 0


def run_plot(args: argparse.Namespace) -> int:
    """Write the cutaway figure."""
    import matplotlib.pyplot as plt

    from invflame.plotting.fields import plot_fields

    fields = [load_source(s) for s in args.sources]
    labels = args.labels if args.labels is not None else args.sources
    if len(labels) != len(fields):
        raise SystemExit(f"error: {len(labels)} labels for {len(fields)} sources")
    plt.close(plot_fields(fields, labels=labels, path=args.out))
    print(f"wrote {args.out}")
    return 0
