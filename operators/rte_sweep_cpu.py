r"""The emission kernel's sweeps compiled for CPUs by Numba: forward, forward-mode, reverse.

The sweeps of :mod:`operators.rte_kernel` (module notes there: the derivatives, the segment
weights, the table rows) need, per segment of a ray, the optical depth and Planck spectra
from gathered table rows and the running products :math:`P_k`; the forward-mode sweep also
the tangents of the optical depth, the reverse sweep the running sums :math:`I_{\le k}` and
``n_tau + 1`` sums over wavenumber. XLA's CPU backend does not fuse a gathered row into its
several consumers and writes each intermediate spectrum of a ray batch to memory; here one ray
is swept at a time, camera side first, its spectra (a few KiB each) stay in the core's cache,
and each table row is read once per segment. Rays run in parallel over the CPU's cores
(``numba.prange``), longest first. The forward and forward-mode sweeps take two consecutive
segments of a ray that lie in the same temperature interval (most do) in one pass, their table
rows and running spectra read once for both; the reverse sweep, which holds ``n_tau + 1`` sums
per segment, takes one at a time (two were slower with 256-bit vectors; with 512-bit ones they
changed its time by −8 to +1 % in five trials, too little for a second loop).

Each segment (or pair) is one pass over wavenumber: every gas's row of the optical depth, its offset
derivative, the Planck spline, the transmission and the running sums, held in registers from
one to the next. For that the compiler needs the gases written out one by one (a loop over a
count known only at run time, inside the loop over wavenumber, is not vectorized: 8 × slower
in a trial), so the sweeps' source is a template, :data:`_KERNELS`, whose per-gas lines
:func:`_kernels` writes for the tables' number of gases into a file of its own
(:func:`_source_file`), one per float dtype, which Numba compiles on first use (2–6 s per sweep
in float32 on two cores, first-call times) and caches on disk.

XLA runs each sweep on its own buffers: :func:`target` names a handler of XLA's typed FFI
(:mod:`operators.xla_ffi`) that reads the operands and writes the results in place, where a
host callback (:func:`jax.pure_callback`) would copy both (about 4 ms of a forward evaluation and
12 ms of a gradient's at the paper's size, ``docs/performance.md``).

Each sweep flushes subnormal numbers to zero while it runs a ray, as XLA does on its own
threads (:func:`_flush_subnormals`, x86 only), and gives the thread back its mode after: Numba's
threads inherit the mode of the thread that starts them, an XLA thread (flushing) or Python's
main thread (not), so without this the results would depend on which came first (on the paper's
scene, 0.17 % of the radiances and 0.23 % of the reverse sweep's cotangents differed, by under
5e-39 of the largest); and a subnormal operand or result costs an Intel processor many cycles
(the reverse sweep on one thread, on that scene: 600–681 ms keeping them, 370–392 ms flushing
them; ``docs/performance.md``).

Each sweep's loop body asks LLVM for the processor's widest vectors (:func:`_wide_vectors`):
LLVM tunes Intel's AVX-512 processors to 256-bit vectors, and on one (a two-core Xeon, Emerald
Rapids) 512-bit ones took 14–21 % off the forward sweep, 14–18 % off the reverse and 21–25 % off
the forward-mode one (synthetic rays of the paper's size, ``docs/performance.md``); processors
without AVX-512 compile as before.

The sweeps need each segment's absorptance :math:`1 - e^{-\tau}` only (:func:`_absorptance`):
the transmittance in front of the next segment is :math:`P - P (1 - e^{-\tau})`. float32 uses a
vectorizable exponential (:func:`_expm1_parts`) that gives the absorptance without cancellation
where :math:`\tau` is small, in one fused multiply-add that fast-math rewriting leaves whole
(:func:`_fma`); float64 uses ``math.expm1``. The XLA sweeps of
:mod:`operators.rte_kernel` stay those of other backends and the reference these are tested
against (``tests/operators/test_rte_sweep_cpu.py``); ``benchmarks/bench_rte.py`` times both.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import math
import os
import platform
import sys
import tempfile
from pathlib import Path
from types import ModuleType

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic, overload

from operators.disk_cache import cache_dir
from operators.xla_ffi import HANDLER, register

__all__ = ["KINDS", "target"]


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
_X86 = platform.machine().lower() in ("x86_64", "amd64", "i386", "i686")


def _mxcsr_call(builder, name, word):
    """Call LLVM's x86 intrinsic ``name`` (``stmxcsr``: store MXCSR into the int32 at
    ``word``; ``ldmxcsr``: load it from there)."""
    signature = ir.FunctionType(ir.VoidType(), [word.type])
    builder.call(cgutils.get_or_insert_function(builder.module, signature,
                                                f"llvm.x86.sse.{name}"), [word])


@intrinsic
def _flush_subnormals(typingctx):
    """Make this thread's float arithmetic flush subnormal numbers to zero (x86: FTZ and DAZ in
    MXCSR; elsewhere nothing) and return the previous control word for
    :func:`_restore_control`."""
    def codegen(context, builder, signature, args):
        if not _X86:
            return ir.Constant(ir.IntType(32), 0)
        word = cgutils.alloca_once(builder, ir.IntType(32))
        _mxcsr_call(builder, "stmxcsr", word)
        previous = builder.load(word)
        builder.store(builder.or_(previous, ir.Constant(ir.IntType(32), _FLUSH_BITS)), word)
        _mxcsr_call(builder, "ldmxcsr", word)
        return previous
    return types.uint32(), codegen


@intrinsic
def _restore_control(typingctx, previous):
    """Give this thread's float arithmetic back the control word ``previous`` that
    :func:`_flush_subnormals` returned."""
    def codegen(context, builder, signature, args):
        if _X86:
            word = cgutils.alloca_once(builder, ir.IntType(32))
            builder.store(args[0], word)
            _mxcsr_call(builder, "ldmxcsr", word)
        return context.get_dummy_value()
    return types.none(types.uint32), codegen


@intrinsic
def _wide_vectors(typingctx):
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


def _absorptance(tau):
    r"""Absorptance :math:`1 - e^{-\tau}` of a segment's optical depth ``tau``, accurate where
    :math:`\tau` is small, for compiled code only (Numba picks the implementation by the type
    of ``tau``). The sweeps carry the transmittance in front of a segment, :math:`P`, to the
    next as :math:`P - P (1 - e^{-\tau})`."""
    raise TypeError("_absorptance is compiled by Numba; call it from jitted code")


@overload(_absorptance, inline="always", fastmath=True)
def _absorptance_for(tau):
    if tau == types.float64:
        return lambda tau: -math.expm1(-tau)

    def float32(tau):
        # (1 - 2**k) - m 2**k rounded once: exactly -m where k = 0, with no cancellation
        m, scale = _expm1_parts(tau)
        return _fma(-m, scale, np.float32(1.0) - scale)
    return float32


@numba.njit(fastmath=True, inline="always")
def _cubic(c, row, j, u):
    """Value of the cubic in rows ``row … row + 3`` of ``c`` at wavenumber ``j``."""
    return ((c[row, j] * u + c[row + 1, j]) * u + c[row + 2, j]) * u + c[row + 3, j]


@numba.njit(fastmath=True, inline="always")
def _slope(c, row, j, u):
    """Offset derivative of :func:`_cubic` (in ``c``'s precision: an integer factor would
    promote float32 to float64)."""
    three, two = c.dtype.type(3), c.dtype.type(2)
    return (three * c[row, j] * u + two * c[row + 1, j]) * u + c[row + 2, j]


_KERNELS = """import numba
import numpy as np

