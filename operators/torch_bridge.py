"""A JAX function as a differentiable torch function (reverse mode).

:func:`torch_function` wraps ``fun(*arrays) -> array``, written in JAX, as a callable on torch
tensors that torch autograd differentiates: the forward pass runs :func:`jax.vjp` (so a custom
VJP of ``fun``, such as the memory-lean one of :func:`operators.rte.kernel.emission_radiance`,
keeps only its own residuals) and the backward pass calls the pullback it returned. Arrays
cross between the frameworks through :mod:`operators.interop` (DLPack, no copy on CPU).

Pass a jitted ``fun`` and keep input shapes fixed between calls so that JAX compiles once::

    kernel = jax.jit(lambda f, s: emission_radiance(tables, f, s, batch_rays))
    radiance = torch_function(kernel)(fields, lengths)   # torch tensors in and out
    radiance.sum().backward()                             # runs the kernel's VJP
"""

from __future__ import annotations

import jax
import numpy as np
import torch

from operators.base import precision
from operators.interop import to_jax, to_torch


def _jax_dtype(tensors):
    """The precision JAX computes in for these tensors: float64 when any of them is."""
    return np.float64 if any(t.dtype == torch.float64 for t in tensors) else np.float32


class _JaxFunction(torch.autograd.Function):
    """Autograd node of one call: forward through ``jax.vjp``, backward through its pullback."""

    @staticmethod
    def forward(ctx, fun, *tensors):
        ctx.dtype = _jax_dtype(tensors)
        with precision(ctx.dtype):
            value, pullback = jax.vjp(fun, *(to_jax(t) for t in tensors))
        ctx.pullback = pullback
        ctx.devices = [t.device for t in tensors]
        return to_torch(value, device=tensors[0].device)

    @staticmethod
    def backward(ctx, cotangent):
        with precision(ctx.dtype):
            grads = ctx.pullback(to_jax(cotangent))
        del ctx.pullback
        return (None, *(to_torch(g, device=d) for g, d in zip(grads, ctx.devices, strict=True)))


def torch_function(fun):
    """Torch-differentiable version of a JAX function of arrays.

    Parameters
    ----------
    fun : callable
        JAX function ``fun(*arrays) -> array`` (preferably jitted), differentiable in reverse
        mode with respect to every argument.

    Returns
    -------
    callable
        ``f(*tensors) -> tensor``: converts the tensors to JAX arrays, evaluates ``fun`` and
        returns the result as a tensor on the first input's device; ``backward`` through it
        applies ``fun``'s vector-Jacobian product. Inputs must be floating-point tensors of
        the dtype ``fun`` expects (the gradient has the input's dtype and shape).
    """

    def call(*tensors):
        if not tensors or not all(isinstance(t, torch.Tensor) for t in tensors):
            raise TypeError("torch_function expects torch tensors as arguments; got "
                            + ", ".join(type(t).__name__ for t in tensors))
        return _JaxFunction.apply(fun, *tensors)

    call.__name__ = getattr(fun, "__name__", "jax_function")
    return call
