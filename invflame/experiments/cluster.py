"""Many reconstructions at once on a Dask cluster: comparisons, sweeps, repeated noise draws.

Each job is one :func:`invflame.experiments.runner.run_experiment` (a configuration and a run
folder); the runs are independent, so they are Dask tasks, one per worker at a time. The
cluster is either a :class:`distributed.LocalCluster` on this machine (``workers=N``) or an
existing one reached by its scheduler address or scheduler file (``scheduler=...``), e.g.
started by ``dask-jobqueue`` on Slurm, ``dask-mpi`` or ``dask scheduler`` /
``dask worker``. Run folders are written by the workers, so the output folder must lie on a
file system every worker sees (as on a cluster's shared home or scratch).

Before submitting, the absorption tables the runs need are built once here into the disk cache
(:meth:`~invflame.spectroscopy.absorption_table.AbsorptionTable.cached`), so that workers
sharing that cache load them instead of each building its own.

Failures. A run that raises is retried ``retries`` times; each failed attempt appends its
traceback to ``failures.log`` in the run folder, and a retry continues from the run's last
checkpoint. A run that still fails is reported (:class:`Outcome` with ``error``); the other
runs go on and keep their results. A worker that dies is replaced and its task rescheduled by
Dask itself.
"""

from __future__ import annotations

import json
import logging
import socket
import time
import traceback
import uuid
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

FAILURES = "failures.log"
"""File in a run folder collecting the tracebacks of its failed attempts."""


@dataclass(frozen=True)
class Job:
    """One reconstruction to run.

    Attributes
    ----------
    name : str
        Label in reports (a method, a parameter combination).
    config : dict
        Validated configuration (:func:`invflame.experiments.config.validate`).
    folder : Path
        Run folder (outputs of :func:`~invflame.experiments.runner.run_experiment`).
    """

    name: str
    config: dict
    folder: Path


@dataclass(frozen=True)
class Outcome:
    """What became of a :class:`Job`.

    Attributes
    ----------
    job : Job
    summary : dict or None
        The run's summary (``summary.json``) when it succeeded.
    error : str or None
        ``"ExceptionType: message"`` of the last attempt when it failed.
    attempts : int
        Attempts made (1 + failed attempts before the last one).
    """

    job: Job
    summary: dict | None
    error: str | None
    attempts: int

    @property
    def ok(self) -> bool:
        """Whether the run finished."""
        return self.error is None


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None,
                processes: bool = True) -> Iterator:
    """A Dask client on a new local cluster or on an existing cluster; closed on exit.

    Parameters
    ----------
    workers : int, optional
        Start a :class:`distributed.LocalCluster` of this many single-threaded workers
        (listening on the loopback interface only; the dashboard, when bokeh is installed, at
        ``client.dashboard_link``).
    scheduler : str, optional
        Connect to a running cluster instead: a scheduler address (``tcp://host:8786``) or
        the path of a scheduler file (JSON, as written by ``dask scheduler
        --scheduler-file``, ``dask-mpi`` or ``dask-jobqueue``).
    processes : bool, optional
        Local workers as processes (default; each with its own JAX runtime) or as threads of
        this process.

    Yields
    ------
    distributed.Client
    """
    from distributed import Client, LocalCluster

    if (workers is None) == (scheduler is None):
        raise ValueError("give either workers (a local cluster) or scheduler (an existing "
                         "cluster's address or scheduler file), not both or neither")
    if scheduler is not None:
        scheduler_file = Path(scheduler)
        client = (Client(scheduler_file=str(scheduler_file)) if scheduler_file.is_file()
                  else Client(scheduler))
        with client:
            yield client
        return
    if int(workers) < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    local = {"host": "127.0.0.1"} if processes else {}
    # loopback only, any free port; failures are reported by run_jobs and logged in the run
    # folders rather than by the workers' logs
    with LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=processes,
                      dashboard_address="127.0.0.1:0", silence_logs=logging.CRITICAL,
                      **local) as cluster, Client(cluster) as client:
        yield client