from operators.rte_sweep_cpu import (_absorptance, _cubic, _flush_subnormals, _restore_control,
                                      _slope, _wide_vectors)
from operators.xla_ffi import argument, executing, no_error, result

DTYPE, INDEX = np.{dtype}, np.int32


@numba.njit(inline="always")
def common_operands(frame):
    return (argument(frame, 0, 3, DTYPE), argument(frame, 1, 2, INDEX),
            argument(frame, 2, 3, DTYPE), argument(frame, 3, 2, DTYPE),
            argument(frame, 4, 1, INDEX), argument(frame, 5, 1, INDEX))


@numba.njit(fastmath=True, inline="always")
def forward_step(c, j, u, {a_}through, partial):
    zero = c.dtype.type(0)
    {rows}
    seen = through * _absorptance({tau})
    return through - seen, partial + _cubic(c, {planck_row}, j, u) * seen


@numba.njit(fastmath=True, parallel=True, cache=True)
def forward(coef, index, amount, offset, n_segments, order, background, radiance):
    n_rays, n_eta = amount.shape[0], coef.shape[2]
    for q in numba.prange(n_rays):
        _wide_vectors()
        control = _flush_subnormals()
        i = order[q]
        partial_sum = np.zeros(n_eta, coef.dtype)
        through = np.ones(n_eta, coef.dtype)
        k = 0
        while k < n_segments[i]:
            c, u = coef[index[i, k]], offset[i, k]
            {amounts}
            if k + 1 < n_segments[i] and index[i, k + 1] == index[i, k]:
                v = offset[i, k + 1]
                {amounts_next}
                for j in range(n_eta):
                    th, ps = forward_step(c, j, u, {a_}through[j], partial_sum[j])
                    through[j], partial_sum[j] = forward_step(c, j, v, {b_}th, ps)
                k += 2
            else:
                for j in range(n_eta):
                    through[j], partial_sum[j] = forward_step(c, j, u, {a_}through[j],
                                                              partial_sum[j])
                k += 1
        b = min(i, background.shape[0] - 1)
        for j in range(n_eta):
            radiance[i, j] = partial_sum[j] + through[j] * background[b, j]
        _restore_control(control)


