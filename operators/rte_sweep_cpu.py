r"""The emission kernel's reverse sweep compiled for CPUs by Numba: one pass over memory.

The reverse sweep of :mod:`operators.rte_kernel` (module notes there: the derivatives, the
segment weights, the table rows) needs, per segment of a ray, the optical depth and Planck
spectra from gathered table rows, the running sums :math:`P_k` and :math:`I_{\le k}`, and
``n_tau + 1`` sums over wavenumber. XLA's CPU backend does not fuse a gathered row into its
several consumers and writes each intermediate spectrum of a ray batch to memory; here one ray
is swept at a time, its spectra (a few KiB each) stay in the core's cache, and the table rows
are read twice per segment: once for :math:`\tau` and :math:`\partial\tau/\partial u`, once
for the sums. Rays run in parallel over the CPU's cores (``numba.prange``).

float32 uses a vectorizable exponential (:func:`_exp_neg`, the Cephes ``expf`` polynomial)
and the kernel's absorptance series; float64 uses ``math.exp`` and ``expm1``. The JAX reverse
sweep (:func:`operators.rte_kernel._sweep_vjp`) stays the one of other backends and the
reference this one is tested against (``tests/operators/test_rte_sweep_cpu.py``);
``benchmarks/bench_rte.py`` times both.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic, overload

__all__ = ["sweep_vjp"]


@intrinsic
def _float32_from_bits(typingctx, bits):
    """The float32 whose IEEE bits are the int32 ``bits`` (a bit cast, vectorizable)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.FloatType())
    return types.float32(types.int32), codegen


@numba.njit(fastmath=True, inline="always")
def _exp_neg(x):
    r""":math:`e^{-x}` in float32 for :math:`x \ge 0` (underflows to 2**-126 below e^-87.3):
    range reduction by ln 2 and the Cephes degree-6 polynomial."""
    v = max(-x, np.float32(-87.3))
    k = np.floor(v * np.float32(1.44269504) + np.float32(0.5))  # float32 throughout
    r = v - k * np.float32(0.693359375) - k * np.float32(-2.12194440e-4)
    p = np.float32(1.9875691500e-4)
    p = p * r + np.float32(1.3981999507e-3)
    p = p * r + np.float32(8.3334519073e-3)
    p = p * r + np.float32(4.1665795894e-2)
    p = p * r + np.float32(1.6666665459e-1)
    p = p * r + np.float32(5.0000001201e-1)
    p = p * r * r + r + np.float32(1.0)
    return p * _float32_from_bits((np.int32(k) + np.int32(127)) << np.int32(23))


def _transmission(tau):
    """Transmittance and absorptance as :func:`operators.rte_kernel._transmission`, for
    compiled code only (Numba picks the implementation by the type of ``tau``)."""
    raise TypeError("_transmission is compiled by Numba; call it from jitted code")


@overload(_transmission, inline="always", fastmath=True)
def _transmission_for(tau):
    if tau == types.float64:
        return lambda tau: (math.exp(-tau), -math.expm1(-tau))

    def float32(tau):
        t = _exp_neg(tau)
        series = np.float32(1.0) - tau * np.float32(1 / 6)
        for n in (5, 4, 3, 2):
            series = np.float32(1.0) - tau * np.float32(1 / n) * series
        return t, tau * series if tau < np.float32(0.1) else np.float32(1.0) - t
    return float32


@numba.njit(fastmath=True, inline="always")
def _cubic(c, row, j, u):
    """Value of the cubic in rows ``row … row + 3`` of ``c`` at wavenumber ``j``."""
    return ((c[row, j] * u + c[row + 1, j]) * u + c[row + 2, j]) * u + c[row + 3, j]


@numba.njit(fastmath=True, inline="always")
def _slope(c, row, j, u):
    """Offset derivative of :func:`_cubic`."""
    return (3 * c[row, j] * u + 2 * c[row + 1, j]) * u + c[row + 2, j]


