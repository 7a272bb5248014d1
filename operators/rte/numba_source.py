"""The source of the emission kernel's Numba sweeps, written out for the tables' gases.

Each segment (or pair) is one pass over wavenumber: every gas's row of the optical depth, its
offset derivative, the Planck spline, the transmission and the running sums, held in registers
from one to the next. For that the compiler needs the gases written out one by one (a loop over
a count known only at run time, inside the loop over wavenumber, is not vectorized: 8 × slower
in a trial), so the sweeps' source is a template, :data:`TEMPLATE`, whose per-gas parts
:func:`gas_code` writes for the tables' number of gases; :mod:`operators.rte.numba_targets`
compiles it.
"""

from __future__ import annotations

TEMPLATE = """import numba
import numpy as np

from operators.rte.numba_arithmetic import (absorptance, cubic, flush_subnormals,
                                            restore_control, slope, wide_vectors)
from operators.rte.xla_ffi import argument, executing, no_error, result

DTYPE, INDEX = np.{dtype}, np.int32


@numba.njit(inline="always")
def common_operands(frame):
    return (argument(frame, 0, 3, DTYPE), argument(frame, 1, 2, INDEX),
            argument(frame, 2, 3, DTYPE), argument(frame, 3, 2, DTYPE),
            argument(frame, 4, 1, INDEX), argument(frame, 5, 1, INDEX))


@numba.njit(inline="always")
def start_ray(coef, order, q):
    wide_vectors()
    n_eta = coef.shape[2]
    return flush_subnormals(), order[q], np.zeros(n_eta, coef.dtype), np.ones(n_eta, coef.dtype)


@numba.njit(fastmath=True, inline="always")
def forward_step(c, j, u, {a_}through, partial):
    zero = c.dtype.type(0)
    {rows}
    seen = through * absorptance({tau})
    return through - seen, partial + cubic(c, {planck_row}, j, u) * seen


@numba.njit(fastmath=True, parallel=True, cache=True)
def forward(coef, index, amount, offset, n_segments, order, background, radiance):
    n_rays, n_eta = amount.shape[0], coef.shape[2]
    for q in numba.prange(n_rays):
        control, i, partial_sum, through = start_ray(coef, order, q)
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
        restore_control(control)


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
    emission = cubic(c, {planck_row}, j, u)
    seen = through * absorptance({tau})
    through -= seen
    d_sum += (seen * (du * slope(c, {planck_row}, j, u) - emission * depth)
              + through * emission * d_tau)
    return through, partial + emission * seen, d_sum, depth + d_tau


@numba.njit(fastmath=True, parallel=True, cache=True)
def forward_mode(coef, index, amount, offset, n_segments, order, background, d_amount,
                 d_offset, d_background, radiance, d_radiance):
    n_rays, n_eta = amount.shape[0], coef.shape[2]
    for q in numba.prange(n_rays):
        control, i, partial_sum, through = start_ray(coef, order, q)
        d_sum = np.zeros(n_eta, coef.dtype)
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
        restore_control(control)


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
    emission = cubic(c, {planck_row}, j, u)
    absorbed = through * absorptance({tau})
    partial += emission * absorbed
    through -= absorbed
    g = cotangent * (through * emission - (radiance - partial))
    d_offset += g * tau_u + cotangent * absorbed * slope(c, {planck_row}, j, u)
    return through, partial, d_offset{_sums_add}


@numba.njit(fastmath=True, parallel=True, cache=True)
def reverse(coef, index, amount, offset, n_segments, order, radiance, cotangent, d_weights,
            transmittance):
    n_rays, n_eta = amount.shape[0], coef.shape[2]
    zero = coef.dtype.type(0)
    for q in numba.prange(n_rays):
        control, i, partial_sum, through = start_ray(coef, order, q)
        d_weights[i, n_segments[i]:] = zero
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
        restore_control(control)


def reverse_handler(frame):
    if executing(frame):
        reverse(*common_operands(frame), argument(frame, 6, 2, DTYPE),
                argument(frame, 7, 2, DTYPE), result(frame, 0, 3, DTYPE),
                result(frame, 1, 2, DTYPE))
    return no_error()
"""
"""The three sweeps as Python source, each with its FFI handler
(:func:`operators.rte.numba_targets.target`). The forward and forward-mode sweeps take a
segment, or two consecutive segments in the same temperature interval (their table rows read
once for both), in one pass over wavenumber, the reverse sweep one segment; each sweep's step
at one wavenumber is an inlined function, and so is the start of every ray (``start_ray``: the
widest vectors, subnormals flushed until ``restore_control``, the ray's index in ``order``,
its running sum and transmission). The sweeps write into XLA's result buffers; a
background of one row serves every ray. Each ``{…}`` stands for a line, an expression or names
written out gas by gas (:func:`gas_code`), which
:func:`operators.rte.numba_targets.compiled_sweeps` fills in for the tables' gases, or for the
float dtype."""


def gas_code(n_gas: int, n_tau: int) -> dict[str, str]:
    """The parts of :data:`TEMPLATE` that name each row of the optical depth: the gases'
    cubic rows ``4 s … 4 s + 3`` of the table, then the soot's row (constant in ``u``); the
    amounts and their tangents of a segment (``a``, ``da``) and of the one after it (``b``,
    ``db``), and the reverse sweep's sums over wavenumber (``g``)."""
    rows = [f"cubic(c, {4 * s}, j, u)" for s in range(n_gas)] + [f"c[{4 * n_gas}, j]"] * (
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
        "tau_u": total([f"{a[s]} * slope(c, {4 * s}, j, u)" for s in range(n_gas)]),
        "d_tau": total(["du * tau_u"] + [f"{da[s]} * {r[s]}" for s in range(n_tau)]),
        "_sums_add": after([f"{g[s]} + g * {r[s]}" for s in range(n_tau)]),
        "store": assign(taken("d_weights", "k", n_tau + 1), [*g, "d_offset"]),
    }
