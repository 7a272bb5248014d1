r"""The spectral norm :math:`\|A\|_2` of a linear operator, estimated by power iteration.

Primal–dual step sizes need :math:`\|A\|`; the estimate runs the power method on
:math:`A^\mathsf{H} A` from a random start,

.. math:: v_{k+1} = \frac{A^\mathsf{H} A v_k}{\|A^\mathsf{H} A v_k\|}, \qquad
          \|A\| \approx \|A^\mathsf{H} A v_k\|^{1/2},

which approaches the norm from below (a margin of a few per cent is customary).
"""

from __future__ import annotations

import numpy as np

from operators.base import LinearOperator


def operator_norm(op: LinearOperator, iterations: int = 20, seed=0) -> float:
    r""":math:`\|A\|_2` by ``iterations`` power iterations on :math:`A^\mathsf{H} A`.

    Parameters
    ----------
    op : operators.LinearOperator
        The operator :math:`A` (e.g. a stack of Jacobians from :func:`operators.vstack`).
    iterations : int, optional
        Power iterations (default 20); each applies :math:`A` and :math:`A^\mathsf{H}` once.
    seed : int or numpy.random.Generator, optional
        Randomness of the start vector.

    Returns
    -------
    float
        The estimate, in the units of :math:`A` (0 for the zero operator).
    """
    if not getattr(op, "linear", False):
        raise TypeError(f"operator_norm needs a linear operator; {op!r} is not: linearize it "
                        "first (op.linearize(x))")
    if int(iterations) < 1:
        raise ValueError(f"iterations must be >= 1, got {iterations}")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    v = rng.standard_normal(op.dims).astype(op.dtype)
    v /= np.linalg.norm(v)
    value = 0.0
    for _ in range(int(iterations)):
        w = op.adjoint(op(v))
        value = float(np.linalg.norm(w))
        if value == 0:
            return 0.0
        v = w / value
    return float(np.sqrt(value))
