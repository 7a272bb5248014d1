"""Where a benchmark computes: torch's device for the neural field, and the accelerators'
peak memory.

JAX computes on its default backend (a GPU where jaxlib has one). The neural field's networks,
samples and losses are torch tensors made on torch's default device (``--torch-device``); the
emission kernel then runs on the JAX device those tensors are handed to through DLPack.
"""

import argparse

import jax
import torch

from invflame.experiments.machine import describe_machine, in_words
from invflame.experiments.parameters import torch_device


def add_argument(parser: argparse.ArgumentParser) -> None:
    """Register ``--torch-device`` on a benchmark's command line."""
    parser.add_argument("--torch-device", default="cpu",
                        help="torch device of the neural field (networks, samples, losses): "
                        "auto, cpu, cuda or cuda:N (default: cpu)")


def apply(device: str) -> str:
    """Make ``device`` (as ``representation.device`` takes it,
    :func:`invflame.experiments.parameters.torch_device`) torch's default device; returns
    :func:`describe`."""
    torch.set_default_device(torch_device(device))
    return describe()


def describe() -> str:
    """Where the process computes, in words, for the benchmark's output
    (:func:`invflame.experiments.machine.in_words`)."""
    return in_words(describe_machine(uses_torch=True))


def synchronize() -> None:
    """Wait for the work queued on torch's CUDA device, if torch uses one (before reading a
    clock)."""
    if torch.cuda.is_initialized():
        torch.cuda.synchronize()


def device_peaks() -> str:
    """Peak memory in MiB of each accelerator so far, by framework, in words; empty on CPUs.

    JAX's figure is its allocator's ``peak_bytes_in_use`` (what was in use, not what it
    reserved ahead); torch's is ``torch.cuda.max_memory_allocated``.
    """
    peaks = [f"JAX {device} {stats['peak_bytes_in_use'] / 2**20:.0f} MiB"
             for device in jax.local_devices()
             if (stats := device.memory_stats()) and "peak_bytes_in_use" in stats]
    if torch.cuda.is_initialized():
        peaks.append(f"torch {torch.cuda.get_device_name()} "
                     f"{torch.cuda.max_memory_allocated() / 2**20:.0f} MiB")
    return ", ".join(peaks)
