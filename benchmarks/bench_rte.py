"""Time the emission RTE in the study's configuration against a bare exponential.

Run: ``python benchmarks/bench_rte.py [--cells 60] [--pixels 32] [--rays-per-pixel 9]
[--repeats 5] [--batch-rays N | --memory-budget BYTES] [--phantom synthetic]
[--clock cpu|wall] [--stages] [--default-allocator]``.

Builds :meth:`invflame.scene.Scene.paper` (60³ grid over a 1 m cube, four 32×32 cameras,
650–725 cm⁻¹ at 0.04 cm⁻¹ from :meth:`AbsorptionTable.default`, float32) and times, best of
the repeats:

* forward: the fused voxel forward map (sampling, emission RTE, instrument lineshape);
* forward+VJP: value and gradient of ``0.5 ||H(f) - g||²``, one epoch of gradient descent;
* JVP: one product of the Jacobian from ``Scene.operator.linearize`` (the forward-mode
  sweep, value and tangent together), as Gauss–Newton and PDHG use it;
* kernel forward, VJP, JVP: the emission kernel alone on the scene's segment fields
  (:func:`~operators.rte.kernel.emission_radiance`, its pullback of a given cotangent with the
  value, :func:`~operators.rte.kernel.emission_radiance_jvp`), each with the default sweeps
  (:func:`~operators.rte.dispatch.choose_sweeps`: Numba's on one CPU device) and with XLA's;
* exp-only: a jitted ``exp`` over as many float32 elements, in the same ray batches and
  the same number of segment steps per batch as the kernel;
* with ``--stages``, the stages of the kernel, each a jitted loop over the same batches and
  segment steps on the scene's segment fields: the cross-section spline (gathered table
  rows, Horner sums, the optical depth), the Planck spline, the transmission (``exp`` and
  absorptance), the sums over wavenumber of the reverse sweep, the whole forward and reverse
  sweeps (the reverse one as XLA runs it and as Numba does, :mod:`operators.rte.numba_targets`,
  all rays at once, called by XLA), and the gathers and scatters that put rays into batches and
  back (with their VJP).

The rows are timed in turn (:func:`timing.best_times`: one call of each per round), in two
groups: exp-only, forward and forward+VJP, whose ratios are the targets, then the others (the
JVP's ratio to the forward mixes the groups); the stages each alone.

"elements" is the number of real segments times the number of wavenumbers; the kernel also
sweeps the padding of each batch (rays sorted by segment count), reported as "swept".
Peak memory is the process's peak resident set size (``bench_memory.peak_mib``): at the end, once
the scene was built, and after exp-only, forward and forward+VJP, before anything else is
built; XLA's temporary buffers of the compiled forward+VJP; and on an accelerator its peak
memory over all rows (:func:`accelerator.device_peaks`). On an accelerator time with
``--clock wall`` (the process's CPU time leaves out the device's). Last, ``bench_memory.py`` runs
in a process of its own on the same grid, cameras and rays and prints what a voxel
reconstruction's process holds: scene, data and gradient epochs only. Both processes set the C
allocator as the ``invflame`` command sets it (glibc's defaults with ``--default-allocator``;
``benchmarks/allocator.py``).
"""

import argparse
import subprocess
import sys
from functools import partial
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from accelerator import device_peaks
from allocator import add_argument, apply
from bench_memory import peak_mib
from timing import CLOCKS, best_time, best_times

from invflame.experiments.machine import processor
from invflame.phantoms.registry import make_phantom
from invflame.scene import Scene
from operators.rte import sweeps_numba, sweeps_xla
from operators.rte.batches import (
    batched_inputs,
    from_batches,
    ray_order,
    spectra_batches,
)
from operators.rte.kernel import emission_radiance, emission_radiance_jvp
from operators.rte.weights import locate, segment_weights


def segment_loop(body, n_segments, init):
    """Jitted ``lax.map`` over batches of a ``fori_loop`` over each batch's segments.

    ``body(k, acc, batch) -> acc``; the returned function takes ``(n_segments, batches)``.
    """
    def batch(args):
        n, inputs = args
        return jax.lax.fori_loop(0, n, lambda k, acc: body(k, acc, inputs), init)

    return jax.jit(lambda n, batches: jax.lax.map(batch, (n, batches)))


def exp_only(n_segments, batch_rays: int, n_eta: int):
    """Jitted loop: per batch, ``n_segments[b]`` steps of ``exp`` over (batch_rays, n_eta)."""
    x = jnp.linspace(0.0, 1.0, batch_rays * n_eta, dtype=jnp.float32).reshape(batch_rays, n_eta)
    loop = segment_loop(lambda k, acc, _: acc + jnp.exp(-x * k.astype(jnp.float32)),
                        n_segments, jnp.zeros_like(x))
    return lambda: loop(n_segments, None)


