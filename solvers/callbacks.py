"""Callbacks run after every iteration: progress bar, checkpoints, or any plain function.

A callback is a :class:`Callback` or a plain callable ``f(run) -> bool | None`` receiving the
:class:`solvers.base.RunState` after each iteration (``run.iteration``, ``run.x``,
``run.current.loss``, ``run.history``...). Returning True stops the run (stop reason
``"callback"``); raising propagates out of ``Solver.run`` after every callback's ``on_end``.
"""

from __future__ import annotations

from pathlib import Path

from solvers.progress import progress_bar


class Callback:
    """Base class: override any of :meth:`Callback.on_start`, :meth:`Callback.__call__`,
    :meth:`Callback.on_end`."""

    def on_start(self, run) -> None:
        """Called once before the first iteration (after a resume, with its state)."""

    def __call__(self, run) -> bool | None:
        """Called after each iteration; return True to stop."""
        return None

    def on_end(self, run) -> None:
        """Called once when the run ends, also when it ends by an exception."""


class FunctionCallback(Callback):
    """A plain function ``f(run) -> bool | None`` as a :class:`Callback`."""

    def __init__(self, fun):
        self.fun = fun

    def __call__(self, run):
        return self.fun(run)


def as_callback(callback) -> Callback:
    """A :class:`Callback` from a callback or a callable."""
    if isinstance(callback, Callback):
        return callback
    if callable(callback):
        return FunctionCallback(callback)
    raise TypeError(f"callbacks must be Callback instances or callables, got "
                    f"{type(callback).__name__}")


class ProgressBar(Callback):
    """A tqdm progress bar over ``max_iter`` iterations showing the loss.

    Parameters
    ----------
    desc : str, optional
        Label (default: the solver's name).
    **tqdm_kwargs
        Passed to :func:`solvers.progress.progress_bar` (e.g. ``disable=True``,
        ``file=...``).
    """

    def __init__(self, desc: str | None = None, **tqdm_kwargs):
        self.desc = desc
        self.tqdm_kwargs = tqdm_kwargs
        self.bar = None

    def on_start(self, run):
        self.bar = progress_bar(total=run.solver.stopping.max_iter, initial=run.iteration,
                        desc=self.desc or run.solver.name, **self.tqdm_kwargs)

    def __call__(self, run):
        self.bar.update(1)
        self.bar.set_postfix(loss=f"{run.current.loss:.4e}", refresh=False)

    def on_end(self, run):
        if self.bar is not None:
            self.bar.close()


class Checkpoint(Callback):
    """Save the run every ``every`` iterations and when it ends, atomically, to one file.

    Resume with ``solver.run(problem, resume=path)``.

    Parameters
    ----------
    path : str or Path
        Checkpoint file (``.npz``), overwritten each time.
    every : int, optional
        Save interval in iterations (default 10).
    seconds : float, optional
        Wall time in s of the run that must have passed since the last save (or the start)
        for a save at an ``every``-th iteration (default 0: each of them saves); a run of
        fast iterations then saves every few seconds instead of every few iterations.
    """

    def __init__(self, path, every: int = 10, seconds: float = 0.0):
        if int(every) != every or every < 1:
            raise ValueError(f"every must be a positive integer, got {every}")
        if not seconds >= 0:
            raise ValueError(f"seconds must be a number >= 0 (wall seconds), got {seconds}")
        self.path = Path(path)
        self.every = int(every)
        self.seconds = float(seconds)
        self._saved_at = 0.0

    def on_start(self, run):
        self._saved_at = run.elapsed

    def __call__(self, run):
        if run.iteration % self.every == 0 and run.elapsed - self._saved_at >= self.seconds:
            run.save(self.path)
            self._saved_at = run.elapsed

    def on_end(self, run):
        run.save(self.path)