def forward_handler(frame):
    if executing(frame):
        forward(*common_operands(frame), argument(frame, 6, 2, DTYPE),
                result(frame, 0, 2, DTYPE))
    return no_error()


@numba.njit(fastmath=True, inline="always")
def forward_mode_step(c, j, u, du, {a_}{da_}through, partial, d_sum, depth):
    zero = c.dtype.type(0)
    {rows}
    tau_u = {tau_u}
    d_tau = {d_tau}
    emission = _cubic(c, {planck_row}, j, u)
    seen = through * _absorptance({tau})
    through -= seen
    d_sum += (seen * (du * _slope(c, {planck_row}, j, u) - emission * depth)
              + through * emission * d_tau)
    return through, partial + emission * seen, d_sum, depth + d_tau


@numba.njit(fastmath=True, parallel=True, cache=True)
def forward_mode(coef, index, amount, offset, n_segments, order, background, d_amount,
                 d_offset, d_background, radiance, d_radiance):
    n_rays, n_eta = amount.shape[0], coef.shape[2]
    for q in numba.prange(n_rays):
        _wide_vectors()
        control = _flush_subnormals()
        i = order[q]
        partial_sum = np.zeros(n_eta, coef.dtype)
        d_sum = np.zeros(n_eta, coef.dtype)
        through = np.ones(n_eta, coef.dtype)
        depth = np.zeros(n_eta, coef.dtype)  # tangent of the optical depth in front
        k = 0
        while k < n_segments[i]:
            c, u, du = coef[index[i, k]], offset[i, k], d_offset[i, k]
            {amounts}
            {d_amounts}
            if k + 1 < n_segments[i] and index[i, k + 1] == index[i, k]:
                v, dv = offset[i, k + 1], d_offset[i, k + 1]
                {amounts_next}
                {d_amounts_next}
                for j in range(n_eta):
                    th, ps, ds, dp = forward_mode_step(c, j, u, du, {a_}{da_}through[j],
                                                       partial_sum[j], d_sum[j], depth[j])
                    through[j], partial_sum[j], d_sum[j], depth[j] = forward_mode_step(
                        c, j, v, dv, {b_}{db_}th, ps, ds, dp)
                k += 2
            else:
                for j in range(n_eta):
                    through[j], partial_sum[j], d_sum[j], depth[j] = forward_mode_step(
                        c, j, u, du, {a_}{da_}through[j], partial_sum[j], d_sum[j], depth[j])
                k += 1
        b = min(i, background.shape[0] - 1)
        for j in range(n_eta):
            radiance[i, j] = partial_sum[j] + through[j] * background[b, j]
            d_radiance[i, j] = d_sum[j] + through[j] * (d_background[b, j]
                                                        - depth[j] * background[b, j])
        _restore_control(control)


