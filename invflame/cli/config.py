"""``invflame config``: the configuration keys with their defaults, units and meanings, or a
file checked and completed.

Everything comes from :data:`invflame.experiments.config.SCHEMA`; see
``docs/guide/configuration.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(subparsers) -> None:
    """Register ``invflame config``."""
    parser = subparsers.add_parser(
        "config", help="print the default configuration with a comment per key, or check one",
        description="Print a configuration as TOML with a comment per key (its unit, meaning "
        "and allowed values). --show-defaults prints the defaults: save it, delete what you do "
        "not change, and edit the rest. CONFIG.toml is checked like 'invflame run' checks it "
        "and printed complete, every default filled in.")
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("config", type=Path, nargs="?", metavar="CONFIG.toml",
                      help="a configuration to check and print complete")
    what.add_argument("--show-defaults", action="store_true",
                      help="print the default configuration")
    what.add_argument("--markdown", action="store_true",
                      help="print the keys as Markdown tables (key, default, unit, allowed, "
                      "meaning), as in docs/guide/configuration.md")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``invflame config``."""
    from invflame.experiments import config as configuration

    if args.markdown:
        print(configuration.keys_markdown(), end="")
    elif args.show_defaults:
        print(configuration.dumps_commented(), end="")
    else:
        print(configuration.dumps_commented(configuration.load(args.config)), end="")
    return 0
