"""The C allocator's handling of large arrays in a long-running process.

A reconstruction allocates and frees the same large arrays every iteration: the spectra of all
rays (30 MB at the paper's size), XLA's temporaries, and for a neural field the networks'
activations (16 MB per layer for a batch of 1024 rays × 64 samples). glibc's ``malloc`` gives
each thread that allocates its own arena, up to eight per core; the threads of XLA, Numba and
torch each keep freed blocks in theirs, so the resident memory of a process holds several
arenas' free blocks and creeps from epoch to epoch. With one arena for the whole process every
thread reuses the same freed blocks. Measured at the paper's size on a 2-core machine, two runs
each, alternating (``docs/performance.md``, "The allocator"):

- a voxel reconstruction (``benchmarks/bench_memory.py --rays-per-pixel 1 --epochs 40``): peak
  750 and 753 MiB with one arena, 857 and 889 MiB with glibc's defaults; 0.47 s per epoch with
  either;
- a neural field (``benchmarks/bench_paper_epoch.py --method NN/TV --epochs 10``): 1.81 and
  1.79 s per epoch with one arena, peak 1291 and 1311 MB; 1.79 and 1.85 s, 1401 and 1389 MB
  with the defaults.

An earlier setting, mapping every block of 8 MiB or more directly and unmapping it when freed,
bounded the peak too (816 and 792 MiB; 1209 and 1208 MB) but paid for the page faults of
mapping the blocks afresh: 0.52 and 0.51 s per voxel epoch, 2.23 s per neural-field epoch.
"""

from __future__ import annotations

import ctypes
import platform

__all__ = ["limit_malloc_arenas"]

#: glibc's ``mallopt`` parameter for the largest number of arenas (``malloc.h``).
M_ARENA_MAX = -8


def limit_malloc_arenas(arenas: int = 1) -> bool:
    """Have glibc's ``malloc`` serve every thread of the process from at most ``arenas``
    arenas, so that blocks one thread frees are reused by the others.

    Called by the ``invflame`` command before it runs, after its imports and before the
    numerical libraries start their worker threads (the imports start two helper threads,
    which keep the arenas they first allocated from); affects the whole process.

    Parameters
    ----------
    arenas : int, optional
        Largest number of arenas, at least 1 (default 1).

    Returns
    -------
    bool
        True where glibc took the setting; False elsewhere (another C library or operating
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
    return bool(mallopt(M_ARENA_MAX, int(arenas)))
