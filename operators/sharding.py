r"""Ray-parallel evaluation of ray-wise JAX kernels on several devices.

A kernel is *ray-wise* when every output ray depends only on the same ray of its ray-wise
inputs and on inputs shared by all rays (parameters, tables): the emission kernel
:func:`operators.rte.kernel.emission_radiance`, the voxel forward map of a scene, a neural
field rendered along rays. :func:`shard_rays` runs such a kernel with its rays cut into equal
contiguous blocks, one per device of a one-axis :class:`jax.sharding.Mesh` (axis ``"rays"``),
and the shared inputs replicated, through :func:`jax.shard_map`:

.. math:: F(\theta)_{r} = F_{d(r)}(\theta)_{r}, \qquad
          \nabla_\theta \langle w, F(\theta) \rangle
          = \sum_{d} \nabla_\theta \langle w_d, F_d(\theta) \rangle,

so the forward map needs no communication and the reverse pass (JAX's transpose of
``shard_map``) sums the devices' gradient contributions to the replicated inputs (one
all-reduce of a parameter-sized array). Derivatives through :func:`jax.vjp`, :func:`jax.grad`
and :func:`jax.jvp` work unchanged, custom VJPs of the kernel included.

The ray count need not divide evenly: ray-wise inputs are padded by repeating their last ray
(valid input for any kernel) and the padded outputs are dropped, so they take no part in any
result or gradient.

The same code runs on one device (a mesh of one), on the GPUs of one host and, after
:func:`jax.distributed.initialize` in every process, on the devices of several hosts (the mesh
then spans ``jax.devices()`` of all processes; see ``docs/scaling.md``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

RAY_AXIS = "rays"
"""Name of the mesh axis the rays are split over."""


def ray_mesh(devices: int | Sequence | Mesh | None = None) -> Mesh:
    """A one-axis device mesh (axis :data:`RAY_AXIS`) to split rays over.

    Parameters
    ----------
    devices : int, sequence of jax.Device, Mesh or None
        ``None``: every device of the default backend (all hosts after
        :func:`jax.distributed.initialize`); an int ``n``: the first ``n`` of them; a sequence:
        those devices; a mesh: returned as is (it must have the axis :data:`RAY_AXIS`).

    Returns
    -------
    jax.sharding.Mesh
    """
    if isinstance(devices, Mesh):
        if RAY_AXIS not in devices.axis_names:
            raise ValueError(f"the mesh must have an axis named {RAY_AXIS!r}, got axes "
                             f"{devices.axis_names}; build one with ray_mesh(devices)")
        return devices
    available = jax.devices()
    if devices is None:
        chosen = available
    elif isinstance(devices, int | np.integer):
        if not 1 <= devices <= len(available):
            raise ValueError(
                f"asked for {devices} devices but {len(available)} are available "
                f"({available[0].platform}); on a CPU, more can be simulated by setting "
                "XLA_FLAGS=--xla_force_host_platform_device_count=N before importing jax")
        chosen = available[:int(devices)]
    else:
        chosen = list(devices)
        if not chosen:
            raise ValueError("devices must not be empty")
    return Mesh(np.array(chosen), (RAY_AXIS,))


def _spec(axis: int | None) -> PartitionSpec:
    """Partition spec splitting dimension ``axis`` over the ray axis (``None``: replicated)."""
    if axis is None:
        return PartitionSpec()
    return PartitionSpec(*([None] * axis), RAY_AXIS)


def _check_axes(axes, what: str) -> None:
    for axis in jax.tree_util.tree_leaves(axes, is_leaf=lambda a: a is None):
        if axis is not None and (not isinstance(axis, int | np.integer) or axis < 0):
            raise ValueError(f"{what} must hold non-negative ints or None, got {axis!r}")


def shard_rays(kernel: Callable, ray_axes: Sequence[int | None], out_axes=0,
               devices: int | Sequence | Mesh | None = None) -> Callable:
    """Split a ray-wise JAX kernel's rays over devices; shared inputs stay replicated.

    Parameters
    ----------
    kernel : callable
        ``kernel(*args) -> out``, JAX-traceable, ray-wise (module docstring). Bind keyword or
        static arguments with :func:`functools.partial` first.
    ray_axes : sequence of (int or None)
        One entry per positional argument: the axis of its rays (applied to every array of
        that argument, which may be a pytree), or ``None`` for an input shared by all rays.
    out_axes : int or pytree of int, optional
        Ray axis of the output (default 0), or a pytree of axes matching the output.
    devices : int, sequence of jax.Device, Mesh or None, optional
        Devices to split over, as in :func:`ray_mesh` (default all).

    Returns
    -------
    callable
        ``sharded(*args) -> out``, equal to ``kernel(*args)`` up to floating-point
        round-off, jit-compatible and differentiable; its outputs are sharded over the mesh.

    Examples
    --------
    >>> from functools import partial
    >>> from operators.rte import emission_radiance
    >>> radiance = shard_rays(partial(emission_radiance, batch_rays=64),
    ...                       ray_axes=(None, 1, 0))          # tables, fields, lengths
    >>> # radiance(tables, fields, lengths) has the rays of each device's block in parallel
    """
    ray_axes = tuple(ray_axes)
    _check_axes(ray_axes, "ray_axes")
    _check_axes(out_axes, "out_axes")
    if all(axis is None for axis in ray_axes):
        raise ValueError("at least one argument must be ray-wise (an int in ray_axes)")
    mesh = ray_mesh(devices)
    n_devices = mesh.devices.size
    in_specs = tuple(_spec(axis) for axis in ray_axes)
    out_specs = jax.tree_util.tree_map(_spec, out_axes)
    mapped = jax.shard_map(kernel, mesh=mesh, in_specs=in_specs, out_specs=out_specs,
                           check_vma=False)

    def sharded(*args):
        if len(args) != len(ray_axes):
            raise TypeError(f"the sharded kernel takes {len(ray_axes)} positional arguments "
                            f"(one per entry of ray_axes), got {len(args)}")
        n_rays = _ray_count(args, ray_axes)
        pad = -n_rays % n_devices
        padded = tuple(arg if axis is None or pad == 0 else
                       jax.tree_util.tree_map(lambda a, ax=axis: _pad_edge(a, ax, pad), arg)
                       for arg, axis in zip(args, ray_axes, strict=True))
        out = mapped(*padded)
        if pad == 0:
            return out
        return jax.tree_util.tree_map(
            lambda axis, a: jax.lax.slice_in_dim(a, 0, n_rays, axis=axis), out_axes, out)

    sharded.mesh = mesh
    return sharded


def _ray_count(args, ray_axes) -> int:
    counts = {int(jnp.shape(a)[axis])
              for arg, axis in zip(args, ray_axes, strict=True) if axis is not None
              for a in jax.tree_util.tree_leaves(arg)}
    if len(counts) != 1:
        raise ValueError(f"ray-wise arguments disagree on the number of rays: {sorted(counts)}")
    return counts.pop()


def _pad_edge(array, axis: int, pad: int):
    widths = [(0, 0)] * jnp.ndim(array)
    widths[axis] = (0, pad)
    return jnp.pad(array, widths, mode="edge")


def place_rays(tree, axis: int = 0, devices: int | Sequence | Mesh | None = None):
    """Pad ray-wise arrays to a whole number of rays per device and split them over the mesh.

    Use it for constant ray-wise inputs (ray geometry) so that they are cut and moved to the
    devices once, not at every call; :func:`shard_rays` then needs no padding.

    Parameters
    ----------
    tree : pytree of arrays
        Ray-wise arrays, rays along ``axis``.
    axis : int, optional
        Ray axis (default 0).
    devices : as in :func:`ray_mesh`

    Returns
    -------
    The same pytree with :class:`jax.Array` leaves sharded over :data:`RAY_AXIS`, padded by
    repeating the last ray; the outputs of those rays are to be dropped.
    """
    mesh = ray_mesh(devices)

    def place(array):
        array = np.asarray(array)
        pad = -array.shape[axis] % mesh.devices.size
        widths = [(0, 0)] * array.ndim
        widths[axis] = (0, pad)
        array = np.pad(array, widths, mode="edge") if pad else array
        return jax.device_put(array, NamedSharding(mesh, _spec(axis)))

    return jax.tree_util.tree_map(place, tree)


def replicate(tree, devices: int | Sequence | Mesh | None = None):
    """Place every array of ``tree`` on every device of the mesh (shared inputs, constants).

    Parameters
    ----------
    tree : pytree of arrays
    devices : as in :func:`ray_mesh`

    Returns
    -------
    The same pytree with fully replicated :class:`jax.Array` leaves.
    """
    return jax.device_put(tree, NamedSharding(ray_mesh(devices), PartitionSpec()))
