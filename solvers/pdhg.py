r"""Primal–dual hybrid gradient for a nonsmooth regularizer and a nonlinear forward map.

This is the linearized scheme, not the nonlinear PDHG of Valkonen (2014): each outer
iteration linearizes :math:`F` and :math:`K` at :math:`\theta_k` (Jacobians :math:`J`, :math:`L`)
and runs Chambolle–Pock iterations (Chambolle & Pock, J. Math. Imaging Vis. 40, 2011, with
:math:`\vartheta = 1`) on the convex model

.. math:: \min_{\theta \in C}\ \|J(\theta - \theta_k) + F(\theta_k) - d\|^2
          + \lambda\, g(L(\theta - \theta_k) + K(\theta_k)),

both terms dualized with the stacked operator :math:`A = (J; L)` and the box :math:`C` of the
bounds handled by projection in the primal step:

.. math::
    \theta^{+} = P_C(\theta - \tau A^\mathsf{T} y), \quad
    \bar\theta = \theta^{+} + \vartheta(\theta^{+} - \theta), \quad
    y^{+} = \mathrm{prox}_{\sigma h^*}(y + \sigma A \bar\theta),

with :math:`\tau = \sigma = 0.99 / \|A\|` (power iteration, 5 % margin). The dual variables are
kept from one outer iteration to the next. If :math:`F` and :math:`K` are linear the model is
exact and the run is plain Chambolle–Pock; otherwise a step that increases the true objective
is halved until it does not (at most ``max_backtracks`` times).
"""

from __future__ import annotations

import numpy as np

from operators import Composite
from solvers.base import Solver, Step, UnsupportedProblemError
from solvers.registry import register


def _operator_norm(apply, adjoint, dims, dtype, iterations, rng) -> float:
    """:math:`\\|A\\|` by power iteration on :math:`A^\\mathsf{T}A`."""
    v = rng.standard_normal(dims).astype(dtype)
    v /= np.linalg.norm(v)
    value = 0.0
    for _ in range(iterations):
        w = adjoint(apply(v))
        value = float(np.linalg.norm(w))
        if value == 0:
            return 0.0
        v = w / value
    return float(np.sqrt(value))


@register("pdhg")
class PDHG(Solver):
    """Linearized primal–dual (Chambolle–Pock) iterations; see the module docstring.

    Options
    -------
    inner_iter : int
        Chambolle–Pock iterations per outer iteration (default 50).
    tau, sigma : float or None
        Primal and dual step sizes; None picks :math:`0.99/\\|A\\|` for both
        (need :math:`\\tau\\sigma\\|A\\|^2 < 1`).
    norm_iter : int
        Power iterations for :math:`\\|A\\|` (default 20); recomputed every outer iteration
        when :math:`F` or :math:`K` is nonlinear, once otherwise.
    max_backtracks : int
        Step halvings on the true objective per outer iteration (default 10).
    """

    defaults = {"inner_iter": 50, "tau": None, "sigma": None, "norm_iter": 20,
                "max_backtracks": 10}
    supports = frozenset({"generic", "voxel", "neural-centres"})
    kind_advice = {"neural-field": (
        "Linearizing a neural field queried at every ray sample in weight space makes no "
        "sense: use the voxel-centre neural reparameterization (kind='neural-centres') or a "
        "first-order solver such as 'adam'.")}
    stochastic_ok = False

    def check_options(self):
        o = self.options
        steps_ok = all(o[k] is None or o[k] > 0 for k in ("tau", "sigma"))
        if not (steps_ok and (o["tau"] is None) == (o["sigma"] is None)
                and int(o["inner_iter"]) >= 1 and int(o["norm_iter"]) >= 1
                and int(o["max_backtracks"]) >= 0):
            raise ValueError(f"pdhg options out of range: need tau and sigma both None or both "
                             f"> 0, inner_iter >= 1, norm_iter >= 1, max_backtracks >= 0; "
                             f"got {o}")

    def check_problem(self, problem):
        reg = problem.regularizer
        if reg is not None and isinstance(reg.functional, Composite):
            raise UnsupportedProblemError(
                "pdhg needs the regularizer's outer functional to have a proximal map; give "
                "it as Regularizer(g, K) with g e.g. operators.L1, not a Composite g(Ax)"
            )

    def _uses_regularizer(self, problem) -> bool:
        return problem.regularizer is not None and problem.lam > 0

    def _linear(self, problem) -> bool:
        return problem.forward.linear and (not self._uses_regularizer(problem)
                                           or problem.regularizer.operator.linear)

    def init_state(self, run):
        problem = run.problem
        state = {"p": np.zeros(problem.forward.dimsd, problem.dtype), "norm": np.nan}
        if self._uses_regularizer(problem):
            state["q"] = np.zeros(problem.regularizer.operator.dimsd, problem.dtype)
        return state

    def step(self, run) -> Step:
        o = self.options
        problem = run.problem
        current = run.linearized()
        jf = current.forward_jacobian
        use_reg = self._uses_regularizer(problem)
        jk = current.regularizer_jacobian if use_reg else None

        def apply(v):
            return [jf.jvp(None, v)] + ([jk.jvp(None, v)] if use_reg else [])

        def adjoint(ys):
            out = jf.vjp(None, ys[0])
            return out + jk.vjp(None, ys[1]) if use_reg else out

        n_data = int(np.prod(jf.dimsd))
        norm = run.state["norm"]
        if not (self._linear(problem) and np.isfinite(norm)):
            norm = 1.05 * _operator_norm(
                lambda v: np.concatenate([a.ravel() for a in apply(v)]),
                lambda y: adjoint(np.split(y, [n_data])),
                problem.dims, problem.dtype, int(o["norm_iter"]), run.rng())
        tau = o["tau"] or 0.99 / max(norm, np.finfo(float).tiny)
        sigma = o["sigma"] or 0.99 / max(norm, np.finfo(float).tiny)

        x0 = run.x
        b = problem.data - jf.value                    # data model: J (x - x0) - b
        c = jk.value if use_reg else None              # regularizer model: L (x - x0) + c
        g, lam = (problem.regularizer.functional, problem.lam) if use_reg else (None, 0.0)
        p, q = run.state["p"], run.state.get("q")
        x = x0
        for _ in range(int(o["inner_iter"])):
            x_new = problem.project(x - tau * adjoint([p, q]))
            x_bar = 2.0 * x_new - x
            a = apply(x_bar - x0)
            # prox of sigma h1* for h1(u) = ||u - b||^2 (Moreau)
            v = p + sigma * a[0]
            p = (v - sigma * b) / (1.0 + sigma / 2.0)
            if use_reg:
                # prox of sigma h2* for h2(u) = lam g(u + c): lam prox_{(sigma/lam) g*}(.)
                q = lam * g.prox_dual((q + sigma * (a[1] + c)) / lam, sigma / lam)
            x = x_new

        state = {"p": p.astype(problem.dtype), "norm": norm}
        if use_reg:
            state["q"] = q.astype(problem.dtype)
        target = x
        trial = run.evaluate(target)
        alpha = 1.0
        if not self._linear(problem):
            for _ in range(int(o["max_backtracks"])):
                if trial.loss <= current.loss:
                    break
                alpha /= 2
                x = x0 + alpha * (target - x0)
                trial = run.evaluate(x)
        return Step(x.astype(problem.dtype, copy=False), trial, state,
                    {"step": alpha, "tau": tau, "sigma": sigma})
