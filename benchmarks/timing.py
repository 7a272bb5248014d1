"""Timing shared by the benchmarks."""

import time

CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}
"""Clocks by name: elapsed wall time, and the CPU time of all the process's threads (on a
machine shared with other jobs it leaves out the time spent waiting for a core)."""


def best_time(fn, repeats: int, clock: str = "wall") -> float:
    """Best time in s of ``fn()`` (blocked until ready) over ``repeats`` calls.

    One call first compiles (JAX) and is not timed.

    Parameters
    ----------
    fn : callable
        The work; returns JAX arrays or anything else.
    repeats : int
        Timed calls.
    clock : {"wall", "cpu"}, optional
        A name in :data:`CLOCKS` (default "wall").
    """
    import jax

    now = CLOCKS[clock]
    jax.block_until_ready(fn())
    times = []
    for _ in range(repeats):
        start = now()
        jax.block_until_ready(fn())
        times.append(now() - start)
    return min(times)
