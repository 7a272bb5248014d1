"""Ray sharding: equal to the one-device kernel on 1 device here, and on 2 forced CPU devices."""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from operators.sharding import RAY_AXIS, place_rays, ray_mesh, shard_rays

CHECK = Path(__file__).resolve().parent / "sharding_check.py"


def ray_kernel(weights, x, y):
    """A ray-wise toy kernel: rays along axis 1 of ``x`` and axis 0 of ``y``."""
    return jnp.tanh(x.sum(axis=0) @ weights) * y[:, :1]


def inputs(n_rays=7):
    rng = np.random.default_rng(0)
    return (jnp.asarray(rng.normal(size=(5, 3))), jnp.asarray(rng.normal(size=(2, n_rays, 5))),
            jnp.asarray(rng.normal(size=(n_rays, 4))))


def test_one_device_mesh_gives_the_kernel_and_its_gradient():
    args = inputs()
    sharded = shard_rays(ray_kernel, ray_axes=(None, 1, 0), devices=1)
    np.testing.assert_allclose(sharded(*args), ray_kernel(*args), rtol=1e-12)
    loss = lambda f: lambda w, x, y: jnp.sum(f(w, x, y) ** 2)  # noqa: E731
    grads = jax.grad(loss(sharded), argnums=(0, 1, 2))(*args)
    expected = jax.grad(loss(ray_kernel), argnums=(0, 1, 2))(*args)
    for g, e in zip(grads, expected, strict=True):
        np.testing.assert_allclose(g, e, rtol=1e-12)
    assert sharded.mesh.axis_names == (RAY_AXIS,)


def test_bad_arguments_are_clear_errors():
    with pytest.raises(ValueError, match="at least one argument must be ray-wise"):
        shard_rays(ray_kernel, ray_axes=(None, None, None))
    with pytest.raises(ValueError, match="non-negative ints or None"):
        shard_rays(ray_kernel, ray_axes=(None, -1, 0))
    with pytest.raises(ValueError, match="xla_force_host_platform_device_count"):
        ray_mesh(jax.device_count() + 1)
    sharded = shard_rays(ray_kernel, ray_axes=(None, 1, 0))
    weights, x, y = inputs()
    with pytest.raises(TypeError, match="3 positional arguments"):
        sharded(weights, x)
    with pytest.raises(ValueError, match="disagree on the number of rays"):
        sharded(weights, x, y[:-1])


def test_place_rays_pads_to_whole_blocks():
    placed = place_rays(np.arange(6).reshape(3, 2), axis=0, devices=1)
    np.testing.assert_array_equal(placed, np.arange(6).reshape(3, 2))
    assert placed.sharding.spec == jax.sharding.PartitionSpec(RAY_AXIS)


def test_two_devices_equal_one_device_to_round_off(script_report):
    """Kernel forward/VJP (37 rays: padded), scene forward/VJP and 5 Adam steps."""
    result = script_report(CHECK, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    assert result["devices"] == 2 and result["scene_devices"] == 2
    assert result["kernel_shape_equal"]
    for key in ("kernel_forward", "kernel_vjp_fields", "kernel_vjp_lengths", "scene_forward",
                "scene_vjp", "adam"):
        assert result[key] < 1e-5, (key, result[key])
    assert result["adam_moved"] > 1e-3  # the iterations did something to compare