def forward_mode_handler(frame):
    if executing(frame):
        forward_mode(*common_operands(frame), argument(frame, 6, 2, DTYPE),
                     argument(frame, 7, 3, DTYPE), argument(frame, 8, 2, DTYPE),
                     argument(frame, 9, 2, DTYPE), result(frame, 0, 2, DTYPE),
                     result(frame, 1, 2, DTYPE))
    return no_error()


@numba.njit(fastmath=True, inline="always")
def reverse_step(c, j, u, {a_}through, partial, radiance, cotangent, d_offset{_g}):
    zero = c.dtype.type(0)
    {rows}
    tau_u = {tau_u}
    emission = _cubic(c, {planck_row}, j, u)
    absorbed = through * _absorptance({tau})
    partial += emission * absorbed
    through -= absorbed
    g = cotangent * (through * emission - (radiance - partial))
    d_offset += g * tau_u + cotangent * absorbed * _slope(c, {planck_row}, j, u)
    return through, partial, d_offset{_sums_add}


@numba.njit(fastmath=True, parallel=True, cache=True)
def reverse(coef, index, amount, offset, n_segments, order, radiance, cotangent, d_weights,
            transmittance):
    n_rays, n_eta = amount.shape[0], coef.shape[2]
    zero = coef.dtype.type(0)
    for q in numba.prange(n_rays):
        _wide_vectors()
        control = _flush_subnormals()
        i = order[q]
        d_weights[i, n_segments[i]:] = zero
        partial_sum = np.zeros(n_eta, coef.dtype)
        through = np.ones(n_eta, coef.dtype)
        for k in range(n_segments[i]):
            c, u = coef[index[i, k]], offset[i, k]
            {amounts}
            d_offset{_g} = zero{_zeros}
            for j in range(n_eta):
                through[j], partial_sum[j], d_offset{_g} = reverse_step(
                    c, j, u, {a_}through[j], partial_sum[j], radiance[i, j], cotangent[i, j],
                    d_offset{_g})
            {store}
        if transmittance.shape[0] > 0:
            transmittance[i] = through
        _restore_control(control)


def reverse_handler(frame):
    if executing(frame):
        reverse(*common_operands(frame), argument(frame, 6, 2, DTYPE),
                argument(frame, 7, 2, DTYPE), result(frame, 0, 3, DTYPE),
                result(frame, 1, 2, DTYPE))
    return no_error()
"""
"""The three sweeps as Python source, each with its FFI handler (:func:`target`). The forward
and forward-mode sweeps take a segment, or two consecutive segments in the same temperature
interval (their table rows read once for both), in one pass over wavenumber, the reverse sweep
one segment; each sweep's step at one wavenumber is an inlined function. The sweeps write into
XLA's result buffers; a background of one row serves every ray. Each ``{…}`` stands for a
line, an expression or names written out gas by gas (:func:`_gas_code`), which
:func:`_kernels` fills in for the tables' gases, or for the float dtype."""


