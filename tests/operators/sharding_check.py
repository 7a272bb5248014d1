"""Sharded vs one-device results, run in a fresh process with two forced CPU devices.

``XLA_FLAGS=--xla_force_host_platform_device_count=2`` must be set before JAX starts, so
``test_sharding.py`` runs this file as a script with that environment. It prints one JSON
object: the relative differences of the emission kernel (forward, VJP), of the scene's
forward map and gradient, and of a few Adam iterations on a voxel problem.
"""

import json
import sys
from functools import partial
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import operators as op
import solvers
from invflame.geometry import VoxelGrid, paper_rig
from invflame.representations.voxel import VoxelRepresentation
from invflame.scene import Scene
from operators.rte import emission_radiance
from operators.sharding import shard_rays

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "invflame"))
from test_scene import small_table, smooth_field  # noqa: E402


def relative(a, b) -> float:
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a)))


def kernel_differences(scene: Scene, rng) -> dict:
    """The bare emission kernel on 37 rays (not a multiple of 2: padding) on 2 devices."""
    fields = np.asarray(scene.sampling(smooth_field(scene.grid)), np.float32)[:, :37]
    lengths = jnp.asarray(scene.segments.length[:37], np.float32)
    kernel = partial(emission_radiance, batch_rays=8)
    sharded = jax.jit(shard_rays(kernel, ray_axes=(None, 1, 0)))
    one, pull_one = jax.vjp(kernel, scene.tables, jnp.asarray(fields), lengths)
    two, pull_two = jax.vjp(sharded, scene.tables, jnp.asarray(fields), lengths)
    w = jnp.asarray(rng.normal(size=one.shape), np.float32)
    g_one, g_two = pull_one(w)[1:], pull_two(w)[1:]
    return {"kernel_shape_equal": one.shape == two.shape,
            "kernel_forward": relative(one, two),
            "kernel_vjp_fields": relative(g_one[0], g_two[0]),
            "kernel_vjp_lengths": relative(g_one[1], g_two[1])}


def scene_differences(single: Scene, sharded: Scene, rng) -> dict:
    fields = jnp.asarray(smooth_field(single.grid), np.float32)
    one, pull_one = jax.vjp(single.forward, fields)
    two, pull_two = jax.vjp(sharded.forward, fields)
    w = jnp.asarray(rng.normal(size=one.shape), np.float32)
    return {"scene_devices": len(two.sharding.device_set),
            "scene_forward": relative(one, two),
            "scene_vjp": relative(pull_one(w)[0], pull_two(w)[0])}


def adam_parameters(scene: Scene, data, start) -> tuple[np.ndarray, np.ndarray]:
    """Starting parameters and those after five Adam steps on a TV-regularized problem."""
    forward = op.Operator.from_jax(scene.forward, scene.field_shape, scene.data_shape,
                                   dtype=scene.dtype, name="scene")
    representation = VoxelRepresentation(scene.grid, forward)
    x0 = representation.initial_parameters(start)
    problem = representation.problem(data, regularizer="tv", lam=1e-3 * data.size, x0=x0)
    return x0, solvers.solve(problem, "adam", max_iter=5, lr=0.01).x


def main() -> None:
    rng = np.random.default_rng(0)
    grid = VoxelGrid.cube(6, size=1.0, centre=(0.0, 0.5, 0.0))
    rig = paper_rig(grid, n_pixels=3)
    single = Scene(grid, rig, small_table(), resolution=4.0)
    sharded = Scene(grid, rig, small_table(), resolution=4.0, devices=2)
    truth = smooth_field(grid)
    data = single.simulate(truth)
    start = truth * (1 + 0.1 * rng.standard_normal(truth.shape))
    x0, x_one = adam_parameters(single, data, start)
    _, x_two = adam_parameters(sharded, data, start)
    result = {"devices": jax.device_count(),
              **kernel_differences(single, rng),
              **scene_differences(single, sharded, rng),
              "adam_moved": relative(x_one, x0),
              "adam": relative(x_one, x_two)}
    print(json.dumps(result))


if __name__ == "__main__":
    main()
