"""Emission radiative transfer along rays through a hot gas: the flame-specific operators.

Thermal emission of a piecewise-homogeneous gas (and soot) in front of a background, seen
along fixed rays: Planck's law (:mod:`operators.rte.planck`), the spectral tables prepared
from absorption splines (:mod:`operators.rte.tables`, :mod:`operators.rte.blocks`), the
emission kernel and its derivatives (:mod:`operators.rte.kernel`) with its two
implementations of the sweeps (JAX's, :mod:`operators.rte.sweeps_xla`, and Numba's for CPUs,
:mod:`operators.rte.sweeps_numba`), and the kernel as an operator
(:mod:`operators.rte.operator`). The rest of :mod:`operators` knows nothing of the flame;
:mod:`operators` exports the names here that a user needs, Planck's law among them.
"""

from operators.rte.batches import DEFAULT_MEMORY_BUDGET, batch_rays_for
from operators.rte.dispatch import SWEEPS, choose_sweeps
from operators.rte.kernel import (
    check_background,
    emission_radiance,
    emission_radiance_jvp,
    radiance_kernel,
)
from operators.rte.operator import EmissionRTE, KernelOperator
from operators.rte.tables import SOOT_REFRACTIVE_INDEX, RTETables, rayleigh_soot_constant

__all__ = [
    "DEFAULT_MEMORY_BUDGET",
    "SOOT_REFRACTIVE_INDEX",
    "SWEEPS",
    "EmissionRTE",
    "KernelOperator",
    "RTETables",
    "batch_rays_for",
    "check_background",
    "choose_sweeps",
    "emission_radiance",
    "emission_radiance_jvp",
    "radiance_kernel",
    "rayleigh_soot_constant",
]