def _gas_code(n_gas: int, n_tau: int) -> dict[str, str]:
    """The parts of :data:`_KERNELS` that name each row of the optical depth: the gases'
    cubic rows ``4 s … 4 s + 3`` of the table, then the soot's row (constant in ``u``); the
    amounts and their tangents of a segment (``a``, ``da``) and of the one after it (``b``,
    ``db``), and the reverse sweep's sums over wavenumber (``g``)."""
    rows = [f"_cubic(c, {4 * s}, j, u)" for s in range(n_gas)] + [f"c[{4 * n_gas}, j]"] * (
        n_tau - n_gas)
    r, a, b, da, db, g = ([f"{name}{s}" for s in range(n_tau)]
                          for name in ("r", "a", "b", "da", "db", "g"))

    def assign(names, values):
        return f"{', '.join(names)} = {', '.join(values)}" if names else "pass"

    def total(terms):
        return " + ".join(terms) if terms else "zero"

    def before(names):  # names, each followed by a comma: a list that goes on
        return "".join(f"{name}, " for name in names)

    def after(names):  # names, each after a comma: a list that went before
        return "".join(f", {name}" for name in names)

    def taken(array, segment, n):  # the first n entries of a segment's row of the array
        return [f"{array}[i, {segment}, {s}]" for s in range(n)]

    return {
        "planck_row": str(n_tau + 3 * n_gas),
        "amounts": assign(a, taken("amount", "k", n_tau)),
        "amounts_next": assign(b, taken("amount", "k + 1", n_tau)),
        "d_amounts": assign(da, taken("d_amount", "k", n_tau)),
        "d_amounts_next": assign(db, taken("d_amount", "k + 1", n_tau)),
        "a_": before(a), "b_": before(b), "da_": before(da), "db_": before(db),
        "_g": after(g),
        "_zeros": after(["zero"] * n_tau),
        "rows": assign(r, rows),
        "tau": total([f"{a[s]} * {r[s]}" for s in range(n_tau)]),
        "tau_u": total([f"{a[s]} * _slope(c, {4 * s}, j, u)" for s in range(n_gas)]),
        "d_tau": total(["du * tau_u"] + [f"{da[s]} * {r[s]}" for s in range(n_tau)]),
        "_sums_add": after([f"{g[s]} + g * {r[s]}" for s in range(n_tau)]),
        "store": assign(taken("d_weights", "k", n_tau + 1), [*g, "d_offset"]),
    }


