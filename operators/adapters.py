"""pylops (and scipy) linear operators as operators: :func:`aslinearoperator`.

The wrapper it builds is defined in :mod:`operators.base`, as are :class:`~operators.JaxOperator`
and :class:`~operators.TorchOperator`, since ``A @ pylops_op``, ``Operator.from_jax`` and
``Operator.from_torch`` build them there; this module imports that one.
"""

from __future__ import annotations

from operators.base import LinearOperator, _PylopsWrapper
from operators.pylops_import import pylops


def aslinearoperator(op, name: str | None = None) -> LinearOperator:
    """Any pylops (or scipy) linear operator as an :class:`operators.LinearOperator`.

    Parameters
    ----------
    op : pylops.LinearOperator or scipy.sparse.linalg.LinearOperator
        Operator with ``matvec``/``rmatvec`` (and ideally ``dims``/``dimsd``).
    name : str, optional
        Label for reprs and messages.
    """
    if isinstance(op, LinearOperator):
        return op
    return _PylopsWrapper(pylops.aslinearoperator(op), name=name)