@numba.njit(fastmath=True, parallel=True, cache=True)
def _sweep_vjp(coef, index, amount, offset, n_segments, n_gas, radiance, cotangent, order):
    n_rays, n_seg, n_tau = amount.shape
    n_eta = coef.shape[2]
    soot, planck_row = n_tau > n_gas, n_tau + 3 * n_gas
    d_weights = np.zeros((n_rays, n_seg, n_tau + 1), coef.dtype)
    transmittance = np.empty((n_rays, n_eta), coef.dtype)
    for q in numba.prange(n_rays):
        i = order[q]
        partial_sum = np.zeros(n_eta, coef.dtype)
        through = np.ones(n_eta, coef.dtype)
        tau = np.empty(n_eta, coef.dtype)
        tau_offset = np.empty(n_eta, coef.dtype)
        g_tau = np.empty(n_eta, coef.dtype)
        for k in range(n_segments[i]):
            c, u = coef[index[i, k]], offset[i, k]
            tau[:] = 0
            tau_offset[:] = 0
            for s in range(n_gas):
                a = amount[i, k, s]
                for j in range(n_eta):
                    tau[j] += a * _cubic(c, 4 * s, j, u)
                    tau_offset[j] += a * _slope(c, 4 * s, j, u)
            if soot:
                a = amount[i, k, n_gas]
                for j in range(n_eta):
                    tau[j] += a * c[4 * n_gas, j]
            d_offset = coef.dtype.type(0)
            for j in range(n_eta):
                emission = _cubic(c, planck_row, j, u)
                t, absorptance = _transmission(tau[j])
                absorbed = through[j] * absorptance
                partial_sum[j] += emission * absorbed
                through[j] *= t
                g = cotangent[i, j] * (through[j] * emission - (radiance[i, j] - partial_sum[j]))
                g_tau[j] = g
                d_offset += g * tau_offset[j] + (cotangent[i, j] * absorbed
                                                 * _slope(c, planck_row, j, u))
            d_weights[i, k, n_tau] = d_offset
            for s in range(n_gas):
                total = coef.dtype.type(0)
                for j in range(n_eta):
                    total += g_tau[j] * _cubic(c, 4 * s, j, u)
                d_weights[i, k, s] = total
            if soot:
                total = coef.dtype.type(0)
                for j in range(n_eta):
                    total += g_tau[j] * c[4 * n_gas, j]
                d_weights[i, k, n_gas] = total
        transmittance[i] = through
    return d_weights, transmittance


def sweep_vjp(coef, index, amount, offset, n_segments, radiance, cotangent, *, n_gas):
    r"""Cotangents of the segment weights of every ray, and each ray's transmittance.

    The reverse sweep of :func:`operators.rte_kernel._sweep_vjp` for all rays at once, with
    the Planck spline (``planck == "table"``): per segment, camera side first, the sums over
    wavenumber of :math:`g_\tau` times each row of :math:`\tau` (the amounts' cotangents) and of
    :math:`g_\tau\,\partial\tau/\partial u + g_B\,\partial B/\partial u` (the offset's).

    Parameters
    ----------
    coef : ndarray, shape (n_intervals, n_rows, n_eta)
        :attr:`operators.rte_tables.RTETables.coef` (float32 or float64).
    index : ndarray of int, shape (n_rays, n_seg)
        Temperature interval of each segment.
    amount : ndarray, shape (n_rays, n_seg, n_tau)
        Amounts :math:`X_s \Delta s / T` (m/K) per gas, then the soot's :math:`f_v \Delta s` (m).
    offset : ndarray, shape (n_rays, n_seg)
        Offset :math:`u \in [0, 1]` in the temperature interval.
    n_segments : ndarray of int, shape (n_rays,)
        Segments of each ray (those after are padding, their cotangents zero).
    radiance, cotangent : ndarray, shape (n_rays, n_eta)
        The kernel's radiance in W/(m²·sr·cm⁻¹) (background included) and its cotangent.
    n_gas : int
        Absorbing gases (``n_tau - n_gas`` is 1 with soot, else 0).

    Returns
    -------
    d_weights : ndarray, shape (n_rays, n_seg, n_tau + 1)
        Cotangents of the amounts, then of the offset.
    transmittance : ndarray, shape (n_rays, n_eta)
        Each ray's transmittance :math:`\tau_\mathrm{ray}` (the background's cotangent is
        ``cotangent * transmittance``).
    """
    dtype = np.asarray(coef).dtype
    n_segments = np.asarray(n_segments, np.int64)
    # longest rays first, so that the cores' last rays are short ones
    order = np.argsort(-n_segments, kind="stable")
    return _sweep_vjp(np.ascontiguousarray(coef), np.asarray(index, np.int64),
                      np.asarray(amount, dtype), np.asarray(offset, dtype), n_segments,
                      int(n_gas), np.asarray(radiance, dtype), np.asarray(cotangent, dtype),
                      order)
