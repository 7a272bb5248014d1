"""Handlers of XLA's typed FFI compiled by Numba: operands read and results written in place."""

import jax
import jax.numpy as jnp
import numba
import numpy as np
import pytest

from operators.base import precision
from operators.rte.xla_ffi import HANDLER, argument, executing, ffi_target, no_error, result


def scaled_rows(frame):
    """Result 0: operand 0 (rank 2) times operand 1 (rank 1, one factor per row); result 1:
    the sums of operand 0's rows; result 2: operand 0 (rank 3) plus one."""
    if executing(frame):
        x, factor = argument(frame, 0, 2, np.float64), argument(frame, 1, 1, np.float64)
        cube = argument(frame, 2, 3, np.float32)
        scaled, sums = result(frame, 0, 2, np.float64), result(frame, 1, 1, np.float64)
        cube_plus_one = result(frame, 2, 3, np.float32)
        for i in range(x.shape[0]):
            sums[i] = 0.0
            for j in range(x.shape[1]):
                scaled[i, j] = factor[i] * x[i, j]
                sums[i] += x[i, j]
        cube_plus_one[:] = cube + np.float32(1)
    return no_error()


HANDLER_SCALED_ROWS = numba.cfunc(HANDLER)(scaled_rows)


def call_scaled_rows(x, factor, cube):
    name = ffi_target("test_scaled_rows", HANDLER_SCALED_ROWS)
    shapes = (jax.ShapeDtypeStruct(x.shape, x.dtype), jax.ShapeDtypeStruct(x.shape[:1], x.dtype),
              jax.ShapeDtypeStruct(cube.shape, cube.dtype))
    return jax.jit(jax.ffi.ffi_call(name, shapes))(x, factor, cube)


def test_a_handler_reads_its_operands_and_writes_its_results_in_place():
    rng = np.random.default_rng(0)
    x, factor = rng.standard_normal((5, 7)), rng.standard_normal(5)
    cube = rng.standard_normal((2, 3, 4)).astype(np.float32)
    with precision(np.float64):
        scaled, sums, cube_plus_one = call_scaled_rows(jnp.asarray(x), jnp.asarray(factor),
                                                       jnp.asarray(cube))
        assert scaled.dtype == jnp.float64
    np.testing.assert_array_equal(np.asarray(scaled), factor[:, None] * x)
    np.testing.assert_allclose(np.asarray(sums), x.sum(axis=1), rtol=1e-15)
    np.testing.assert_array_equal(np.asarray(cube_plus_one), cube + np.float32(1))


def test_a_handler_takes_empty_operands_and_results():
    with precision(np.float64):
        scaled, sums, cube_plus_one = call_scaled_rows(jnp.zeros((0, 3)), jnp.zeros(0),
                                                       jnp.zeros((2, 0, 4), jnp.float32))
    assert scaled.shape == (0, 3) and sums.shape == (0,) and cube_plus_one.shape == (2, 0, 4)


def test_a_name_becomes_a_target_once_and_not_for_another_handler():
    assert ffi_target("test_scaled_rows", HANDLER_SCALED_ROWS) == "test_scaled_rows"
    assert ffi_target("test_scaled_rows", HANDLER_SCALED_ROWS) == "test_scaled_rows"
    with pytest.raises(ValueError, match="'test_scaled_rows' is already another handler's"):
        ffi_target("test_scaled_rows", numba.cfunc(HANDLER)(scaled_rows))


def test_the_rank_of_an_operand_must_be_a_literal():
    def ranked(frame, ndim):
        if executing(frame):
            argument(frame, 0, ndim, np.float64)
        return no_error()

    with pytest.raises(numba.core.errors.TypingError, match="rank must be a literal integer"):
        numba.njit(ranked).compile((numba.types.voidptr, numba.types.int64))
