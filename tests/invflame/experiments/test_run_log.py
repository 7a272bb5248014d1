"""Where a run's time went: the stage clock."""

from invflame.experiments import run_log
from invflame.experiments.run_log import StageClock


def test_laps_give_each_stage_the_time_since_the_one_before(monkeypatch):
    readings = iter([10.0, 12.5, 16.0, 17.0])  # the clock's start, then one per lap
    monkeypatch.setattr(run_log.time, "perf_counter", lambda: next(readings))
    clock = StageClock()
    clock.lap("first")
    clock.lap("second")
    clock.lap("first")  # a stage named again adds up
    assert clock.seconds == {"first": 3.5, "second": 3.5}
    assert clock.table() == "time by stage: first 3.5 s (50 %), second 3.5 s (50 %)"


def test_the_shares_add_up_to_the_whole():
    line = StageClock.table_of({"a": 1.0, "b": 3.0})
    assert line == "time by stage: a 1.0 s (25 %), b 3.0 s (75 %)"