def run_attempt(config: dict, folder, resume: bool = False) -> dict:
    """One attempt at a run, on a worker: a retry resumes; a failure is logged and re-raised.

    Parameters
    ----------
    config : dict
        Validated configuration.
    folder : str or Path
        Run folder.
    resume : bool, optional
        Continue from a checkpoint (also done automatically after a failed attempt).

    Returns
    -------
    dict
        The run's summary.
    """
    from invflame.experiments.runner import run_experiment

    folder = Path(folder)
    failures = folder / FAILURES
    try:
        return run_experiment(config, folder, resume=resume or failures.is_file(),
                              progress=False)
    except Exception:
        folder.mkdir(parents=True, exist_ok=True)
        with open(failures, "a") as handle:
            handle.write(f"--- attempt failed on {socket.gethostname()} at "
                         f"{time.strftime('%Y-%m-%d %H:%M:%S')}\n{traceback.format_exc()}\n")
        raise


def run_jobs(client, jobs: Sequence[Job], resume: bool = False, retries: int = 1,
             progress: bool = True) -> list[Outcome]:
    """Run independent reconstructions on a Dask cluster and collect what became of each.

    Parameters
    ----------
    client : distributed.Client
        E.g. from :func:`dask_client`.
    jobs : sequence of Job
        Runs; their folders must be distinct and visible to every worker.
    resume : bool, optional
        Keep finished runs and continue interrupted ones from their checkpoints.
    retries : int, optional
        Extra attempts for a run that fails (default 1).
    progress : bool, optional
        Show a progress bar and print each failure as it happens.

    Returns
    -------
    list of Outcome
        In the order of ``jobs``; failed runs carry their error, the others their summary.
    """
    from distributed import as_completed

    from solvers.progress import progress_bar

    folders = [Path(job.folder).resolve() for job in jobs]
    if len(set(folders)) != len(folders):
        raise ValueError("two jobs share a run folder; give each job its own folder")
    for folder in folders:
        (folder / FAILURES).unlink(missing_ok=True)
    warm_table_cache(jobs)
    futures = {
        client.submit(run_attempt, job.config, str(folder), resume, retries=int(retries),
                      key=f"invflame-run-{_key_safe(job.name)}-{uuid.uuid4().hex[:8]}"): i
        for i, (job, folder) in enumerate(zip(jobs, folders, strict=True))
    }
    outcomes: list[Outcome | None] = [None] * len(jobs)
    bar = progress_bar(total=len(jobs), desc="runs", unit="run", disable=not progress)
    for future in as_completed(futures):
        i = futures[future]
        outcomes[i] = _outcome(jobs[i], folders[i], future)
        if progress and not outcomes[i].ok:
            bar.write(f"{jobs[i].name}: FAILED after {outcomes[i].attempts} attempt(s): "
                      f"{outcomes[i].error} (tracebacks in {folders[i] / FAILURES})")
        bar.update()
    bar.close()
    return outcomes


def warm_table_cache(jobs: Sequence[Job]) -> None:
    """Build each distinct absorption table of the jobs once, into the disk cache.

    A table that cannot be built is left to the runs that need it, which then fail and are
    reported like any other failure.
    """
    from invflame.experiments.inputs import absorption_table

    spectra = {json.dumps(job.config["spectrum"], sort_keys=True): job.config for job in jobs}
    for config in spectra.values():
        try:
            absorption_table(config)
        except Exception:  # reported by the runs themselves
            continue


def _outcome(job: Job, folder: Path, future) -> Outcome:
    failures = folder / FAILURES
    failed = failures.read_text().count("--- attempt failed") if failures.is_file() else 0
    try:
        summary = future.result()
    except Exception as error:  # the run's own exception, re-raised here by Dask
        return Outcome(job, None, f"{type(error).__name__}: {error}", max(failed, 1))
    return Outcome(job, summary, None, failed + 1)


def _key_safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "._=-" else "_" for c in name)


def failure_report(outcomes: Sequence[Outcome]) -> str:
    """Lines naming each failed run, its error and where its tracebacks are ('' if none)."""
    return "".join(f"FAILED {o.job.name} after {o.attempts} attempt(s): {o.error}; see "
                   f"{Path(o.job.folder) / FAILURES}\n" for o in outcomes if not o.ok)
