"""The C allocator of a benchmark's process: as the ``invflame`` command sets it, or glibc's
defaults for comparison (:func:`invflame.process_memory.configure_malloc`)."""

import argparse

from invflame.process_memory import configure_malloc


def add_argument(parser: argparse.ArgumentParser) -> None:
    """Register ``--default-allocator`` on a benchmark's command line."""
    parser.add_argument("--default-allocator", action="store_true",
                        help="leave glibc's malloc as it is (default: one arena for all "
                        "threads, freed blocks kept, as the invflame command sets it)")


def apply(default_allocator: bool) -> str:
    """Set the allocator unless ``default_allocator``; returns what the process runs with,
    in words, for the benchmark's output."""
    if default_allocator:
        return "glibc's defaults"
    if not configure_malloc():
        return "allocator unchanged (not glibc)"
    return "one malloc arena, freed blocks kept"
