"""The ``invflame`` command line: one subcommand module per job.

Each module in :data:`COMMANDS` defines ``add_parser(subparsers)``, which registers its
subcommand and sets ``func`` (``run(args) -> int``) as the parser default.
"""

from __future__ import annotations

import argparse
import sys

from invflame import __version__
from invflame.cli import co2, demo, experiment, lines, phantom, reproduce, sweep

COMMANDS = [reproduce, experiment, sweep, demo, phantom, lines, co2]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="invflame",
        description="Hyperspectral infrared flame-emission tomography: simulate FTIR camera "
        "data of a flame and reconstruct its 3-D temperature and composition.",
    )
    parser.add_argument("--version", action="version", version=f"invflame {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        module.add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``invflame`` command; returns the process exit code."""
    args = build_parser().parse_args(argv)
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
