"""The benchmarks' timing: rows timed in turn, the best of each kept."""


import numpy as np
import timing


def test_rows_are_timed_in_turn_and_each_keeps_its_best(monkeypatch):
    """One untimed call of each row, then rounds of one call of each; every row's best is the
    shortest of its own timed calls, on a clock that each call advances by a known step."""
    now, calls = [0.0], []
    steps = {"a": [9.0, 3.0, 5.0, 4.0], "b": [7.0, 8.0, 2.0, 6.0]}  # first call untimed

    def call(name):
        def fn():
            now[0] += steps[name][sum(c == name for c in calls)]
            calls.append(name)
        return fn

    monkeypatch.setitem(timing.CLOCKS, "fake", lambda: now[0])
    best = timing.best_times({"a": call("a"), "b": call("b")}, repeats=3, clock="fake")
    assert calls == ["a", "b"] * 4
    assert best == {"a": 3.0, "b": 2.0}
    calls.clear()
    assert timing.best_time(call("a"), repeats=3, clock="fake") == 3.0


def test_two_clocks_keep_each_its_own_best(monkeypatch):
    """With a clock of two readings (wall and CPU), each reading's best is taken on its own,
    from whichever round gave it."""
    now = np.zeros(2)
    steps = iter([[9.0, 9.0], [3.0, 6.0], [5.0, 2.0], [4.0, 4.0]])  # first call untimed

    def fn():
        now[:] += next(steps)

    monkeypatch.setitem(timing.CLOCKS, "fake pair", lambda: now.copy())
    best = timing.best_times({"a": fn}, repeats=3, clock="fake pair")
    np.testing.assert_array_equal(best["a"], [3.0, 2.0])
