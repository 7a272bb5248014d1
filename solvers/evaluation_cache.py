"""Remember the last few objective evaluations by parameter value.

Optimizers that drive the evaluations themselves (scipy, jaxopt) call the objective at trial
points and only afterwards report the accepted point; the cache hands back that point's
evaluation (with its data misfit and regularizer parts) without evaluating it again.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from solvers.problem import Evaluation


class EvaluationCache:
    """Map parameter arrays (by their bytes) to evaluations, keeping the latest ``size``."""

    def __init__(self, size: int = 4):
        self.size = size
        self._items: OrderedDict[bytes, Evaluation] = OrderedDict()

    @staticmethod
    def _key(x) -> bytes:
        x = np.ascontiguousarray(x)
        return x.dtype.str.encode() + x.tobytes()

    def put(self, x, evaluation: Evaluation) -> Evaluation:
        """Store ``evaluation`` for ``x``; returns it."""
        self._items[self._key(x)] = evaluation
        while len(self._items) > self.size:
            self._items.popitem(last=False)
        return evaluation

    def get(self, x) -> Evaluation | None:
        """The evaluation stored for exactly ``x``, or None."""
        return self._items.get(self._key(x))
