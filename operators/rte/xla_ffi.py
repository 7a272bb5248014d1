"""XLA's typed foreign-function interface (FFI) for handlers compiled by Numba.

A handler is a C function ``XLA_FFI_Error* handler(XLA_FFI_CallFrame* frame)`` (XLA's
``xla/ffi/api/c_api.h``, shipped with jaxlib under :func:`jax.ffi.include_dir`) that XLA calls
on its own buffers: nothing is copied on the way in or out, where :func:`jax.pure_callback`
copies every operand and result (a 30 MB result cost 3.6–4.4 ms, ``docs/performance.md``). A
handler written with the functions here, compiled by :func:`numba.cfunc` with
:data:`HANDLER`, reads its operands with :func:`argument` and writes its results into
:func:`result`; :func:`ffi_target` makes it a target of :func:`jax.ffi.ffi_call`::

    def double(frame):
        if executing(frame):
            x, y = argument(frame, 0, 1, np.float32), result(frame, 0, 1, np.float32)
            y[:] = 2 * x
        return no_error()

    name = ffi_target("double", numba.cfunc(HANDLER)(double))
    jax.ffi.ffi_call(name, jax.ShapeDtypeStruct(x.shape, x.dtype))(x)

The handler trusts its caller for the operands' count, ranks and dtypes (it reads the rank's
leading sizes, not the dtype), so each is called from one JAX function that builds its
operands. The call frame's layout is that of API version 0.3 on a 64-bit platform.
"""

from __future__ import annotations

import jax
import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic, overload
from numba.np.unsafe.ndarray import to_fixed_tuple

__all__ = ["HANDLER", "argument", "executing", "ffi_target", "no_error", "result"]

#: The C signature of a handler: ``void* handler(void* frame)`` (the error, NULL on success).
HANDLER = types.voidptr(types.voidptr)

#: The FFI version the handlers are written to (``XLA_FFI_API_MAJOR``, ``_MINOR``).
API_VERSION = (0, 3)

# Offsets in 8-byte words: XLA_FFI_CallFrame {struct_size, extension_start, api, ctx, stage,
# args {struct_size, extension_start, size, types, args}, rets {... rets}, ...};
# XLA_FFI_Buffer {struct_size, extension_start, dtype, data, rank, dims};
# XLA_FFI_Metadata_Extension {{struct_size, type, next}, metadata};
# XLA_FFI_Metadata {struct_size, api_version {struct_size, extension_start, major, minor},
# traits}.
_EXTENSION, _STAGE, _ARGUMENTS, _RESULTS, _FRAME_WORDS = 1, 4, 9, 14, 15
_DATA, _DIMS, _BUFFER_WORDS = 3, 5, 6
_TYPE, _METADATA, _EXTENSION_WORDS = 1, 3, 4
_VERSION_BYTES, _TRAITS_BYTES = 24, 32
_EXECUTE, _METADATA_EXTENSION = 3, 1

_handlers = {}  # each target's handler, by name, kept alive while XLA may call it


@intrinsic
def _pointer(typingctx, address):
    """The pointer at the int64 ``address``."""
    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], ir.IntType(8).as_pointer())
    return types.voidptr(types.int64), codegen


@intrinsic
def _address(typingctx, pointer):
    """The int64 address of ``pointer``."""
    def codegen(context, builder, signature, args):
        return builder.ptrtoint(args[0], ir.IntType(64))
    return types.int64(types.voidptr), codegen


@numba.njit(inline="always")
def _words(address, n):
    """The ``n`` 8-byte words at ``address``, as int64."""
    return numba.carray(_pointer(address), n, np.int64)


@numba.njit(inline="always")
def executing(frame):
    """Whether XLA calls the handler to run it (its execute stage). When XLA asks for the
    handler's metadata instead (when it becomes a target), this answers: API version
    :data:`API_VERSION`, no traits. At the other stages (instantiate, prepare, initialize) there
    is nothing to do."""
    words = _words(_address(frame), _FRAME_WORDS)
    extension = words[_EXTENSION]
    if extension != 0:
        asked = _words(extension, _EXTENSION_WORDS)
        if asked[_TYPE] & 0xFFFFFFFF == _METADATA_EXTENSION:
            metadata = asked[_METADATA]
            version = numba.carray(_pointer(metadata + _VERSION_BYTES), 2, np.int32)
            version[0], version[1] = API_VERSION
            numba.carray(_pointer(metadata + _TRAITS_BYTES), 1, np.uint32)[0] = 0
        return False
    return words[_STAGE] & 0xFFFFFFFF == _EXECUTE


@numba.njit(inline="always")
def no_error():
    """What a handler returns on success (NULL)."""
    return _pointer(0)


def _buffer(frame, table, i, ndim, dtype):
    raise TypeError("compiled by Numba; call it from a handler")


@overload(_buffer, inline="always")
def _buffer_for(frame, table, i, ndim, dtype):
    if not isinstance(ndim, types.IntegerLiteral):
        raise numba.core.errors.TypingError("the rank must be a literal integer")
    rank = ndim.literal_value

    def impl(frame, table, i, ndim, dtype):
        pointers = _words(_words(_address(frame), _FRAME_WORDS)[table], i + 1)
        buffer = _words(pointers[i], _BUFFER_WORDS)
        dims = _words(buffer[_DIMS], rank)
        return numba.carray(_pointer(buffer[_DATA]), to_fixed_tuple(dims, rank), dtype)
    return impl


@numba.njit(inline="always")
def argument(frame, i, ndim, dtype):
    """The handler's operand ``i`` as a C-contiguous array of rank ``ndim`` (a literal) and
    ``dtype``, on XLA's buffer (read it only)."""
    return _buffer(frame, _ARGUMENTS, i, ndim, dtype)


@numba.njit(inline="always")
def result(frame, i, ndim, dtype):
    """The handler's result ``i`` as a C-contiguous array of rank ``ndim`` (a literal) and
    ``dtype``, on XLA's buffer (write all of it)."""
    return _buffer(frame, _RESULTS, i, ndim, dtype)


def ffi_target(name: str, handler) -> str:
    """Make ``handler`` (a :func:`numba.cfunc` of :data:`HANDLER`) the CPU target ``name`` of
    :func:`jax.ffi.ffi_call` (:func:`jax.ffi.register_ffi_target`), once per name; returns
    ``name``.

    Raises
    ------
    ValueError
        If ``name`` is already the target of another handler.
    """
    known = _handlers.get(name)
    if known is None:
        jax.ffi.register_ffi_target(name, jax.ffi.pycapsule(handler.address), platform="cpu")
        _handlers[name] = handler
    elif known is not handler:
        raise ValueError(f"the FFI target {name!r} is already another handler's")
    return name
