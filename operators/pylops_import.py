"""pylops, imported without importing torch.

pylops imports torch whenever torch is installed (for its own torch operator, which
:mod:`operators` does not use), and importing torch takes seconds and changes the process (its
thread pools, its CUDA state). Here pylops is imported with torch hidden from its availability
check, so ``import operators`` leaves torch out; torch imported later works as usual, and
pylops' own torch operator reports torch as unavailable. When torch is already imported, pylops
is imported as it is.
"""

from __future__ import annotations

import sys

import scipy.signal  # noqa: F401  (imported first: scipy's array-API checks read sys.modules)
import scipy.sparse.linalg  # noqa: F401

if "torch" in sys.modules or "pylops" in sys.modules:
    import pylops
else:
    sys.modules["torch"] = None  # find_spec("torch") answers None: pylops skips torch
    try:
        import pylops
    finally:
        del sys.modules["torch"]

__all__ = ["pylops"]