def stages(scene: Scene, fields, repeats: int, clock: str) -> dict:
    """Best times in s of the kernel's stages on the scene's segment fields (module notes)."""
    tables, batch_rays = scene.tables, scene.batch_rays
    lengths = jnp.asarray(scene.segments.length, tables.dtype)
    segment_fields = jnp.asarray(scene.sampling(np.asarray(fields)), tables.dtype)
    order, n_segments = ray_order(lengths, batch_rays)
    temperature, fractions, length = batched_inputs(tables, segment_fields, lengths, order,
                                                    batch_rays)
    index, interval = jax.vmap(partial(locate, tables))(temperature, fractions)
    amount, offset, temp = jax.vmap(partial(segment_weights, tables))(
        interval, temperature, fractions, length)
    batches = (index, amount, offset, temp)
    radiance = emission_radiance(tables, segment_fields, lengths, batch_rays)
    # the sweeps run on the spectral points, of which a bin may hold several (the values do
    # not change the time)
    points = jnp.ones((lengths.shape[0], tables.n_points), tables.dtype)
    zeros = jnp.zeros((batch_rays, tables.n_points), tables.dtype)

    def spectra(k, b):
        return sweeps_xla._spectra(tables, b[0][k], b[1][k], b[2][k], b[3][k])

    x = jnp.linspace(0.0, 1.0, zeros.size, dtype=tables.dtype).reshape(zeros.shape)
    n_sums = amount.shape[-1] + 1  # per row of tau, and the offset's (Planck table)

    def reduce(k, acc, _):
        sums = [jnp.sum(acc * (x + j), axis=-1) for j in range(n_sums)]
        return acc + k * jnp.stack(sums, axis=-1).sum(axis=-1, keepdims=True)

    loops = {
        "spline tau": lambda k, acc, b: acc + spectra(k, b)[0],
        "Planck B": lambda k, acc, b: acc + spectra(k, b)[3],
        "transmission": lambda k, acc, b: acc + sum(sweeps_xla._transmission(x * k)),
        "reductions": reduce,
    }
    times = {}
    for name, body in loops.items():
        times[name] = best_time(partial(segment_loop(body, n_segments, zeros), n_segments,
                                        batches), repeats, clock)

    sweep = jax.jit(lambda n, b: jax.lax.map(
        lambda a: sweeps_xla._sweep(tables, *a[1], a[0], None), (n, b)))
    times["forward sweep"] = best_time(lambda: sweep(n_segments, batches), repeats, clock)
    spectra_in = (spectra_batches(points, order, batch_rays),) * 2
    reverse = jax.jit(lambda n, b, s: jax.lax.map(
        lambda a: sweeps_xla._sweep_vjp(tables, *a[1], a[0], *a[2]), (n, b, s)))
    times["reverse sweep"] = best_time(lambda: reverse(n_segments, batches, spectra_in),
                                       repeats, clock)
    index, weights = sweeps_numba._numba_weights(tables, segment_fields)
    amount, offset = weights(segment_fields, lengths)
    shapes = (jax.ShapeDtypeStruct((*amount.shape[:-1], amount.shape[-1] + 1), tables.dtype),
              jax.ShapeDtypeStruct((0, tables.n_points), tables.dtype))
    numba_reverse = jax.jit(lambda t, *a: sweeps_numba._numba_sweep("reverse", shapes, t, *a))
    numba_inputs = (tables, index, amount, offset, lengths, points, points)
    times["reverse sweep, Numba"] = best_time(lambda: numba_reverse(*numba_inputs), repeats,
                                              clock)

    def batching(f, s, spectrum):
        out, to_inputs = jax.vjp(
            lambda f, s: batched_inputs(tables, f, s, order, batch_rays), f, s)
        both = (spectra_batches(spectrum, order, batch_rays),
                spectra_batches(spectrum, order, batch_rays))
        return to_inputs(out), from_batches(both[0] + both[1], order)

    times["batching"] = best_time(lambda: jax.jit(batching)(segment_fields, lengths, radiance),
                                  repeats, clock)
    return times


