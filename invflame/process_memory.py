"""The C allocator's handling of large arrays in a long-running process.

A reconstruction allocates and frees the same large arrays every iteration: the spectra of all
rays (30 MB at the paper's size), XLA's temporaries, and for a neural field the networks'
activations (16 MB per layer for a batch of 1024 rays × 64 samples). Two of glibc's defaults
cost such a process memory or time:

- ``malloc`` gives each thread that allocates its own arena, up to eight per core; the threads
  of XLA, Numba and torch each keep freed blocks in theirs, so the resident memory of a process
  holds several arenas' free blocks and creeps from epoch to epoch. With one arena for the
  whole process every thread reuses the same freed blocks.
- A block above the mapping threshold (at most 32 MiB) is mapped from the kernel when allocated
  and unmapped when freed, and the top of the heap is returned to the kernel once 128 KiB of it
  is free; either way the next block of that size is mapped afresh, and every page of it costs
  a page fault when first written (8887 per forward evaluation at the paper's size, where XLA
  copies the 30 MB of spectra the kernel returns into a temporary block of 35 MB). With no block
  mapped and none returned, freed blocks are reused as they are.

Measured at the paper's size on a 2-core machine (``docs/performance.md``, "The allocator" and
"Freed blocks kept"): one arena took a voxel reconstruction's peak from 857–889 to 750–753 MiB
(``benchmarks/bench_memory.py --rays-per-pixel 1 --epochs 40``) and a neural field's from
1389–1401 to 1291–1311 MB (``benchmarks/bench_paper_epoch.py --method NN/TV --epochs 10``), at
the same speed. Keeping the freed blocks as well, against one arena alone: a voxel forward
evaluation 133–137 ms against 146–148 ms (2 and 1271 page faults per evaluation against 8887),
its forward and gradient 353–356 ms against 395–413 ms (548 and 2 page faults against
28 865–34 427; a one-off script, best of 7, two runs of each, alternating);
``bench_memory.py`` as above, three runs of each, alternating: 0.36–0.40 s per epoch against
0.39–0.43 s, and a peak of 772–821 MiB against 751–755 MiB (784 MiB after 200 epochs): what the
process has freed it keeps, in pieces the next arrays do not always fit.

An earlier setting, mapping every block of 8 MiB or more and unmapping it when freed, bounded
the peak too (816 and 792 MiB; 1209 and 1208 MB) but paid for those page faults: 0.52 and
0.51 s per voxel epoch against 0.47 s, 2.23 s per neural-field epoch against 1.79–1.85 s.
"""

from __future__ import annotations

import ctypes
import platform

__all__ = ["configure_malloc"]

#: glibc's ``mallopt`` parameters (``malloc.h``): the free memory at the top of the heap above
#: which it is returned to the kernel (-1: never), the most blocks mapped at once (0: none),
#: the largest number of arenas.
M_TRIM_THRESHOLD, M_MMAP_MAX, M_ARENA_MAX = -1, -4, -8


def configure_malloc(arenas: int = 1, keep_freed: bool = True) -> bool:
    """Have glibc's ``malloc`` serve every thread of the process from at most ``arenas``
    arenas, and keep the blocks freed for reuse instead of mapping and unmapping them.

    Called by the ``invflame`` command before it runs, after its imports and before the
    numerical libraries start their worker threads (the imports start two helper threads,
    which keep the arenas they first allocated from); affects the whole process. With
    ``keep_freed`` the process's resident memory does not fall after its peak: what it frees is
    held for the next iteration's arrays (module notes).

    Parameters
    ----------
    arenas : int, optional
        Largest number of arenas, at least 1 (default 1).
    keep_freed : bool, optional
        Serve every block from the heap (none mapped on its own) and never return the heap's
        free top to the kernel (default True).

    Returns
    -------
    bool
        True where glibc took the settings; False elsewhere (another C library or operating
        system), where nothing changes.

    Raises
    ------
    ValueError
        If ``arenas`` is less than 1.
    """
    if int(arenas) < 1:
        raise ValueError(f"arenas must be at least 1, got {arenas}")
    if platform.libc_ver()[0] != "glibc":
        return False
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return False
    settings = [(M_ARENA_MAX, int(arenas))]
    if keep_freed:
        settings += [(M_MMAP_MAX, 0), (M_TRIM_THRESHOLD, -1)]
    return all([bool(mallopt(parameter, value)) for parameter, value in settings])