@functools.cache
def _kernels(n_gas: int, n_tau: int, dtype: str) -> ModuleType:
    """The sweeps of :data:`_KERNELS` for ``n_gas`` gases, ``n_tau`` rows of the optical
    depth (``n_tau - n_gas`` soot rows) and float ``dtype``: a module of ``forward``,
    ``forward_mode``, ``reverse`` and their handlers, compiled by Numba on first use and cached
    on disk (:func:`_source_file`)."""
    if not 0 <= n_gas <= n_tau <= n_gas + 1:
        raise ValueError(f"the sweeps take n_gas >= 0 gases and at most one soot row; got "
                         f"n_gas = {n_gas}, n_tau = {n_tau} rows of the optical depth")
    if dtype not in ("float32", "float64"):
        raise ValueError(f"the sweeps run in float32 or float64; got {dtype}")
    path = _source_file(_KERNELS.format(dtype=dtype, **_gas_code(n_gas, n_tau)),
                        f"sweeps_{n_gas}_gases_{n_tau - n_gas}_soot_{dtype}")
    spec = importlib.util.spec_from_file_location(f"{__name__}_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # where Numba's cache finds the sweeps' globals
    spec.loader.exec_module(module)
    return module


def _source_file(source: str, stem: str) -> Path:
    """``source`` as a Python file of its own, where Numba's disk cache can find it.

    The name carries a hash of the source and of this module, so a file once written never
    changes (Numba keys its cache on the file's time stamp; a change to the helpers here makes
    new files). A file found there is read back and used only if it holds ``source`` exactly;
    one that does not (damaged, cut short) is written again, which also gives it a new time
    stamp, so that Numba compiles it afresh. Each write fills a uniquely named temporary file,
    flushes it to disk and renames it over the file: no process reads half a file. The
    folder is ``sweeps`` in :func:`operators.disk_cache.cache_dir`, or, if that cannot be
    written, ``invflame-sweeps`` in the temporary directory.
    """
    digest = hashlib.sha256(source.encode() + Path(__file__).read_bytes()).hexdigest()[:16]
    folders = (cache_dir() / "sweeps", Path(tempfile.gettempdir()) / "invflame-sweeps")
    for folder in folders:
        path = folder / f"{stem}_{digest}.py"
        try:
            if not _holds(path, source):
                folder.mkdir(parents=True, exist_ok=True)
                fd, partial = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.")
                try:
                    with os.fdopen(fd, "w", encoding="utf-8") as handle:
                        handle.write(source)
                        handle.flush()
                        os.fsync(handle.fileno())
                    os.replace(partial, path)
                except BaseException:
                    os.unlink(partial)
                    raise
            return path
        except OSError as error:
            failure = error
    raise OSError(f"cannot write the compiled sweeps' source to {folders[0]} or "
                  f"{folders[1]}; set INVFLAME_CACHE to a writable folder") from failure


def _holds(path: Path, source: str) -> bool:
    """Whether the file ``path`` exists and holds ``source`` exactly."""
    try:
        return path.read_bytes() == source.encode()
    except FileNotFoundError:
        return False


#: The sweeps, by the names :func:`target` takes.
KINDS = ("forward", "forward_mode", "reverse")


@functools.cache
def target(kind: str, n_gas: int, n_tau: int, dtype) -> str:
    r"""The name of the :func:`jax.ffi.ffi_call` target that runs sweep ``kind`` on XLA's
    buffers (:mod:`operators.xla_ffi`), its handler compiled on first use (2–6 s, or loaded from
    Numba's disk cache).

    Every sweep takes, in this order: ``coef`` (n_intervals, n_rows, n_eta), the tables'
    coefficients (:attr:`operators.rte_tables.RTETables.coef`); ``index`` (n_rays, n_seg),
    int32, each segment's temperature interval; ``amount`` (n_rays, n_seg, n_tau), the amounts
    :math:`X_s \Delta s / T` (m/K) per gas, then the soot's :math:`f_v \Delta s` (m);
    ``offset`` (n_rays, n_seg), the offset :math:`u \in [0, 1]` in the interval;
    ``n_segments`` (n_rays,), int32, each ray's segments (those after are padding); ``order``
    (n_rays,), int32, the rays longest first (so that the cores' last rays are short ones).
    Floats in ``dtype``, radiances in W/(m²·sr·cm⁻¹). Then:

    ``"forward"``
        ``background`` (n_rays or 1, n_eta), the radiance behind each ray (one row: behind
        every ray) → the radiance (n_rays, n_eta),
        :math:`I = \sum_k B_k (1 - t_k) P_k + \tau_\mathrm{ray} I_\mathrm{bg}`.
    ``"forward_mode"``
        ``background``, ``d_amount``, ``d_offset`` (tangents shaped as ``amount`` and
        ``offset``), ``d_background`` (shaped as ``background``) → the radiance and its
        tangent: with :math:`D_k = \sum_{m<k} \dot\tau_m` the tangent of the optical depth in
        front of segment :math:`k` (:math:`\dot P_k = -P_k D_k`),
        :math:`\dot I = \sum_k P_k [(1 - t_k)(\dot B_k - B_k D_k) + t_k B_k \dot\tau_k]
        + \tau_\mathrm{ray} (\dot I_\mathrm{bg} - D_n I_\mathrm{bg})`,
        :math:`\dot\tau_k = \sum_s \dot a_s \tilde\sigma_s + \dot u\,\partial_u\tau`,
        :math:`\dot B_k = \dot u\,\partial_u \tilde B`.
    ``"reverse"``
        ``radiance`` and ``cotangent`` (n_rays, n_eta), the kernel's radiance (background
        included) and its cotangent → ``d_weights`` (n_rays, n_seg, n_tau + 1), the
        cotangents of the amounts, then of the offset (per segment, the sums over wavenumber
        of :math:`g_\tau` times each row of :math:`\tau`, and of
        :math:`g_\tau\,\partial\tau/\partial u + g_B\,\partial B/\partial u`; zero on
        padding), and each ray's transmittance :math:`\tau_\mathrm{ray}` (n_rays or 0, n_eta;
        asked for with 0 rows where no background needs its cotangent).

    Parameters
    ----------
    kind : {"forward", "forward_mode", "reverse"}
        The sweep.
    n_gas, n_tau : int
        Absorbing gases, and rows of the optical depth (``n_tau - n_gas`` is 1 with soot,
        else 0).
    dtype : {"float32", "float64"}
        The floats' dtype.

    Raises
    ------
    ValueError
        For an unknown kind or dtype, or more than one soot row.
    """
    if kind not in KINDS:
        raise ValueError(f"unknown sweep {kind!r}; choose one of {KINDS}")
    dtype = np.dtype(dtype).name
    module = _kernels(int(n_gas), int(n_tau), dtype)
    numba.get_num_threads()  # starts Numba's threads, whose symbols a cached handler links to
    handler = numba.cfunc(HANDLER, cache=True)(getattr(module, f"{kind}_handler"))
    return register(f"invflame_{kind}_{n_gas}_gases_{n_tau}_rows_{dtype}", handler)
