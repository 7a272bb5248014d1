"""The C allocator's handling of large arrays in a long-running process.

A reconstruction allocates and frees the same large arrays every epoch (spectra of all rays,
30 MB at the paper's size, and XLA's temporaries). glibc's ``malloc`` raises its threshold for
mapping a block directly each time such a block is freed, so that later ones come from its
heaps, which it rarely gives back: the resident memory of a process then creeps from epoch to
epoch. Measured with ``benchmarks/bench_memory.py --rays-per-pixel 1 --epochs 40`` (paper
configuration, voxel gradient epochs), three runs each on one machine: peaks of 879, 973 and
902 MiB with glibc's defaults, 808, 809 and 813 MiB with the threshold fixed at 8 MiB. The
price is the page faults of mapping those blocks afresh: with ``--epochs 20``, 0.76 and
0.80 s per epoch against 0.73 and 0.73 s with the defaults (``docs/performance.md``).
"""

from __future__ import annotations

import ctypes
import platform

__all__ = ["map_large_blocks"]

#: glibc's ``mallopt`` parameter for the direct-mapping threshold (``malloc.h``).
M_MMAP_THRESHOLD = -3


def map_large_blocks(threshold: int = 8 * 2**20) -> bool:
    """Have glibc's ``malloc`` map every block of ``threshold`` bytes or more directly and
    unmap it when freed, with the threshold fixed (not raised as blocks are freed).

    Called by the ``invflame`` command before it runs; affects the whole process.

    Parameters
    ----------
    threshold : int, optional
        Block size in bytes from which blocks are mapped directly (default 8 MiB; glibc
        allows up to 32 MiB on 64-bit systems).

    Returns
    -------
    bool
        True where glibc took the setting; False elsewhere (another C library or operating
        system), where nothing changes.
    """
    if platform.libc_ver()[0] != "glibc":
        return False
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return False
    return bool(mallopt(M_MMAP_THRESHOLD, int(threshold)))
