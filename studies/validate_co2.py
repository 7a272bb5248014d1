"""Print the validation of the generated 12C16O2 line list against the HITRAN slice.

Usage: python studies/validate_co2.py [--reference PATH] [--rows N]
(the same report as ``invflame co2 validate``).
"""

import argparse
import sys

from invflame.cli import co2

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="validate_co2")
    co2.add_parser(parser.add_subparsers(dest="command", required=True))
    sys.exit(co2.run(parser.parse_args(["co2", "validate", *sys.argv[1:]])))
