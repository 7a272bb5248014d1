"""An operator as a function that JAX can trace, for programs built of several operators."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any


@dataclasses.dataclass(frozen=True)
class JaxMap:
    r"""An operator as a function that JAX can trace: :math:`y = F(x)` is
    ``function(args, x)``.

    Programs built of several operators (:mod:`solvers.compiled_objective`) call these inside
    one :func:`jax.jit`, so that the whole program runs on JAX's device and JAX differentiates
    it.

    Attributes
    ----------
    function : callable
        ``function(args, x) -> y``, traceable by JAX, ``x`` of the operator's ``dims`` and
        ``y`` of its ``dimsd``.
    args : pytree of jax.Array
        The operator's constant arrays, passed at every call so that they are not compiled in
        as constants.
    check : callable or None
        ``check(x)`` raises ``ValueError`` for a NumPy point ``x`` outside the operator's
        domain, as the operator itself would; None when every point is in it.
    """

    function: Callable
    args: Any = ()
    check: Callable | None = None
