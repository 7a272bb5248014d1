"""Time per epoch and memory of the ``paper`` preset, measured over a few epochs.

Runs VG/TV and NN/Tikh. (or all six methods with ``--all``) of ``invflame reproduce --preset
paper`` (60³ voxels, four cameras of 32×32 pixels, 650–725 cm⁻¹ at 0.04 cm⁻¹) for ``--epochs``
epochs each through the same runner
as the full comparison (pretraining shortened to ``--pretrain`` steps: it does not change the
cost of an epoch), and prints seconds per epoch, parameter memory and the process's peak
resident memory, next to the paper's Table 1 (GPU, 2000 epochs). The C allocator is set as the
``invflame`` command sets it (glibc's defaults with ``--default-allocator``;
``benchmarks/allocator.py``). JAX computes on its default backend; ``--torch-device cuda`` puts
the neural fields on the GPU too, and the accelerators' peak memory is printed
(``benchmarks/accelerator.py``).

    python benchmarks/bench_paper_epoch.py [--epochs 3] [--pretrain 50] [--out DIR] [--all]
        [--default-allocator] [--torch-device cuda]
"""

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import accelerator
from allocator import add_argument, apply

from invflame.experiments import reproduce, runner
from invflame.experiments.comparison_table import PAPER_TABLE


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=int, default=3)
    parser.add_argument("--pretrain", type=int, default=50)
    parser.add_argument("--out", type=Path, default=None,
                        help="keep the runs in this folder (default: a temporary folder, "
                        "removed at the end)")
    parser.add_argument("--method", choices=list(reproduce.METHODS),
                        help="measure one method in this process (default: each in its own "
                        "process, so that peak memories are separate)")
    parser.add_argument("--all", action="store_true",
                        help="all six methods (default: VG/TV and NN/Tikh.)")
    add_argument(parser)
    accelerator.add_argument(parser)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="invflame-paper-epoch-") as scratch:
        measure(args, args.out or Path(scratch))


def measure(args, out):
    """Run the chosen methods (each in a process of its own) or ``args.method`` here,
    writing their runs under the folder ``out``."""
    if args.method is None:
        for method in reproduce.METHODS if args.all else ("VG/TV", "NN/Tikh."):
            subprocess.run([sys.executable, __file__, "--method", method, "--epochs",
                            str(args.epochs), "--pretrain", str(args.pretrain), "--out",
                            str(out), "--torch-device", args.torch_device]
                           + ["--default-allocator"] * args.default_allocator,
                           check=True)
        return
    allocator = apply(args.default_allocator)
    cfg = reproduce.method_config("paper", args.method)
    cfg["solver"]["iterations"] = args.epochs  # the runner counts a solver's iterations in epochs
    cfg["representation"]["pretrain_iterations"] = args.pretrain
    cfg["representation"]["device"] = args.torch_device
    summary = runner.run_experiment(cfg, out / reproduce.folder_name(args.method),
                                    progress=False)
    paper = PAPER_TABLE[args.method]
    print(f"{args.method:>9}: {summary['seconds_per_epoch']:.2f} s per epoch "
          f"({summary['epochs']:g} epochs, {summary['iterations']} iterations), parameters "
          f"{summary['parameter_memory_mb']:.2f} MB, process peak "
          f"{summary['peak_memory_mb']:.0f} MB, {allocator}, {accelerator.describe()}"
          + (f", peak accelerator memory {peaks}" if (peaks := accelerator.device_peaks()) else "")
          + f"   [paper, GPU: {paper[0]} ms, {paper[1]} MB]", flush=True)


if __name__ == "__main__":
    main()
