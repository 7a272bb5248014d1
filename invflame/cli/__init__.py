"""The ``invflame`` command line: one subcommand module per job.

Each module in :data:`COMMANDS` defines ``add_parser(subparsers)``, which registers its
subcommand and sets ``func`` (``run(args) -> int``) as the parser default.

Before a command runs, glibc's allocator is set to serve all threads from one arena and to keep
freed blocks, so that arrays freed by one thread are reused by the others without being mapped
afresh (:func:`invflame.process_memory.configure_malloc`).

Bad input (:class:`invflame.errors.InvflameError`, a damaged or missing file) ends the command
with its message on stderr and exit status 2, without a traceback; so does a file the system
refuses to write (a full disk, no permission, a read-only file system), named with the
system's reason. ``--debug`` shows the traceback.

Building the parser imports no array library: ``invflame --help``, ``invflame --version`` and
``invflame COMMAND --help`` answer at once. A command imports what it computes with (JAX,
torch, the operators) inside the function that runs it.
"""

from __future__ import annotations

import argparse
import errno
import sys

from invflame import __version__
from invflame.cli import (
    co2,
    config,
    demo,
    experiment,
    export,
    lines,
    phantom,
    reproduce,
    rig,
    sweep,
    uncertainty,
)
from invflame.errors import InvflameError
from invflame.process_memory import configure_malloc

COMMANDS = [reproduce, experiment, config, export, uncertainty, sweep, demo, phantom, lines, co2,
            rig]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="invflame",
        description="Hyperspectral infrared flame-emission tomography: simulate FTIR camera "
        "data of a flame and reconstruct its 3-D temperature and composition.",
    )
    parser.add_argument("--version", action="version", version=f"invflame {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the traceback of an error instead of its message only")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        module.add_parser(subparsers)
    return parser


def bad_input_errors() -> tuple[type[Exception], ...]:
    """The exceptions that :func:`main` reports as bad input: a message, exit status 2.

    :class:`solvers.atomic.CorruptFileError` (a damaged file) is imported here, when an error is
    being handled, since importing :mod:`solvers` imports JAX.
    """
    from solvers.atomic import CorruptFileError

    return (InvflameError, CorruptFileError, FileNotFoundError, NotADirectoryError,
            IsADirectoryError)


REFUSED = {errno.ENOSPC: "free space on its disk", errno.EDQUOT: "free space in your quota",
           errno.EACCES: "change its permissions", errno.EPERM: "change its permissions",
           errno.EROFS: "use a writable disk"}
"""System errors that refuse a file to this process (a full disk or quota, no permission, a
read-only file system) → what to do about it."""


def error_lines(err: Exception) -> list[str] | None:
    """The lines :func:`main` prints for ``err``: one per error of a configuration, one for
    other bad input (:func:`bad_input_errors`) or a file the system refused (:data:`REFUSED`,
    named with the system's reason); None for an error that is not the input's fault."""
    if isinstance(err, bad_input_errors()):
        return [str(message) for message in getattr(err, "messages", [err])]
    if isinstance(err, OSError) and err.errno in REFUSED:
        return [f"{err.filename or 'a file'}: {err.strerror}: {REFUSED[err.errno]}, or write "
                "elsewhere"]
    return None


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``invflame`` command; returns the process exit code (2 for bad
    input, whose message goes to stderr)."""
    args = build_parser().parse_args(argv)
    configure_malloc()  # long runs: memory that does not creep, no page faults (module notes)
    try:
        return int(args.func(args) or 0)
    except (*bad_input_errors(), OSError) as err:  # evaluated only when the command raised
        lines = error_lines(err)
        if args.debug or lines is None:
            raise
        for line in lines:
            print(f"invflame {args.command}: error: {line}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
