"""Progress bars that redraw on a terminal and write lines into a log.

On a terminal a tqdm bar redraws itself in place with carriage returns; written to a file or a
pipe (``invflame run ... 2> log``, a batch job's output) those frames pile up in one line of
the log. :func:`progress_bar` gives a tqdm bar that draws on a terminal as usual and, on any
other stream, writes its state as a line of its own at most every
:data:`LOG_INTERVAL` seconds.
"""

from __future__ import annotations

import io
import sys

from tqdm import tqdm

LOG_INTERVAL = 30.0
"""Least time in s between two lines of a bar written into a log."""


class _Lines(io.TextIOBase):
    """A text stream that writes each of tqdm's frames as a line of ``stream``."""

    def __init__(self, stream):
        self.stream = stream

    def write(self, text: str) -> int:
        frame = text.replace("\r", "").strip()
        if frame:
            self.stream.write(frame + "\n")
        return len(text)

    def flush(self) -> None:
        self.stream.flush()


def progress_bar(iterable=None, **kwargs) -> tqdm:
    """A :class:`tqdm.tqdm` bar over ``iterable`` that writes lines, not frames, into a log.

    Parameters
    ----------
    iterable : iterable, optional
        What the bar iterates over (as for tqdm).
    **kwargs
        Passed to tqdm (``total``, ``desc``, ``disable``, ``file`` ...). When the stream
        (``file``, default ``sys.stderr``) is not a terminal, the bar writes each state as a
        line, at most every :data:`LOG_INTERVAL` seconds.
    """
    stream = kwargs.pop("file", None) or sys.stderr
    if not getattr(stream, "isatty", lambda: False)():
        kwargs.setdefault("mininterval", LOG_INTERVAL)
        kwargs.setdefault("maxinterval", max(LOG_INTERVAL, kwargs["mininterval"]))
        kwargs.update(file=_Lines(stream), ascii=True, dynamic_ncols=False, ncols=100)
    else:
        kwargs["file"] = stream
    return tqdm(iterable, **kwargs)
