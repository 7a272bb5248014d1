"""Time the emission RTE in the study's configuration against a bare exponential.

Run: ``python benchmarks/bench_rte.py [--cells 60] [--pixels 32] [--repeats 5]
[--batch-rays N | --memory-budget BYTES] [--phantom synthetic]``.

Builds :meth:`invflame.scene.Scene.paper` (60³ grid over a 1 m cube, four 32×32 cameras,
650–725 cm⁻¹ at 0.04 cm⁻¹ from :meth:`AbsorptionTable.default`, float32) and times, best of
the repeats:

* forward: the fused voxel forward map (sampling, emission RTE, instrument lineshape);
* forward+VJP: value and gradient of ``0.5 ||H(f) - g||²``, one epoch of gradient descent;
* exp-only: a jitted ``exp`` over as many float32 elements, in the same ray batches and
  the same number of segment steps per batch as the kernel.

"elements" is the number of real segments times the number of wavenumbers; the kernel also
sweeps the padding of each batch (rays sorted by segment count), reported as "swept".
Peak memory is the process's peak resident set size, and XLA's temporary buffers of the
compiled forward+VJP.
"""

import argparse
import resource

import jax
import jax.numpy as jnp
from timing import best_time

from invflame.phantoms.registry import make_phantom
from invflame.scene import Scene
from operators.rte_batches import ray_order


def exp_only(n_segments, batch_rays: int, n_eta: int):
    """Jitted loop: per batch, ``n_segments[b]`` steps of ``exp`` over (batch_rays, n_eta)."""
    x = jnp.linspace(0.0, 1.0, batch_rays * n_eta, dtype=jnp.float32).reshape(batch_rays, n_eta)

    def batch(n):
        step = lambda k, acc: acc + jnp.exp(-x * k.astype(jnp.float32))  # noqa: E731
        return jax.lax.fori_loop(0, n, step, jnp.zeros_like(x))

    return jax.jit(lambda n: jax.lax.map(batch, n))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=60, help="voxels per grid axis")
    parser.add_argument("--pixels", type=int, default=32, help="pixels per image side")
    parser.add_argument("--repeats", type=int, default=5, help="timed repetitions (best kept)")
    parser.add_argument("--batch-rays", type=int, default=None,
                        help="rays per batch (default: from the memory budget)")
    parser.add_argument("--memory-budget", type=int, default=None,
                        help="bytes for one ray batch (default: per JAX backend)")
    parser.add_argument("--phantom", default="synthetic",
                        help="ground-truth field by name (invflame.phantoms.registry)")
    args = parser.parse_args()

    scene = Scene.paper(args.cells, args.pixels, memory_budget=args.memory_budget,
                        batch_rays=args.batch_rays)
    fields = jnp.asarray(make_phantom(args.phantom, grid=scene.grid).values, jnp.float32)
    data = scene.forward(fields) * 1.01

    def loss(f):
        return 0.5 * jnp.sum((scene.forward(f) - data) ** 2)

    gradient = jax.jit(jax.value_and_grad(loss))
    seg, n_eta = scene.segments, scene.wavenumber.size
    elements = seg.n_segments * n_eta
    _, n_steps = ray_order(jnp.asarray(seg.length), scene.batch_rays)
    swept = int(n_steps.sum()) * scene.batch_rays * n_eta
    t_exp = best_time(lambda: exp_only(n_steps, scene.batch_rays, n_eta)(n_steps), args.repeats)
    t_fwd = best_time(lambda: scene.forward(fields), args.repeats)
    t_grad = best_time(lambda: gradient(fields), args.repeats)
    temp = gradient.lower(fields).compile().memory_analysis().temp_size_in_bytes
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10  # KiB -> MiB

    print(f"backend {jax.default_backend()}, {jax.device_count()} device(s)")
    print(f"grid {scene.grid.shape}, {scene.n_rays} rays, {seg.n_segments} segments "
          f"(max {seg.max_segments}/ray), {n_eta} wavenumbers, "
          f"{len(scene.tables.species)} absorbing species, {scene.tables.nodes.size} T nodes")
    print(f"batch {scene.batch_rays} rays; elements {elements:.4g} (segments x n_eta), "
          f"swept {swept:.4g} ({swept / elements - 1:+.1%} padding)")
    for name, t in (("exp-only", t_exp), ("forward", t_fwd), ("forward+VJP", t_grad)):
        print(f"{name:>12}: {1e3 * t:8.1f} ms  {1e9 * t / elements:6.2f} ns/element  "
              f"{t / t_exp:5.1f} x exp-only")
    print(f"peak memory: {peak:.0f} MiB resident; XLA temporaries of forward+VJP "
          f"{temp / 2**20:.0f} MiB")


if __name__ == "__main__":
    main()
