"""Peak resident memory of a voxel reconstruction's process at the paper configuration.

Run: ``python benchmarks/bench_memory.py [--cells 60] [--pixels 32] [--rays-per-pixel 9]
[--epochs 10] [--phantom synthetic] [--default-allocator]``.

A process that does what a voxel reconstruction does and nothing else, with the C allocator set
as the ``invflame`` command sets it (:func:`invflame.process_memory.configure_malloc`;
glibc's defaults with ``--default-allocator``): builds
:meth:`invflame.scene.Scene.paper`, makes its data with the forward map, compiles the value and
gradient of the least-squares misfit ``0.5 ||H(f) - g||²`` and runs ``--epochs`` of it. Prints
the process's peak resident set size (MiB) after each step, the
mean wall time of an epoch and, on an accelerator, its peak memory
(:func:`accelerator.device_peaks`).
``benchmarks/bench_rte.py`` runs it in a process of its own: its own rows compile many other
programs, which a reconstruction does not hold.
"""

import argparse
import resource
import time
from pathlib import Path

import jax
import jax.numpy as jnp
from accelerator import device_peaks
from allocator import add_argument, apply

from invflame.phantoms.registry import make_phantom
from invflame.scene import Scene


def peak_mib() -> float:
    """Peak resident set size of this process so far, in MiB: ``VmHWM`` where Linux has it
    (``getrusage`` there counts the peak of the process this one was started from), else
    ``getrusage``."""
    status = Path("/proc/self/status")
    if status.exists():
        for line in status.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 2**10  # KiB -> MiB
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10


def parser() -> argparse.ArgumentParser:
    """The command line."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cells", type=int, default=60, help="voxels per grid axis")
    p.add_argument("--pixels", type=int, default=32, help="pixels per image side")
    p.add_argument("--rays-per-pixel", type=int, default=9,
                   help="sub-rays per pixel (Scene.paper's default: 9)")
    p.add_argument("--epochs", type=int, default=10, help="gradient evaluations")
    p.add_argument("--phantom", default="synthetic",
                   help="ground-truth field by name (invflame.phantoms.registry)")
    add_argument(p)
    return p


def main() -> None:
    args = parser().parse_args()
    allocator = apply(args.default_allocator)
    steps = {"imported": peak_mib()}
    scene = Scene.paper(args.cells, args.pixels, rays_per_pixel=args.rays_per_pixel)
    fields = jnp.asarray(make_phantom(args.phantom, grid=scene.grid).values, jnp.float32)
    steps["scene built"] = peak_mib()
    data = scene.forward(fields) * 1.01
    steps["data made"] = peak_mib()

    def misfit(f):
        return 0.5 * jnp.sum((scene.forward(f) - data) ** 2)

    gradient = jax.jit(jax.value_and_grad(misfit)).lower(fields).compile()
    steps["gradient compiled"] = peak_mib()
    jax.block_until_ready(gradient(fields))
    steps["first epoch"] = peak_mib()
    start = time.perf_counter()
    for _ in range(args.epochs):
        jax.block_until_ready(gradient(fields))
    epoch = (time.perf_counter() - start) / args.epochs
    steps[f"{args.epochs} epochs"] = peak_mib()
    print(f"peak resident memory of a voxel reconstruction ({allocator}): "
          + ", ".join(f"{m:.0f} MiB {step}" for step, m in steps.items())
          + f"; {epoch:.2f} s per epoch (wall)"
          + (f"; peak accelerator memory {peaks}" if (peaks := device_peaks()) else ""))


if __name__ == "__main__":
    main()
