"""Time the ``invflame`` command's front door: ``--version``, ``--help`` and commands' help.

Run: ``python benchmarks/bench_cli.py [--repeats 5] [--target 1.0]``.

Each command runs in a fresh interpreter, started as the installed ``invflame`` script starts
(``from invflame.cli import main``), so the time includes starting Python and every import the
parser needs. Prints the best and median wall time in s of ``--repeats`` runs of each, the
largest peak resident memory of its runs in MB, and whether the best time meets ``--target``.
"""

import argparse
import os
import subprocess
import sys
import time

COMMANDS = {
    "invflame --version": ["--version"],
    "invflame --help": ["--help"],
    "invflame run --help": ["run", "--help"],
    "invflame reproduce --help": ["reproduce", "--help"],
    "invflame phantom write --help": ["phantom", "write", "--help"],
}
"""Label → arguments of the command."""

ENTRY = "import sys; from invflame.cli import main; sys.argv[0] = 'invflame'; sys.exit(main())"
"""What the ``invflame`` script runs."""


def run_once(arguments: list[str]) -> tuple[float, float]:
    """Wall time in s and peak resident memory in MB of one run of ``invflame arguments``."""
    start = time.perf_counter()
    child = subprocess.Popen([sys.executable, "-c", ENTRY, *arguments],
                             stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    elapsed = time.perf_counter() - start
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        raise RuntimeError(f"invflame {' '.join(arguments)} exited with {child.returncode}")
    return elapsed, usage.ru_maxrss / 1024  # ru_maxrss in KiB on Linux


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs of each command")
    parser.add_argument("--target", type=float, default=1.0, help="target wall time, s")
    args = parser.parse_args()
    print(f"best of {args.repeats} fresh runs, wall clock; target < {args.target:g} s")
    print(f"{'command':32s} {'best [s]':>9s} {'median [s]':>11s} {'peak RSS [MB]':>14s}  target")
    for label, arguments in COMMANDS.items():
        runs = [run_once(arguments) for _ in range(args.repeats)]
        times = sorted(wall for wall, _ in runs)
        memory = max(mb for _, mb in runs)
        met = "met" if times[0] < args.target else "missed"
        print(f"{label:32s} {times[0]:9.2f} {times[len(times) // 2]:11.2f} {memory:14.0f}  {met}")


if __name__ == "__main__":
    main()
