r"""Compiled arithmetic of the emission kernel's Numba sweeps (:mod:`operators.rte.numba_source`).

**Subnormal numbers.** Each sweep flushes subnormal numbers to zero while it runs a ray, as XLA
does on its own threads (:func:`flush_subnormals`, x86 only), and gives the thread back its
mode after (:func:`restore_control`): Numba's threads inherit the mode of the thread that
starts them, an XLA thread (flushing) or Python's main thread (not), so without this the
results would depend on which came first (on the paper's scene, 0.17 % of the radiances and
0.23 % of the reverse sweep's cotangents differed, by under 5e-39 of the largest); and a
subnormal operand or result costs an Intel processor many cycles (the reverse sweep on one
thread, on that scene: 600–681 ms keeping them, 370–392 ms flushing them;
``docs/performance.md``).

**Vector width.** Each sweep's loop body asks LLVM for the processor's widest vectors
(:func:`wide_vectors`): LLVM tunes Intel's AVX-512 processors to 256-bit vectors, and on one (a
two-core Xeon, Emerald Rapids) 512-bit ones took 14–21 % off the forward sweep, 14–18 % off
the reverse and 21–25 % off the forward-mode one (synthetic rays of the paper's size,
``docs/performance.md``); processors without AVX-512 compile as before.

**Absorptance.** The sweeps need each segment's absorptance :math:`1 - e^{-\tau}` only
(:func:`absorptance`): the transmittance in front of the next segment is
:math:`P - P (1 - e^{-\tau})`. float32 uses a vectorizable exponential (:func:`_expm1_parts`)
that gives the absorptance without cancellation where :math:`\tau` is small, in one fused
multiply-add that fast-math rewriting leaves whole (:func:`_fma`); float64 uses
``math.expm1``.

**Table rows.** :func:`cubic` and :func:`slope` evaluate a cubic of the tables
(:attr:`operators.rte.tables.RTETables.coef`) and its offset derivative at one wavenumber.
"""

from __future__ import annotations

import math
import platform

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic, overload


