r"""What the operators that :mod:`operators.base` builds from other objects compute on arrays.

:class:`CompositionRule` computes ``outer(inner(x))`` and its Jacobian products from the parts'
by the chain rule; :class:`CombinationRule` does so for parts applied to (pieces of) one input
whose outputs are assembled: a sum (:class:`SumRule`), a multiple (:class:`ScaleRule`), the
stacks of :mod:`operators.combinators`. :class:`FunctionRule` takes its arrays from a JAX or
torch function, :class:`PylopsRule` from a pylops operator.

Each rule is the array side of a class of :mod:`operators.base` (:class:`~operators.base.Sum` is
:class:`SumRule` and an :class:`~operators.Operator`), which adds what builds operators: the
algebra and, for a combination, its Jacobian. A rule takes arrays, returns arrays and builds no
operator, so this module imports none that defines one, and :mod:`operators.base` imports it.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from operators.jax_map import JaxMap
from operators.protocol import LinearOperatorProtocol, OperatorProtocol, _size
from operators.pylops_import import pylops


def _push(op: OperatorProtocol, x, v):
    """:math:`J_{op}(x) v` (``x`` unused, and may be None, when ``op`` is linear)."""
    return op(v) if op.linear else op.jvp(x, v)


def _pull(op: OperatorProtocol, x, w):
    r""":math:`J_{op}(x)^\mathsf{T} w` (``x`` unused, and may be None, when ``op`` is linear)."""
    return op.adjoint(w) if op.linear else op.vjp(x, w)


class CompositionRule(OperatorProtocol):
    r""":math:`x \mapsto \text{outer}(\text{inner}(x))` on arrays, the chain rule.

    The inner output is reshaped to the outer input when the two shapes differ in layout but
    not in size (checked here, once).
    """

    def __init__(self, outer: OperatorProtocol, inner: OperatorProtocol):
        if _size(outer.dims) != _size(inner.dimsd):
            raise ValueError(
                f"cannot compose {outer.name} (input {outer.dims}) after {inner.name} "
                f"(output {inner.dimsd}): sizes differ"
            )
        dtype = np.result_type(outer.dtype, inner.dtype)
        super().__init__(inner.dims, outer.dimsd, dtype=dtype,
                         name=f"({outer.name} @ {inner.name})")
        self.outer, self.inner = outer, inner
        self.parts = (outer, inner)

    def _mid(self, y):
        return np.reshape(y, self.outer.dims)

    def jax_map(self) -> JaxMap | None:
        """The two parts' maps composed, when both have one; the outer part's domain is
        checked at the inner part's value, computed on the host by the inner operator (cheap
        for a diagonal before the emission map, as a voxel problem has it)."""
        outer, inner = self.outer.jax_map(), self.inner.jax_map()
        if outer is None or inner is None:
            return None
        mid = self.outer.dims

        def function(args, x):
            return outer.function(args[0], jnp.reshape(inner.function(args[1], x), mid))

        def check(x):
            if inner.check is not None:
                inner.check(x)
            if outer.check is not None:
                outer.check(self._mid(self.inner(x)))

        checked = inner.check is not None or outer.check is not None
        return JaxMap(function, (outer.args, inner.args), check if checked else None)

    def _forward(self, x):
        return self.outer(self._mid(self.inner(x)))

    def _inner_value(self, x):
        return None if self.outer.linear else self._mid(self.inner(x))

    def _jvp(self, x, v):
        return _push(self.outer, self._inner_value(x), self._mid(_push(self.inner, x, v)))

    def _vjp(self, x, w):
        inner_w = np.reshape(_pull(self.outer, self._inner_value(x), w), self.inner.dimsd)
        return _pull(self.inner, x, inner_w)


class CombinationRule(OperatorProtocol):
    """``parts`` (an attribute) applied to (pieces of) one input, their outputs assembled.

    Subclasses say how the input is handed to the parts (:meth:`_inputs`), how the parts'
    outputs are assembled (:meth:`_assemble`) and the adjoints of both (:meth:`_cotangents`,
    :meth:`_gather`); the value and the Jacobian products follow.
    """

    parts: tuple[OperatorProtocol, ...]

    def _inputs(self, x) -> list:
        return [np.reshape(x, p.dims) for p in self.parts]

    def _gather(self, grads) -> np.ndarray:
        return sum(np.reshape(g, self.dims) for g in grads)

    def _assemble(self, outputs) -> np.ndarray:
        raise NotImplementedError

    def _cotangents(self, w) -> list:
        raise NotImplementedError

    def _forward(self, x):
        return self._assemble([p(xi) for p, xi in zip(self.parts, self._inputs(x), strict=True)])

    def _jvp(self, x, v):
        return self._assemble([_push(p, xi, vi) for p, xi, vi in
                               zip(self.parts, self._inputs(x), self._inputs(v), strict=True)])

    def _vjp(self, x, w):
        xs = [None] * len(self.parts) if x is None else self._inputs(x)
        return self._gather([_pull(p, xi, wi) for p, xi, wi in
                             zip(self.parts, xs, self._cotangents(w), strict=True)])


class SumRule(CombinationRule):
    """``A + B + ...`` of operators with inputs and outputs of the same sizes (the shapes of
    the first)."""

    def __init__(self, ops):
        ops = list(ops)
        first = ops[0]
        for op in ops[1:]:
            if _size(op.dims) != _size(first.dims) or _size(op.dimsd) != _size(first.dimsd):
                raise ValueError(
                    f"cannot add {first.name} ({first.dims} -> {first.dimsd}) and {op.name} "
                    f"({op.dims} -> {op.dimsd}): sizes differ"
                )
        super().__init__(first.dims, first.dimsd, dtype=np.result_type(*[o.dtype for o in ops]),
                         name="(" + " + ".join(o.name for o in ops) + ")")
        self.parts = tuple(ops)

    def _assemble(self, outputs):
        return sum(np.reshape(y, self.dimsd) for y in outputs)

    def _cotangents(self, w):
        return [np.reshape(w, p.dimsd) for p in self.parts]


class ScaleRule(CombinationRule):
    """``c * A`` for a real scalar ``c``."""

    def __init__(self, op: OperatorProtocol, scale: float):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=f"{scale:g}*{op.name}")
        self.scale = float(scale)
        self.parts = (op,)

    def _assemble(self, outputs):
        return self.scale * outputs[0]

    def _cotangents(self, w):
        return [self.scale * w]


class FunctionRule(OperatorProtocol):
    """An operator's arrays from ``function`` (a :class:`~operators.jax_operator.JaxFunction` or
    a :class:`~operators.torch_operator.TorchFunction`), which offers ``forward(x)``,
    ``jvp(x, v)``, ``vjp(x, w)`` and ``pullback(x) -> (value, jvp, vjp)`` on NumPy arrays."""

    def __init__(self, function, dims, dimsd, dtype, name):
        super().__init__(dims, dimsd, dtype=dtype, name=name)
        self.function = function

    def _forward(self, x):
        return self.function.forward(x)

    def _jvp(self, x, v):
        return self.function.jvp(x, v)

    def _vjp(self, x, w):
        return self.function.vjp(x, w)


class PylopsRule(LinearOperatorProtocol):
    """A linear operator's arrays from the pylops operator ``op``'s ``matvec``/``rmatvec``."""

    def __init__(self, op: pylops.LinearOperator, name: str | None = None):
        super().__init__(getattr(op, "dims", (op.shape[1],)),
                         getattr(op, "dimsd", (op.shape[0],)),
                         dtype=op.dtype, name=name or getattr(op, "name", None) or "pylops")
        self.op = op

    def _forward(self, x):
        return np.asarray(self.op.matvec(x.ravel())).reshape(self.dimsd)

    def _adjoint(self, y):
        return np.asarray(self.op.rmatvec(y.ravel())).reshape(self.dims)
