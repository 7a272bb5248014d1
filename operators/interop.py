"""The one place where arrays cross between NumPy, JAX and torch.

Conversions go through DLPack where the source allows it (no copy on the same device) and
fall back to a NumPy copy otherwise. Every framework adapter in :mod:`operators` uses these
functions, never ad-hoc conversions. torch is imported only by :func:`to_torch` and
``TORCH_DTYPES``: a torch tensor can only be given here once torch has been imported.
"""

from __future__ import annotations

import sys

import jax
import jax.numpy as jnp
import numpy as np


def _is_torch_tensor(x) -> bool:
    torch = sys.modules.get("torch")
    return torch is not None and isinstance(x, torch.Tensor)


def __getattr__(name):
    """``TORCH_DTYPES``: the torch dtype of each NumPy floating-point dtype that the framework
    adapters support, built (importing torch) when first asked for."""
    if name == "TORCH_DTYPES":
        import torch

        return {np.dtype(np.float32): torch.float32, np.dtype(np.float64): torch.float64}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def to_numpy(x) -> np.ndarray:
    """Return ``x`` (NumPy, JAX or torch array, or array-like) as a NumPy array.

    JAX and torch CPU arrays are viewed without a copy where possible; device arrays are
    copied to the host.
    """
    if isinstance(x, np.ndarray):
        return x
    if _is_torch_tensor(x):
        return x.detach().cpu().numpy()
    return np.asarray(x)


def to_jax(x, dtype=None) -> jax.Array:
    """Return ``x`` as a JAX array (DLPack from torch, a view of NumPy memory where possible).

    Parameters
    ----------
    x : array_like or torch.Tensor
        Input array.
    dtype : dtype, optional
        Cast to this dtype after conversion.
    """
    if _is_torch_tensor(x):
        x = jax.dlpack.from_dlpack(x.detach().contiguous())
    out = jnp.asarray(x)
    return out if dtype is None else out.astype(dtype)


def to_torch(x, dtype=None, device=None):
    """Return ``x`` as a torch tensor (DLPack from JAX, shared memory from NumPy).

    Parameters
    ----------
    x : array_like or jax.Array
        Input array.
    dtype : torch.dtype, optional
        Cast to this dtype after conversion.
    device : torch.device or str, optional
        Move to this device after conversion.

    Returns
    -------
    torch.Tensor
    """
    import torch

    if isinstance(x, torch.Tensor):
        out = x
    elif isinstance(x, jax.Array):
        out = torch.from_dlpack(x)
    else:
        out = torch.from_numpy(np.require(x, requirements=["C", "W"]))
    return out.to(dtype=dtype, device=device)
