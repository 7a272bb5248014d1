"""A run's log (``log.txt``) and where its time went, stage by stage."""

from __future__ import annotations

import time
from pathlib import Path


class Log:
    """Appends timestamped lines to ``log.txt`` (and prints them when ``echo``).

    Parameters
    ----------
    path : Path
        The log file; lines are appended.
    echo : bool, optional
        Also print each line (default True).
    """

    def __init__(self, path: Path, echo: bool = True):
        self.path, self.echo, self.start = path, echo, time.perf_counter()

    def __call__(self, message: str) -> None:
        line = f"[{time.perf_counter() - self.start:8.1f} s] {message}"
        with open(self.path, "a") as handle:
            handle.write(line + "\n")
        if self.echo:
            print(line, flush=True)


class StageClock:
    """Wall time of consecutive stages of a run: each :meth:`lap` closes the stage that began at
    the previous lap (or at the clock's start).

    Attributes
    ----------
    seconds : dict of str -> float
        Wall time in s of each stage, in the order they ran (a stage named twice adds up).
    """

    def __init__(self):
        self.seconds: dict[str, float] = {}
        self._last = time.perf_counter()

    def lap(self, stage: str) -> None:
        """Close the stage ``stage``: the wall time since the previous lap is its."""
        now = time.perf_counter()
        self.seconds[stage] = self.seconds.get(stage, 0.0) + now - self._last
        self._last = now

    def table(self) -> str:
        """One line: each stage's wall time in s and its share of the total."""
        return self.table_of(self.seconds)

    @staticmethod
    def table_of(seconds: dict) -> str:
        """One line of stages' wall times ``seconds`` (stage → s, as :attr:`seconds` or a run
        summary's ``stages``) and their shares of the total."""
        total = sum(seconds.values()) or 1.0
        return "time by stage: " + ", ".join(
            f"{stage} {value:.1f} s ({100 * value / total:.0f} %)"
            for stage, value in seconds.items())
