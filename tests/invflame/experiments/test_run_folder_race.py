"""Several processes finding one stale lock at once: exactly one takes it over."""

import multiprocessing
import subprocess
import sys
import time
from pathlib import Path

import pytest

from invflame.errors import OutputError
from invflame.experiments.run_folder import LOCK, RunLock

PROCESSES, TRIALS = 4, 40


def contend(folders, start, done, holding, most, held):
    """In each trial: wait for the others, then take the folder's lock if possible, holding it
    for a moment while counting how many processes hold it."""
    for folder in folders:
        start.wait()
        try:
            with RunLock(folder):
                with holding.get_lock():
                    holding.value += 1
                    most.value = max(most.value, holding.value)
                time.sleep(0.02)
                with holding.get_lock():
                    holding.value -= 1
                    held.value += 1
        except OutputError:  # a live holder: refused
            pass
        done.wait()


@pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(),
                    reason="the processes share the test's function by forking")
def test_one_stale_lock_is_taken_over_by_one_process_at_a_time(tmp_path):
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()  # its process id now names no process
    folders = [tmp_path / f"trial{i}" for i in range(TRIALS)]
    for folder in folders:
        folder.mkdir()
        (folder / LOCK).write_text(f"{child.pid}\n")
    context = multiprocessing.get_context("fork")
    start, done = context.Barrier(PROCESSES + 1), context.Barrier(PROCESSES + 1)
    holding, most, held = (context.Value("i", 0) for _ in range(3))
    workers = [context.Process(target=contend, args=(folders, start, done, holding, most, held))
               for _ in range(PROCESSES)]
    for worker in workers:
        worker.start()
    try:
        for trial, folder in enumerate(folders):
            before = held.value
            start.wait(timeout=60)
            done.wait(timeout=60)
            assert most.value == 1, f"trial {trial}: {most.value} processes held the lock"
            assert held.value > before, f"trial {trial}: nobody took the stale lock over"
            assert not (folder / LOCK).exists()
            assert sorted(p.name for p in Path(folder).iterdir()) == ["INCOMPLETE"]
    finally:
        for worker in workers:
            worker.join(timeout=10)
            if worker.is_alive():
                worker.kill()
    assert all(worker.exitcode == 0 for worker in workers)