@intrinsic
def _float32_from_bits(typingctx, bits):
    """The float32 whose IEEE bits are the int32 ``bits`` (a bit cast, vectorizable)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.FloatType())
    return types.float32(types.int32), codegen


@intrinsic
def _fma(typingctx, x, y, z):
    """``x * y + z`` rounded once (float32): LLVM's ``fma``, which no fast-math rewriting
    splits or reassociates."""
    def codegen(context, builder, signature, args):
        single = ir.FloatType()
        fma = builder.module.declare_intrinsic("llvm.fma", [single],
                                                ir.FunctionType(single, [single] * 3))
        return builder.call(fma, args)
    return types.float32(types.float32, types.float32, types.float32), codegen


#: The bits of x86's floating-point control register (MXCSR) that flush subnormal results to
#: zero (FTZ, bit 15) and read subnormal operands as zero (DAZ, bit 6).
_FLUSH_BITS = 0x8040
#: Whether the processor is an x86 one (elsewhere the sweeps leave the floating-point mode).
X86 = platform.machine().lower() in ("x86_64", "amd64", "i386", "i686")


def _mxcsr_call(builder, name, word):
    """Call LLVM's x86 intrinsic ``name`` (``stmxcsr``: store MXCSR into the int32 at
    ``word``; ``ldmxcsr``: load it from there)."""
    signature = ir.FunctionType(ir.VoidType(), [word.type])
    builder.call(cgutils.get_or_insert_function(builder.module, signature,
                                                f"llvm.x86.sse.{name}"), [word])


@intrinsic
def flush_subnormals(typingctx):
    """Make this thread's float arithmetic flush subnormal numbers to zero (x86: FTZ and DAZ in
    MXCSR; elsewhere nothing) and return the previous control word for
    :func:`restore_control`."""
    def codegen(context, builder, signature, args):
        if not X86:
            return ir.Constant(ir.IntType(32), 0)
        word = cgutils.alloca_once(builder, ir.IntType(32))
        _mxcsr_call(builder, "stmxcsr", word)
        previous = builder.load(word)
        builder.store(builder.or_(previous, ir.Constant(ir.IntType(32), _FLUSH_BITS)), word)
        _mxcsr_call(builder, "ldmxcsr", word)
        return previous
    return types.uint32(), codegen


@intrinsic
def restore_control(typingctx, previous):
    """Give this thread's float arithmetic back the control word ``previous`` that
    :func:`flush_subnormals` returned."""
    def codegen(context, builder, signature, args):
        if X86:
            word = cgutils.alloca_once(builder, ir.IntType(32))
            builder.store(args[0], word)
            _mxcsr_call(builder, "ldmxcsr", word)
        return context.get_dummy_value()
    return types.none(types.uint32), codegen


@intrinsic
def wide_vectors(typingctx):
    """Let LLVM's vectorizer use the processor's widest vectors in the function that calls
    this (the body of a ``prange`` loop): LLVM's attribute ``prefer-vector-width`` at 512 bits.
    LLVM tunes Intel's AVX-512 processors to 256-bit vectors by default; on processors without
    512-bit vectors the attribute changes nothing."""
    def codegen(context, builder, signature, args):
        # llvmlite's FunctionAttributes accepts only keyword attributes; this one is a string
        # attribute, written into the function's IR as it stands
        set.add(builder.function.attributes, '"prefer-vector-width"="512"')
        return context.get_dummy_value()
    return types.none(), codegen


@numba.njit(fastmath=True, inline="always")
def _expm1_parts(x):
    r""":math:`e^{-x} = (1 + m)\,2^k` in float32 for :math:`x \ge 0`: ``(m, 2**k)``, with
    ``m`` :math:`= e^r - 1` (:math:`|r| \le \ln 2 / 2`, no cancellation: for
    :math:`x < 0.35`, :math:`k = 0` and ``-m`` is the absorptance :math:`1 - e^{-x}`).
    Range reduction by ln 2, then :math:`e^r - 1 \approx r + r^2 p(r)` with :math:`p` of
    degree 4, fitted for relative error (weighted least squares on 4000 Chebyshev nodes of
    :math:`|r| \le \ln 2 / 2`, reweighted towards the minimax fit): 1.4e-8 with the float32
    coefficients, an eighth of float32's spacing at 1; underflows to 2**-126 below
    e^-87.3."""
    v = max(-x, np.float32(-87.3))
    k = np.floor(v * np.float32(1.44269504) + np.float32(0.5))  # float32 throughout
    r = v - k * np.float32(0.693359375) - k * np.float32(-2.12194440e-4)
    p = np.float32(1.3858254533e-03)
    p = p * r + np.float32(8.3666723222e-03)
    p = p * r + np.float32(4.1667595506e-02)
    p = p * r + np.float32(1.6666541994e-01)
    p = p * r + np.float32(4.9999997020e-01)
    return p * r * r + r, _float32_from_bits((np.int32(k) + np.int32(127)) << np.int32(23))


def absorptance(tau):
    r"""Absorptance :math:`1 - e^{-\tau}` of a segment's optical depth ``tau``, accurate where
    :math:`\tau` is small, for compiled code only (Numba picks the implementation by the type
    of ``tau``). The sweeps carry the transmittance in front of a segment, :math:`P`, to the
    next as :math:`P - P (1 - e^{-\tau})`."""
    raise TypeError("absorptance is compiled by Numba; call it from jitted code")


@overload(absorptance, inline="always", fastmath=True)
def _absorptance_for(tau):
    if tau == types.float64:
        return lambda tau: -math.expm1(-tau)

    def float32(tau):
        # (1 - 2**k) - m 2**k rounded once: exactly -m where k = 0, with no cancellation
        m, scale = _expm1_parts(tau)
        return _fma(-m, scale, np.float32(1.0) - scale)
    return float32


@numba.njit(fastmath=True, inline="always")
def cubic(c, row, j, u):
    """Value of the cubic in rows ``row … row + 3`` of ``c`` at wavenumber ``j``."""
    return ((c[row, j] * u + c[row + 1, j]) * u + c[row + 2, j]) * u + c[row + 3, j]


@numba.njit(fastmath=True, inline="always")
def slope(c, row, j, u):
    """Offset derivative of :func:`cubic` (in ``c``'s precision: an integer factor would
    promote float32 to float64)."""
    three, two = c.dtype.type(3), c.dtype.type(2)
    return (three * c[row, j] * u + two * c[row + 1, j]) * u + c[row + 2, j]
