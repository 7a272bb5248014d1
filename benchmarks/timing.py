"""Timing shared by the benchmarks."""

import time

import numpy as np

CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time,
          "wall and cpu": lambda: np.array([time.perf_counter(), time.process_time()])}
"""Clocks by name: elapsed wall time, the CPU time of all the process's threads (on a machine
shared with other jobs it leaves out the time spent waiting for a core), and both as one
array."""


def best_times(calls: dict, repeats: int, clock: str = "wall") -> dict:
    """Best time in s of each ``fn()`` of ``calls`` (blocked until ready), the calls taken in
    turn: ``repeats`` rounds of one call each.

    Taken in turn, a change in the machine's load during the run (another job starting or
    ending) reaches every row alike, so the ratios between rows, which the benchmarks report,
    are fair to each; one row timed after the other would give the slow spell to one row only.
    One call of each first compiles (JAX) and is not timed.

    Parameters
    ----------
    calls : dict of str to callable
        The work by name; each returns JAX arrays or anything else.
    repeats : int
        Timed rounds.
    clock : {"wall", "cpu", "wall and cpu"}, optional
        A name in :data:`CLOCKS` (default "wall").

    Returns
    -------
    dict of str to float or ndarray
        The best time of each name, in s; with "wall and cpu" the best of each clock (the two
        may come from different rounds), ``[wall, cpu]``.
    """
    import jax

    now = CLOCKS[clock]
    for fn in calls.values():
        jax.block_until_ready(fn())
    times = {name: [] for name in calls}
    for _ in range(repeats):
        for name, fn in calls.items():
            start = now()
            jax.block_until_ready(fn())
            times[name].append(now() - start)
    return {name: np.minimum.reduce(spent) for name, spent in times.items()}


def best_time(fn, repeats: int, clock: str = "wall") -> float:
    """Best time in s of ``fn()`` over ``repeats`` calls (:func:`best_times` of one call)."""
    return best_times({"": fn}, repeats, clock)[""]
