"""Where a run computed: the processor, JAX's devices, torch's device and the versions.

A run's times (``seconds_per_epoch`` in its summary, the ``epoch [ms]`` column of a
comparison table) say little without the machine that took them, and a comparison resumed on
another machine mixes two. The runner records this description in each run's summary and
log; ``invflame reproduce`` and ``study`` name it under their table.

JAX and torch are imported by :func:`describe_machine` itself, so that the command line, which
imports the tables' code to build its parser, starts without them.
"""

from __future__ import annotations

import os
import platform
from pathlib import Path

import numpy as np

import invflame


def processor() -> str:
    """The processor's model name and the cores this process may use, e.g. ``"AMD EPYC 7B13,
    2 cores"`` (the model from ``/proc/cpuinfo`` on Linux, else :func:`platform.processor`)."""
    model = ""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        model = next((line.split(":", 1)[1].strip() for line in cpuinfo.read_text().splitlines()
                      if line.startswith("model name")), "")
    model = model or platform.processor() or platform.machine() or "unknown processor"
    cores = (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
             else os.cpu_count())
    return f"{model}, {cores} core{'s' if cores != 1 else ''}"


def describe_machine(uses_torch: bool = False) -> dict:
    """The machine this process computes on, as a run's summary records it.

    Parameters
    ----------
    uses_torch : bool, optional
        Whether the run's representation computes with torch (the neural ones): then torch's
        default device is named too.

    Returns
    -------
    dict
        ``processor`` (:func:`processor`), ``jax`` (its backend and its devices' kind, e.g.
        ``"gpu: NVIDIA H200"``, or ``"cpu"``), ``torch`` (torch's default device and, for a
        CUDA one, its name; None where the run does not use torch) and ``versions``
        (invflame, JAX, jaxlib, torch, NumPy).
    """
    import jax
    import jaxlib
    import torch

    backend, kinds = jax.default_backend(), sorted({d.device_kind for d in jax.local_devices()})
    device = torch.get_default_device()
    named = (f"{device}: {torch.cuda.get_device_name(device)}" if device.type == "cuda"
             else str(device))
    return {
        "processor": processor(),
        "jax": backend if kinds == [backend] else f"{backend}: {', '.join(kinds)}",
        "torch": named if uses_torch else None,
        "versions": {"invflame": invflame.__version__, "jax": jax.__version__,
                     "jaxlib": jaxlib.__version__, "torch": torch.__version__,
                     "numpy": np.__version__},
    }


def in_words(machine: dict | None) -> str:
    """A machine of :func:`describe_machine` in one line, e.g. ``"JAX on gpu: NVIDIA H200;
    processor Intel(R) Xeon(R) Processor, 2 cores"``; ``"not recorded"`` for None (a run
    written before runs recorded it)."""
    if machine is None:
        return "not recorded"
    torch_part = "" if machine["torch"] is None else f"; torch on {machine['torch']}"
    return f"JAX on {machine['jax']}{torch_part}; processor {machine['processor']}"
