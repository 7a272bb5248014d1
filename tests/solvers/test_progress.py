"""Progress bars: frames on a terminal, lines in a log."""

import io

from solvers import progress
from solvers.progress import progress_bar


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_bar_written_into_a_log_gives_lines_without_carriage_returns(monkeypatch):
    monkeypatch.setattr(progress, "LOG_INTERVAL", 0.0)
    log = io.StringIO()
    for _ in progress_bar(range(5), desc="work", file=log):
        pass
    text = log.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert len(lines) >= 2 and all(line.startswith("work:") for line in lines)
    assert "5/5" in lines[-1]


def test_a_bar_on_a_terminal_redraws_in_place():
    terminal = Terminal()
    for _ in progress_bar(range(3), desc="work", file=terminal, mininterval=0.0):
        pass
    assert "\r" in terminal.getvalue()


def test_a_log_bar_waits_its_interval_between_lines():
    log = io.StringIO()
    for _ in progress_bar(range(1000), desc="work", file=log):
        pass
    assert len(log.getvalue().splitlines()) <= 3  # the first state, the last, at most one more
