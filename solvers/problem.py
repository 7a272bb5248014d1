r"""The inverse problem every solver works on, whatever the parameters represent.

A :class:`Problem` holds a forward operator :math:`F` from parameters :math:`\theta` (voxel
values, network weights, any array) to predicted data, the measured data :math:`d`, an optional
regularizer :math:`\Phi(\theta) = g(K(\theta))` and its weight :math:`\lambda`, and optional box
bounds. The objective is the paper's loss, **without** a factor one half:

.. math:: L(\theta) = \|F(\theta) - d\|_2^2 + \lambda\, g(K(\theta)),

with gradient :math:`\nabla L = 2 J_F(\theta)^\mathsf{T}(F(\theta) - d)
+ \lambda\, J_K(\theta)^\mathsf{T} \nabla g(K(\theta))`. The inner operator :math:`K` may be
linear (the finite-difference gradient of a voxel grid) or nonlinear (that gradient after a
network evaluated at voxel centres); gradient methods use ``K.vjp`` and primal–dual methods use
``g.prox_dual`` with ``K``'s linearization.

Capability flags tell a solver what it may do with the problem, whatever the parameters
represent:

``linearizable``
    Whether linearizing :math:`F` and :math:`K` at a point and applying those Jacobians many
    times (Gauss–Newton's inner least squares, PDHG's inner iterations) is affordable. False
    when one Jacobian product costs as much as a whole pass over the data and is only worth it
    once per gradient (e.g. a network queried at every sample of every measurement): solvers
    that build stacked Jacobians refuse such a problem and name the solvers that fit it.
``stochastic``
    Whether a stochastic ``value_and_grad`` replaces the full objective (read-only; set by
    passing ``value_and_grad``).

A problem may carry a stochastic ``value_and_grad(theta, iteration, rng) -> (loss, grad)``
(e.g. a random subset of rays per iteration); first-order solvers use it instead of the full
objective. ``rng`` is ``numpy.random.default_rng([seed, iteration])``: a function of the run's
seed and the iteration only, so the same iteration sees the same sample after a resume.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np

from operators import Composite, Operator, linearize_together
from operators.interop import to_numpy
from solvers.bounds import compact, project, projected_gradient
from solvers.compiled_objective import CompiledObjective

#: :math:`\Phi = g \circ K` as solvers name it: the class :class:`operators.Composite` itself.
Regularizer = Composite


def as_regularizer(regularizer) -> Composite | None:
    r"""``None``, an :class:`operators.Composite` :math:`g \circ K` (as from
    :func:`operators.tikhonov`) or a pair ``(g, K)``, as a :class:`operators.Composite`."""
    if regularizer is None or isinstance(regularizer, Composite):
        return regularizer
    if isinstance(regularizer, tuple) and len(regularizer) == 2:
        return Composite(*regularizer)
    raise TypeError(
        "regularizer must be None, an operators.Composite g(K(x)) such as "
        f"operators.total_variation(...), or a pair (g, K); got {type(regularizer).__name__}"
    )


def sum_of_squares(r: np.ndarray) -> float:
    r""":math:`\|r\|_2^2` accumulated in float64."""
    r = np.asarray(r, dtype=np.float64).ravel()
    return float(r @ r)


class Evaluation:
    r"""The objective at one point: total loss, its parts and a lazily computed gradient.

    Attributes
    ----------
    loss : float
        :math:`L(\theta)`.
    misfit : float
        :math:`\|F(\theta) - d\|^2` (NaN when a stochastic ``value_and_grad`` gave the loss).
    regularizer : float
        :math:`\Phi(\theta)`, unweighted (0 without a regularizer, NaN as above).
    sample : int or None
        Iteration whose random sample produced this evaluation; None when deterministic.
    forward_jacobian, regularizer_jacobian : operators.Jacobian or None
        Linearizations of :math:`F` and :math:`K` at the point (with ``.value``), when known.
    point : jax.Array or None
        The point on JAX's device when a compiled objective (:attr:`Problem.compiled`)
        computed this evaluation, None otherwise.
    """

    def __init__(self, loss, misfit, regularizer, grad=None, grad_fn=None, sample=None,
                 forward_jacobian=None, regularizer_jacobian=None, point=None):
        self.loss = float(loss)
        self.misfit = float(misfit)
        self.regularizer = float(regularizer)
        self.sample = sample
        self.forward_jacobian = forward_jacobian
        self.regularizer_jacobian = regularizer_jacobian
        self.point = point
        self._native = grad
        self._grad = None if grad is None else to_numpy(grad)
        self._grad_fn = grad_fn

    @property
    def has_grad(self) -> bool:
        """Whether the gradient has been computed already."""
        return self._native is not None

    @property
    def native_grad(self):
        r""":math:`\nabla L(\theta)` where it was computed, shape of the parameters (computed
        on first access): a JAX array on JAX's device from a compiled objective, a NumPy array
        otherwise."""
        if self._native is None:
            if self._grad_fn is None:
                raise RuntimeError("this evaluation carries no gradient")
            self._native = self._grad_fn()
            self._grad_fn = None
        return self._native

    @property
    def grad(self) -> np.ndarray:
        r""":math:`\nabla L(\theta)` as a NumPy array, shape of the parameters (computed, and
        copied from JAX's device, on first access)."""
        if self._grad is None:
            self._grad = to_numpy(self.native_grad)
        return self._grad


def _bound(value, dims, dtype, what):
    if value is None:
        return None
    arr = np.asarray(compact(value), dtype=dtype)  # a bound per field stays one number each
    try:
        return np.broadcast_to(arr, dims)
    except ValueError:
        raise ValueError(f"{what} bound of shape {arr.shape} does not broadcast to the "
                         f"parameter shape {dims}; give a scalar or an array of that shape"
                         ) from None


class Problem:
    r"""Minimize :math:`\|F(\theta) - d\|_2^2 + \lambda\, g(K(\theta))` subject to bounds.

    Parameters
    ----------
    forward : operators.Operator
        :math:`F`, parameters (shape ``forward.dims``) to predicted data (``forward.dimsd``),
        e.g. radiance in W/(m²·sr·cm⁻¹).
    data : array_like
        Measured data :math:`d`, shape ``forward.dimsd`` (a linear forward operator also takes
        the flat vector, as pylops does), same units.
    regularizer : operators.Composite or (Functional, Operator), optional
        :math:`\Phi = g \circ K`; None for no regularization.
    lam : float, optional
        Weight :math:`\lambda \ge 0` (default 1e-3, as in the paper).
    lower, upper : float or array_like, optional
        Box bounds on :math:`\theta` (scalars or arrays broadcastable to ``forward.dims``), in
        the parameters' units; None for unbounded.
    x0 : array_like, optional
        Default starting point, shape ``forward.dims``; must satisfy the bounds.
    linearizable : bool, optional
        Whether Jacobians of :math:`F` and :math:`K` may be applied many times per iteration
        (default True; see the module docstring); solvers that need it check it.
    advice : str, optional
        What a solver that refuses the problem for a missing capability should suggest
        instead, in the words of the application (e.g. a cheaper parameterization).
    name : str, optional
        Label for results and messages.
    metadata : dict, optional
        Free-form description (representation, regularizer name, units...) kept with results.
    value_and_grad : callable, optional
        Stochastic override ``(theta, iteration, rng) -> (loss, grad)`` used by first-order
        solvers instead of the full objective.
    preconditioner : operators.LinearOperator or callable, optional
        A symmetric positive definite :math:`M` on the parameters (``forward.dims`` in and
        out), shaped like the inverse of the objective's curvature (its scale does not
        matter), for solvers that take one (``preconditioned-lbfgs``), or a function of no
        arguments that builds it (or returns None) when a solver first asks; None: the
        identity.
    """

    def __init__(self, forward: Operator, data, regularizer=None, lam: float = 1e-3,
                 lower=None, upper=None, x0=None, linearizable: bool = True, advice: str = "",
                 name: str | None = None, metadata: dict[str, Any] | None = None,
                 value_and_grad=None, preconditioner=None):
        if not isinstance(forward, Operator):
            raise TypeError(f"forward must be an operators.Operator, got "
                            f"{type(forward).__name__} (wrap functions with "
                            "Operator.from_jax / from_torch)")
        self.forward = forward
        self.dims = forward.dims
        self.dtype = forward.dtype
        data = np.asarray(data)
        flat = forward.linear and data.ndim == 1 and data.size == int(np.prod(forward.dimsd))
        if data.shape != forward.dimsd and not flat:
            raise ValueError(f"data has shape {data.shape} but the forward operator "
                             f"{forward.name} predicts shape {forward.dimsd}; reshape or "
                             "transpose the data to that shape")
        if not np.all(np.isfinite(data)):
            bad = np.argwhere(~np.isfinite(data.reshape(forward.dimsd)))
            raise ValueError(f"data hold {len(bad)} NaN or infinite values (first at index "
                             f"{tuple(int(i) for i in bad[0])}); remove or mask them before "
                             "building the problem")
        self.data = data.reshape(forward.dimsd).astype(self.dtype, copy=False)
        self.regularizer = as_regularizer(regularizer)
        if self.regularizer is not None and self.regularizer.op.dims != self.dims:
            raise ValueError(f"the regularizer's operator {self.regularizer.op.name} takes "
                             f"shape {self.regularizer.op.dims}, the parameters have "
                             f"shape {self.dims}")
        if not np.isfinite(lam) or lam < 0:
            raise ValueError(f"lam must be a finite number >= 0, got {lam}")
        self.lam = float(lam)
        self.lower = _bound(lower, self.dims, self.dtype, "lower")
        self.upper = _bound(upper, self.dims, self.dtype, "upper")
        if self.lower is not None and self.upper is not None and np.any(self.lower > self.upper):
            raise ValueError("lower bound exceeds upper bound somewhere; check lower <= upper")
        if not isinstance(linearizable, bool | np.bool_):
            raise TypeError(f"linearizable must be True or False, got {linearizable!r}")
        self.linearizable = bool(linearizable)
        self.advice = str(advice)
        self.name = name or f"problem({forward.name})"
        self.metadata = dict(metadata or {})
        if value_and_grad is not None and not callable(value_and_grad):
            raise TypeError("value_and_grad must be a callable (theta, iteration, rng) -> "
                            "(loss, grad)")
        self.value_and_grad = value_and_grad
        if isinstance(preconditioner, Operator):
            preconditioner = self._checked_preconditioner(preconditioner)
        elif preconditioner is not None and not callable(preconditioner):
            raise TypeError(f"preconditioner must be an operators.LinearOperator, a function "
                            f"that builds one, or None; got {type(preconditioner).__name__}")
        self._preconditioner = preconditioner
        self.x0 = None if x0 is None else self.check_point(x0, "x0")

    @property
    def preconditioner(self) -> Operator | None:
        """The preconditioner :math:`M` (built on first use when given as a function), or
        None."""
        if self._preconditioner is not None and not isinstance(self._preconditioner, Operator):
            built = self._preconditioner()
            self._preconditioner = None if built is None else self._checked_preconditioner(built)
        return self._preconditioner

    def _checked_preconditioner(self, preconditioner: Operator) -> Operator:
        if (tuple(preconditioner.dims) != tuple(self.dims)
                or tuple(preconditioner.dimsd) != tuple(self.dims)):
            raise ValueError(f"the preconditioner {preconditioner.name} maps "
                             f"{preconditioner.dims} to {preconditioner.dimsd}; it must map the "
                             f"parameters' shape {self.dims} to itself")
        return preconditioner

    # -- parameters and bounds ---------------------------------------------------------------
    @property
    def bounded(self) -> bool:
        """Whether any bound is set."""
        return self.lower is not None or self.upper is not None

    @property
    def stochastic(self) -> bool:
        """Whether a stochastic ``value_and_grad`` replaces the full objective."""
        return self.value_and_grad is not None

    def check_point(self, x, what: str = "x") -> np.ndarray:
        """``x`` as a fresh array of the parameter shape and dtype, checked against the bounds."""
        x = np.asarray(x)
        if x.size != int(np.prod(self.dims)):
            raise ValueError(f"{what} has shape {x.shape}, the parameters have shape {self.dims}")
        x = np.array(x.reshape(self.dims), dtype=self.dtype)
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{what} contains NaN or infinite values")
        if not np.array_equal(self.project(x), x):
            raise ValueError(f"{what} violates the bounds; start inside them "
                             "(e.g. problem.project(x0))")
        return x

    def project(self, x) -> np.ndarray:
        """Projection onto the box ``lower <= x <= upper`` (identity when unbounded)."""
        if not self.bounded:
            return np.asarray(x)
        return project(np.asarray(x), self.lower, self.upper).astype(self.dtype, copy=False)

    def projected_gradient(self, x, grad) -> np.ndarray:
        """The gradient with components pushing out of an active bound set to zero
        (:func:`solvers.bounds.projected_gradient`)."""
        return projected_gradient(np.asarray(x), np.asarray(grad), self.lower, self.upper)

    def projected_gradient_norm(self, x, evaluation: Evaluation) -> float:
        r""":math:`\|\cdot\|_2` of :meth:`projected_gradient` at ``x`` for ``evaluation``'s
        gradient (the history's ``grad_norm``), computed on JAX's device when the gradient
        is there (:attr:`Evaluation.point` set), so that it stays there."""
        if evaluation.point is not None:
            return self.compiled.projected_gradient_norm(evaluation.point,
                                                         evaluation.native_grad)
        return float(np.linalg.norm(self.projected_gradient(x, evaluation.grad)))

    # -- objective -----------------------------------------------------------------------------
    @cached_property
    def compiled(self) -> CompiledObjective | None:
        """The objective and its gradient as compiled JAX programs
        (:mod:`solvers.compiled_objective`), built on first use; None when the forward map,
        the regularizer's operator or its functional has no JAX form. Set it to None to
        evaluate through the operators' own methods."""
        return CompiledObjective.of(self.forward, self.data, self.regularizer,
                                    (self.lower, self.upper))

    @property
    def compiles(self) -> bool:
        """Whether :meth:`evaluate` (without ``jacobians``) runs the :attr:`compiled` programs:
        the problem is deterministic and all its operators have JAX forms."""
        return not self.stochastic and self.compiled is not None

    def evaluate(self, x, iteration: int = 0, seed: int = 0,
                 jacobians: bool = False) -> Evaluation:
        """The objective at ``x``; gradient computed on demand (one reverse pass).

        Without ``jacobians``, a problem whose operators all have JAX forms evaluates by compiled
        JAX programs (:attr:`compiled`). Otherwise each operator is linearized, and a data
        map and regularizer after the same inner operator (e.g. a network at the voxel
        centres) evaluate it once and pull back through it once
        (:func:`operators.linearize_together`).

        Parameters
        ----------
        x : array_like
            The point, shape :attr:`dims`.
        iteration, seed : int, optional
            Pick a stochastic ``value_and_grad``'s sample; otherwise unused.
        jacobians : bool, optional
            Whether the evaluation must carry the Jacobians of :math:`F` and :math:`K`
            (``forward_jacobian``, ``regularizer_jacobian``), as Gauss–Newton and PDHG need;
            default False.
        """
        if self.stochastic:
            loss, grad = self.value_and_grad(x, iteration, np.random.default_rng([seed,
                                                                                 iteration]))
            grad = np.asarray(grad, dtype=self.dtype).reshape(self.dims)
            return Evaluation(loss, np.nan, np.nan, grad=grad, sample=iteration)
        if not jacobians and self.compiled is not None:
            misfit, reg, point, grad = self.compiled(self.forward._as_input(x), self.lam)
            return Evaluation(misfit + self.lam * reg, misfit, reg, grad_fn=grad, point=point)
        ops = [self.forward] + ([] if self.regularizer is None else [self.regularizer.op])
        linearized, pull = linearize_together(ops, x)
        jf, jk = linearized[0], (linearized[1] if len(linearized) > 1 else None)
        residual = jf.value - self.data
        misfit = sum_of_squares(residual)
        reg = 0.0 if jk is None else float(self.regularizer.functional(jk.value))

        def grad():
            ws = [residual]
            if jk is not None:
                ws.append(self.regularizer.functional.grad(jk.value) if self.lam > 0 else None)
            return np.asarray(pull(ws, (2.0, self.lam)[:len(ws)]), dtype=self.dtype).reshape(
                self.dims)

        return Evaluation(misfit + self.lam * reg, misfit, reg, grad_fn=grad,
                          forward_jacobian=jf, regularizer_jacobian=jk)

    def objective(self, x) -> float:
        """:math:`L(x)` (the full, deterministic objective)."""
        r = self.forward(x) - self.data
        reg = 0.0 if self.regularizer is None else self.regularizer(x)
        return sum_of_squares(r) + self.lam * reg

    def __repr__(self) -> str:
        return (f"<Problem {self.name}: params {self.dims}, data "
                f"{self.forward.dimsd}, regularizer={self.regularizer}, lam={self.lam:g}, "
                f"bounded={self.bounded}, linearizable={self.linearizable}, "
                f"stochastic={self.stochastic}>")
