r"""Correctness checks for operators: dot-product (adjoint) tests and Taylor tests.

Each check returns a result object with ``passed`` (bool), the measured quantities, and a
printable table, so it reads well in a notebook and asserts cleanly in a test::

    >>> r = taylor_test(F, x, v)
    >>> print(r)            # table of steps, remainders and observed rates
    >>> assert r.passed

Taylor test (after pyadjoint's ``taylor_to_dict``): for steps :math:`h_k = h_0 2^{-k}`,

.. math:: r_0(h) = \|F(x+hv) - F(x)\|, \qquad r_1(h) = \|F(x+hv) - F(x) - h\,J v\|,

whose observed convergence rates :math:`\log_2 (r(h_k)/r(h_{k+1}))` tend to 1 and 2 when
:math:`J v` is the true directional derivative. Rates are read in the asymptotic window: the
smallest steps whose :math:`r_1` is still well above the round-off floor
:math:`\epsilon\,\|F(x)\|` of the dtype.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from operators.base import Operator


def _rng(seed):
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def _random(shape, dtype, rng):
    return rng.standard_normal(shape).astype(dtype)


@dataclass
class DotTestResult:
    r"""Outcome of a dot-product test :math:`\langle Ax, y\rangle = \langle x, A^H y\rangle`.

    Attributes
    ----------
    forward : float
        :math:`\langle A x, y \rangle`.
    adjoint : float
        :math:`\langle x, A^H y \rangle`.
    relative_error : float
        :math:`|a - b| / \max(|a|, |b|)`.
    rtol : float
        Tolerance used for ``passed``.
    """

    name: str
    forward: float
    adjoint: float
    relative_error: float
    rtol: float

    @property
    def passed(self) -> bool:
        return bool(self.relative_error <= self.rtol)

    def __str__(self) -> str:
        verdict = "PASS" if self.passed else "FAIL"
        return (
            f"dot test {self.name}: <Ax,y> = {self.forward:.16e}\n"
            f"{' ' * (10 + len(self.name))}<x,A^H y> = {self.adjoint:.16e}\n"
            f"relative error {self.relative_error:.3e} (rtol {self.rtol:.1e}) {verdict}"
        )


def _dot_result(name, a, b, rtol):
    scale = max(abs(a), abs(b), np.finfo(float).tiny)
    return DotTestResult(name, float(a), float(b), float(abs(a - b) / scale), rtol)


def dottest(op, rtol: float = 1e-10, seed=0) -> DotTestResult:
    """Dot-product test of a linear operator's adjoint with random vectors.

    Parameters
    ----------
    op : operators.LinearOperator
        Operator with ``op(x)`` and its adjoint ``op.adjoint(y)``.
    rtol : float, optional
        Relative tolerance for ``passed`` (default 1e-10, for float64).
    seed : int or numpy.random.Generator, optional
        Randomness of the test vectors.
    """
    rng = _rng(seed)
    x = _random(op.dims, op.dtype, rng)
    y = _random(op.dimsd, op.dtype, rng)
    return _dot_result(op.name, np.vdot(op(x), y), np.vdot(x, op.adjoint(y)), rtol)


def jacobian_dottest(op: Operator, x, rtol: float = 1e-10, seed=0) -> DotTestResult:
    """Dot-product test of ``op.jvp(x, ·)`` against ``op.vjp(x, ·)`` at the point ``x``.

    Parameters
    ----------
    op : Operator
        Possibly nonlinear operator.
    x : ndarray
        Linearization point, shape ``op.dims``.
    rtol : float, optional
        Relative tolerance (default 1e-10, for float64).
    seed : int or numpy.random.Generator, optional
        Randomness of the test vectors.
    """
    rng = _rng(seed)
    v = _random(op.dims, op.dtype, rng)
    w = _random(op.dimsd, op.dtype, rng)
    return _dot_result(f"J[{op.name}]", np.vdot(op.jvp(x, v), w), np.vdot(v, op.vjp(x, w)),
                       rtol)


@dataclass
class TaylorResult:
    """Outcome of a Taylor test: remainders per step and their observed rates.

    Attributes
    ----------
    steps : ndarray
        Step sizes :math:`h_k`.
    r0, r1 : ndarray
        Zeroth- and first-order remainders at each step.
    rates0, rates1 : ndarray
        Observed rates between consecutive steps (length ``len(steps) - 1``).
    window : slice
        Indices of ``rates1`` read as asymptotic (above the round-off floor).
    floor : float
        Round-off floor of the remainders.
    """

    name: str
    steps: np.ndarray
    r0: np.ndarray
    r1: np.ndarray
    rates0: np.ndarray
    rates1: np.ndarray
    window: slice
    floor: float
    expected: tuple[float, float] = (1.0, 2.0)
    tol: float = 0.25
    exact: bool = field(default=False)

    @property
    def rate0(self) -> float:
        """Observed first-remainder rate over the window (expect 1)."""
        return float(np.median(self.rates0[self.window]))

    @property
    def rate1(self) -> float:
        """Observed second-remainder rate over the window (expect 2); inf when exact."""
        if self.exact:
            return float("inf")
        return float(np.median(self.rates1[self.window]))

    @property
    def passed(self) -> bool:
        first = abs(self.rate0 - self.expected[0]) <= self.tol
        if self.exact:
            return bool(first)
        return bool(first and self.rate1 >= self.expected[1] - self.tol)

    def __str__(self) -> str:
        lines = [f"Taylor test {self.name}",
                 f"{'h':>10} {'r0':>11} {'rate0':>6} {'r1':>11} {'rate1':>6}"]
        lo, hi, _ = self.window.indices(len(self.rates1))
        for k, h in enumerate(self.steps):
            rate0 = f"{self.rates0[k - 1]:6.2f}" if k else " " * 6
            rate1 = f"{self.rates1[k - 1]:6.2f}" if k else " " * 6
            mark = " *" if lo <= k - 1 < hi else ""
            lines.append(f"{h:10.3e} {self.r0[k]:11.3e} {rate0} {self.r1[k]:11.3e} {rate1}{mark}")
        if self.exact:
            lines.append(f"r1 is at the round-off floor {self.floor:.1e} for every step: the "
                         "derivative is exact to round-off (linear map)")
        verdict = "PASS" if self.passed else "FAIL"
        lines.append(f"observed rates {self.rate0:.3f} and {self.rate1:.3f} over the steps "
                     f"marked * (expect {self.expected[0]:g} and {self.expected[1]:g}): {verdict}")
        return "\n".join(lines)


def _taylor(name, f, x, v, derivative, norm, dtype, h0, n_steps, tol) -> TaylorResult:
    eps = np.finfo(dtype).eps
    fx = f(x)
    scale = max(float(norm(fx)), 1.0)
    if h0 is None:
        h0 = 0.1 * max(float(np.linalg.norm(x)), 1.0) / max(float(np.linalg.norm(v)), eps)
    steps = h0 * 0.5 ** np.arange(n_steps)
    r0 = np.empty(n_steps)
    r1 = np.empty(n_steps)
    for k, h in enumerate(steps):
        diff = f(x + h * v) - fx
        r0[k] = norm(diff)
        r1[k] = norm(diff - h * derivative)
    tiny = np.finfo(float).tiny
    with np.errstate(divide="ignore", invalid="ignore"):
        rates0 = np.log2(np.maximum(r0[:-1], tiny) / np.maximum(r0[1:], tiny))
        rates1 = np.log2(np.maximum(r1[:-1], tiny) / np.maximum(r1[1:], tiny))
    floor = 1e3 * eps * scale
    above = np.flatnonzero(r1[1:] > floor)
    exact = above.size == 0
    if exact:
        window = slice(0, len(rates0))
    else:
        last = int(above[-1]) + 1
        window = slice(max(0, last - 3), last)
    return TaylorResult(name, steps, r0, r1, rates0, rates1, window, floor, tol=tol,
                        exact=exact)


def taylor_test(op: Operator, x, v=None, h0: float | None = None, n_steps: int = 14,
                tol: float = 0.25, seed=0) -> TaylorResult:
    """Taylor test of an operator's ``jvp`` at ``x`` in direction ``v``.

    Parameters
    ----------
    op : Operator
        Possibly nonlinear operator.
    x : ndarray
        Point, shape ``op.dims``.
    v : ndarray, optional
        Direction, shape ``op.dims`` (default: standard normal with ``seed``).
    h0 : float, optional
        Largest step (default ``0.1 max(‖x‖, 1)/‖v‖``).
    n_steps : int, optional
        Number of halvings (default 14).
    tol : float, optional
        Accepted deviation of the observed rates from 1 and 2 (default 0.25).
    seed : int or numpy.random.Generator, optional
        Randomness of the default direction.
    """
    x = np.asarray(x, dtype=op.dtype).reshape(op.dims)
    v = _random(op.dims, op.dtype, _rng(seed)) if v is None else np.asarray(v, op.dtype)
    v = v.reshape(op.dims)
    return _taylor(op.name, op, x, v, op.jvp(x, v), np.linalg.norm, op.dtype, h0, n_steps, tol)


def gradient_taylor_test(fun, grad, x, v=None, h0: float | None = None, n_steps: int = 14,
                         tol: float = 0.25, seed=0) -> TaylorResult:
    r"""Taylor test of a scalar objective against its gradient.

    Remainders are :math:`|f(x+hv) - f(x)|` and :math:`|f(x+hv) - f(x) - h\langle \nabla f,
    v\rangle|`.

    Parameters
    ----------
    fun : callable
        Scalar objective ``f(x) -> float``.
    grad : callable or ndarray
        Gradient function ``x -> ∇f(x)`` or the gradient at ``x`` itself.
    x : ndarray
        Point.
    v : ndarray, optional
        Direction (default: standard normal with ``seed``).
    h0, n_steps, tol, seed
        As in :func:`taylor_test`.
    """
    x = np.asarray(x)
    v = _random(x.shape, x.dtype, _rng(seed)) if v is None else np.asarray(v, x.dtype)
    g = np.asarray(grad(x) if callable(grad) else grad)
    derivative = float(np.vdot(g, v))
    name = getattr(fun, "__name__", "objective")
    return _taylor(name, lambda y: float(fun(y)), x, v, derivative, abs, x.dtype, h0,
                   n_steps, tol)
