"""Wall-clock timing shared by the benchmarks."""

import time


def best_time(fn, repeats: int) -> float:
    """Best wall time in s of ``fn()`` (blocked until ready) over ``repeats`` calls.

    One call first compiles (JAX) and is not timed.
    """
    import jax

    jax.block_until_ready(fn())
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - start)
    return min(times)
