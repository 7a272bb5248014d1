r"""L-BFGS from jaxopt (``jaxopt.LBFGS``, or ``jaxopt.LBFGSB`` when the problem has bounds).

The objective is whatever the problem computes (NumPy, JAX or torch operators): it reaches
jaxopt through :func:`jax.pure_callback` returning the value and the gradient, so jaxopt runs
its algorithm and line search (zoom, strong Wolfe) jit-compiled around a host call. The loop,
logging, stopping rules and checkpoints are ours; the full jaxopt state (L-BFGS memory
included) is saved, so a resumed run reproduces an uninterrupted one.

jaxopt runs in the problem's dtype: for a float64 problem inside :func:`operators.precision`,
JAX's 64-bit mode for the calling thread only, so the process's setting never changes. The host
callback may run on one of XLA's threads, which that mode does not reach and where JAX would
round float64 values to float32; the parameters, the value and the gradient therefore cross the
callback as their bits, in uint32 words (:func:`_to_words`, :func:`_from_words`), which no mode
changes.

The first iteration of a run compiles jaxopt's update (seconds); a solver instance keeps the
compiled update for the last problem it solved, so a resume or a second run on that problem
starts at once. Upstream jaxopt is no longer developed (it warns so on import); the solver uses
only its stable L-BFGS(-B) classes.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from operators import precision
from solvers.base import Solver, Step
from solvers.evaluation_cache import EvaluationCache
from solvers.options import SolverOptions, option
from solvers.registry import register

_LEAF = "leaf"


@dataclass(frozen=True)
class JaxoptLBFGSOptions(SolverOptions):
    """Options of ``jaxopt-lbfgs`` (:class:`JaxoptLBFGS`), passed to jaxopt.

    Attributes
    ----------
    history_size : int
        Number of correction pairs kept (default 10); >= 1.
    tol : float
        Stop when jaxopt's error (gradient norm, projected with bounds; loss units per
        parameter unit) is at most ``tol`` (default 1e-8); >= 0.
    maxls : int
        Maximum line-search steps (default 30); >= 1.
    """

    history_size: int = option(10, ">= 1", lambda v: v >= 1)
    tol: float = option(1e-8, ">= 0", lambda v: v >= 0)
    maxls: int = option(30, ">= 1", lambda v: v >= 1)


def _word_shape(dims, dtype) -> tuple[int, ...]:
    """Shape of an array of shape ``dims`` and float ``dtype`` (float32 or float64) as uint32
    words, as :func:`jax.lax.bitcast_convert_type` gives it (a last axis of 2 for float64)."""
    words = np.dtype(dtype).itemsize // 4
    return (*dims, words) if words > 1 else tuple(dims)


def _to_words(value, dtype, dims) -> np.ndarray:
    """The bits of ``value`` (shape ``dims``, cast to ``dtype``) as uint32 words."""
    flat = np.ascontiguousarray(value, dtype).reshape(-1)
    return flat.view(np.uint32).reshape(_word_shape(dims, dtype))


def _from_words(words, dtype, dims) -> np.ndarray:
    """The array of ``dtype`` and shape ``dims`` whose bits are the uint32 ``words``."""
    return np.ascontiguousarray(words, np.uint32).reshape(-1).view(dtype).reshape(dims)


@register("jaxopt-lbfgs")
class JaxoptLBFGS(Solver):
    """jaxopt L-BFGS (L-BFGS-B with bounds); see the module docstring and
    :class:`JaxoptLBFGSOptions`."""

    Options = JaxoptLBFGSOptions
    stochastic_ok = False

    def _setup(self, run):
        """The jaxopt solver for ``run.problem``, pointed at ``run``.

        The jaxopt solver (and its compiled update) is kept on this instance for the last
        problem it saw, so repeated runs (e.g. a resume) do not compile again; its host
        callback evaluates through whichever run is active.
        """
        cached = getattr(self, "_compiled", None)
        if cached is None or cached[0] is not run.problem:
            with precision(run.problem.dtype):  # jaxopt makes constants as it is built
                cached = (run.problem, *self._build(run.problem))
            self._compiled = cached
        _, solver, extra, active = cached
        active["run"] = run
        if "cache" not in run.scratch:
            run.scratch["cache"] = EvaluationCache()
            run.scratch["cache"].put(run.x, run.current)
        return solver, extra, run.scratch["cache"]

    def _build(self, problem):
        import jaxopt

        active = {}
        dtype, dims = problem.dtype, problem.dims
        out_shapes = (jax.ShapeDtypeStruct(_word_shape((), dtype), np.uint32),
                      jax.ShapeDtypeStruct(_word_shape(dims, dtype), np.uint32))

        def host(words):
            run = active["run"]
            # jaxopt's trial points may lie a rounding error outside the box, where a forward
            # model may refuse them (e.g. a mole fraction of -1e-14)
            x = problem.project(_from_words(words, dtype, dims))
            cache = run.scratch["cache"]
            ev = cache.get(x) or cache.put(x, run.evaluate(x))
            return _to_words(ev.loss, dtype, ()), _to_words(ev.grad, dtype, dims)

        def fun(params):
            loss, grad = jax.pure_callback(host, out_shapes,
                                           jax.lax.bitcast_convert_type(params, jnp.uint32))
            return (jax.lax.bitcast_convert_type(loss, dtype),
                    jax.lax.bitcast_convert_type(grad, dtype))

        o = self.options
        kwargs = {"value_and_grad": True, "history_size": o.history_size, "tol": o.tol,
                  "maxls": o.maxls}
        if not problem.bounded:
            return jaxopt.LBFGS(fun, **kwargs), {}, active
        lo = -np.inf if problem.lower is None else problem.lower
        hi = np.inf if problem.upper is None else problem.upper
        bounds = (jnp.asarray(np.broadcast_to(lo, problem.dims), problem.dtype),
                  jnp.asarray(np.broadcast_to(hi, problem.dims), problem.dtype))
        return jaxopt.LBFGSB(fun, **kwargs), {"bounds": bounds}, active

    def init_state(self, run):
        solver, extra, _ = self._setup(run)
        with precision(run.problem.dtype):
            return {"jaxopt": solver.init_state(jnp.asarray(run.x), **extra)}

    def state_to_arrays(self, run):
        leaves = jax.tree_util.tree_leaves(run.state["jaxopt"])
        return {f"{_LEAF}{i:03d}": np.asarray(leaf) for i, leaf in enumerate(leaves)}

    def state_from_arrays(self, arrays, run):
        template = self.init_state(run)["jaxopt"]
        treedef = jax.tree_util.tree_structure(template)
        with precision(run.problem.dtype):
            leaves = [jnp.asarray(arrays[f"{_LEAF}{i:03d}"]) for i in range(treedef.num_leaves)]
        return {"jaxopt": jax.tree_util.tree_unflatten(treedef, leaves)}

    def step(self, run) -> Step:
        solver, extra, cache = self._setup(run)
        with precision(run.problem.dtype):
            params, state = solver.update(jnp.asarray(run.x), run.state["jaxopt"], **extra)
        # jaxopt's projected iterate may lie a rounding error outside the box
        x = run.problem.project(np.asarray(params, dtype=run.problem.dtype))
        ev = cache.get(x) or run.evaluate(x)
        error = float(state.error)
        stop = None
        if error <= self.options.tol:
            stop = f"converged: jaxopt error {error:.3e} <= tol {self.options.tol:g}"
        elif bool(state.failed_linesearch):
            stop = f"line search failed (jaxopt error {error:.3e})"
        return Step(x, ev, {"jaxopt": state}, {"step": float(state.stepsize)}, stop=stop)
