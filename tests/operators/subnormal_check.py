r"""Run by ``test_rte_sweep_cpu.py`` in a process of its own: Numba's threads start from this
process's main thread, which keeps subnormal numbers (as NumPy does), before any sweep runs.
Each sweep is then called directly on one segment whose contribution is subnormal
(:math:`10^{-20} \cdot 10^{-20}`); prints, as JSON, the largest output of each sweep and the
smallest product of the same numbers by Numba's threads afterwards."""

import json

import numba
import numpy as np

from operators.rte.numba_targets import compiled_sweeps

TINY = np.float32(1e-20)


@numba.njit(parallel=True)
def products(a):
    """``a * a`` on Numba's threads."""
    out = np.empty_like(a)
    for i in numba.prange(a.size):
        out[i] = a[i] * a[i]
    return out


products(np.ones(64, np.float32))  # Numba's threads start here, from the main thread
sweeps = compiled_sweeps(1, 1, "float32")
n_rays, n_eta = 8, 32
coef = np.zeros((1, 8, n_eta), np.float32)  # rows 0-3: the gas's cubic, 4-7: Planck's
coef[0, 3] = 1.0  # cross-section row 1 at every offset: the optical depth is the amount
coef[0, 7] = TINY  # Planck radiance 1e-20
index = np.zeros((n_rays, 1), np.int32)
amount = np.full((n_rays, 1, 1), TINY)  # optical depth 1e-20
offset = np.zeros((n_rays, 1), np.float32)
n_segments = np.ones(n_rays, np.int32)
order = np.arange(n_rays, dtype=np.int32)
zeros = np.zeros((1, n_eta), np.float32)
spectra = [np.full((n_rays, n_eta), np.nan, np.float32) for _ in range(3)]
sweeps.forward(coef, index, amount, offset, n_segments, order, zeros, spectra[0])
sweeps.forward_mode(coef, index, amount, offset, n_segments, order, zeros, amount, offset,
                    zeros, spectra[1], spectra[2])
d_weights = np.full((n_rays, 1, 2), np.nan, np.float32)
sweeps.reverse(coef, index, amount, offset, n_segments, order, np.zeros((n_rays, n_eta),
               np.float32), np.full((n_rays, n_eta), TINY), d_weights,
               np.empty((0, n_eta), np.float32))
print(json.dumps({
    "forward": float(np.abs(spectra[0]).max()),
    "forward_mode": float(np.abs(spectra[2]).max()),
    "reverse": float(np.abs(d_weights).max()),
    "threads_after": float(products(np.full(64, TINY)).min()),
}))