def kernel_calls(scene: Scene, fields, direction) -> dict:
    """The kernel alone on the scene's segment fields: forward, forward+VJP, forward+JVP."""
    tables, batch_rays = scene.tables, scene.batch_rays
    lengths = jnp.asarray(scene.segments.length, tables.dtype)
    segment_fields = jnp.asarray(scene.sampling(np.asarray(fields)), tables.dtype)
    tangent_fields = jnp.asarray(scene.sampling(direction.reshape(fields.shape)),
                                 tables.dtype)
    cotangent = jnp.ones((lengths.shape[0], tables.n_eta), tables.dtype)

    def radiance(f, sweeps=None):
        return emission_radiance(tables, f, lengths, batch_rays, sweeps=sweeps)

    def pullback(sweeps):
        return jax.jit(lambda f: jax.vjp(partial(radiance, sweeps=sweeps), f)[1](cotangent))

    def tangent(sweeps):
        return lambda: emission_radiance_jvp(tables, segment_fields, lengths, tangent_fields,
                                             jnp.zeros_like(lengths), batch_rays,
                                             sweeps=sweeps)

    calls = {}
    for sweeps, label in ((None, ""), ("xla", ", XLA sweeps")):
        calls[f"kernel forward{label}"] = partial(radiance, segment_fields, sweeps)
        calls[f"kernel VJP{label}"] = partial(pullback(sweeps), segment_fields)
        calls[f"kernel JVP{label}"] = tangent(sweeps)
    return calls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=60, help="voxels per grid axis")
    parser.add_argument("--pixels", type=int, default=32, help="pixels per image side")
    parser.add_argument("--rays-per-pixel", type=int, default=9,
                        help="sub-rays per pixel (Scene.paper's default: 9)")
    parser.add_argument("--repeats", type=int, default=5, help="timed repetitions (best kept)")
    parser.add_argument("--batch-rays", type=int, default=None,
                        help="rays per batch (default: from the memory budget)")
    parser.add_argument("--memory-budget", type=int, default=None,
                        help="bytes for one ray batch (default: per JAX backend)")
    parser.add_argument("--phantom", default="synthetic",
                        help="ground-truth field by name (invflame.phantoms.registry)")
    parser.add_argument("--clock", choices=sorted(CLOCKS), default="cpu",
                        help="wall time, or the process's CPU time (default: on a shared "
                        "machine it leaves out waiting for a core)")
    parser.add_argument("--stages", action="store_true",
                        help="also time the kernel's stages (module notes)")
    add_argument(parser)
    args = parser.parse_args()
    allocator = apply(args.default_allocator)

    scene = Scene.paper(args.cells, args.pixels, rays_per_pixel=args.rays_per_pixel,
                        memory_budget=args.memory_budget, batch_rays=args.batch_rays)
    fields = jnp.asarray(make_phantom(args.phantom, grid=scene.grid).values, jnp.float32)
    built = peak_mib()
    data = scene.forward(fields) * 1.01

    def loss(f):
        return 0.5 * jnp.sum((scene.forward(f) - data) ** 2)

    gradient = jax.jit(jax.value_and_grad(loss))
    seg, n_eta = scene.segments, scene.wavenumber.size
    elements = seg.n_segments * n_eta
    _, n_steps = ray_order(jnp.asarray(seg.length), scene.batch_rays)
    swept = int(n_steps.sum()) * scene.batch_rays * n_eta
    epoch = {
        "exp-only": exp_only(n_steps, scene.batch_rays, n_eta),
        "forward": lambda: scene.forward(fields),
        "forward+VJP": lambda: gradient(fields),
    }
    times = best_times(epoch, args.repeats, args.clock)
    epoch_peak = peak_mib()  # what a voxel reconstruction needs, before the other rows
    jacobian = scene.operator.linearize(np.asarray(fields))
    direction = np.random.default_rng(0).standard_normal(fields.shape).astype(np.float32)
    direction[0] *= 30.0  # kelvins for T, percent-level for mole fractions
    direction[1:] *= 0.01
    direction = direction.ravel()
    others = {"JVP": lambda: jacobian.matvec(direction), **kernel_calls(scene, fields, direction)}
    times.update(best_times(others, args.repeats, args.clock))
    if args.stages:
        times.update({f"  {name}": t
                      for name, t in stages(scene, fields, args.repeats, args.clock).items()})
    temp = gradient.lower(fields).compile().memory_analysis().temp_size_in_bytes
    peak = peak_mib()

    print(f"backend {jax.default_backend()}, {jax.device_count()} device(s), {args.clock} "
          f"time, best of {args.repeats}, {allocator}; processor {processor()}")
    print(f"grid {scene.grid.shape}, {scene.n_rays} pixels x {args.rays_per_pixel} rays, "
          f"{seg.n_segments} segments (max {seg.max_segments}/ray), {n_eta} wavenumbers, "
          f"{len(scene.tables.species)} absorbing species, {scene.tables.nodes.size} T nodes")
    print(f"batch {scene.batch_rays} rays; elements {elements:.4g} (segments x n_eta), "
          f"swept {swept:.4g} ({swept / elements - 1:+.1%} padding)")
    for name, t in times.items():
        print(f"{name:>22}: {1e3 * t:8.1f} ms  {1e9 * t / elements:6.2f} ns/element  "
              f"{t / times['exp-only']:5.2f} x exp-only")
    print(f"JVP / forward: {times['JVP'] / times['forward']:.2f} (scene), "
          f"{times['kernel JVP'] / times['kernel forward']:.2f} (kernel)")
    print(f"peak memory: {peak:.0f} MiB resident ({built:.0f} MiB once the scene was built, "
          f"{epoch_peak:.0f} MiB after forward and forward+VJP); XLA temporaries of "
          f"forward+VJP {temp / 2**20:.0f} MiB")
    if peaks := device_peaks():
        print(f"peak accelerator memory (all rows): {peaks}")
    scene_args = ["--cells", str(args.cells), "--pixels", str(args.pixels),
                  "--rays-per-pixel", str(args.rays_per_pixel), "--phantom", args.phantom]
    scene_args += ["--default-allocator"] * args.default_allocator
    subprocess.run([sys.executable, str(Path(__file__).with_name("bench_memory.py")),
                    *scene_args], check=True)


if __name__ == "__main__":
    main()
