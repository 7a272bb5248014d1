r"""A voxel that emits as the flame inside it: the emission-equivalent progress of a presumed
sub-voxel spread.

A voxel of the reconstruction grid that holds a thin flame sheet and cool gas emits more than
a uniform gas at its mean state would: emission grows faster than linearly with temperature.
Rendered at their mean state, the truth's own voxels emit 8–12 % less than the flame on a
twice finer grid (``docs/validation.md``, "Why the flame comes out too large"), and a fit that
matches the spectra with mean states makes the flame too hot or too wide.

The model here renders each voxel at the progress whose state emits what a presumed spread of
progress inside it emits, while the voxel's mean progress :math:`\bar s` stays the reported
field. The spread is two states :math:`\bar s \pm a` of equal weight (a double-delta presumed
PDF, the bounded variable kept inside :math:`[0, s_\text{max}]` about its mean), its half-width
from the resolved gradient as in LES models of sub-filter variance,

.. math:: a = \min\bigl(c\, |\nabla \bar s|\,\Delta,\; \bar s,\; s_\text{max} - \bar s\bigr),

with :math:`|\nabla\bar s|\Delta` the central difference over one voxel and :math:`c` the
spread (dimensionless). The emission compared is that of a thin gas at 690 cm⁻¹, the band's
centre, per unit volume: :math:`e(s, h) = X_\text{CO2}\, B_\nu(T) / T` (mole fraction ×
Planck function × number density, up to a constant). The rendered progress :math:`s_e` solves
:math:`e(s_e, h) = \tfrac12 [e(\bar s - a, h) + e(\bar s + a, h)]`, by bisection on the
monotone :math:`e` and one Newton step, which gives the derivatives of the implicit function
(JAX differentiates through the step, not the bisection).
"""

from __future__ import annotations

import numpy as np

from invflame.representations.state_relation import StateRelation
from operators.rte.planck import C2

PROXY_WAVENUMBER = 690.0
"""Wavenumber (cm⁻¹) of the emission proxy: the centre of the CO₂ ν₂ band's wings that the
quick and paper windows (650–725 and 660–710 cm⁻¹) see."""

BISECTIONS = {"numpy": 52, "jax": 30}
"""Bisections of :meth:`SubvoxelEmission.equivalent_progress` per array module: NumPy's reach
the resolution of float64; under JAX one Newton step follows, which squares the error of
30."""


class SubvoxelEmission:
    r"""Rendered progress of each voxel from its mean progress and a presumed spread.

    Parameters
    ----------
    relation : StateRelation
        The state relation whose states emit.
    spread : float
        :math:`c` of the half-width :math:`a = c\,|\nabla\bar s|\Delta` (dimensionless,
        positive).
    """

    def __init__(self, relation: StateRelation, spread: float):
        if not spread > 0:
            raise ValueError(f"the sub-voxel spread must be positive (dimensionless), got "
                             f"{spread}; leave the model out for none")
        self.relation = relation
        self.spread = float(spread)

    def emission(self, s, h, xp=np):
        r"""The thin-gas emission proxy :math:`X_\text{CO2} B_\nu(T)/T` at
        :data:`PROXY_WAVENUMBER` in the array module ``xp``, up to a constant (1/K)."""
        t, co2, _, _ = self.relation.states(s, h)
        return co2 / (t * xp.expm1(C2 * PROXY_WAVENUMBER / t))

    def rendered(self, s, h, xp=np):
        """The emission-equivalent progress of voxels ``s`` (mean progress, shape
        ``(nx, ny, nz)``) at factors ``h`` (same shape), in the array module ``xp`` (NumPy or
        ``jax.numpy``); differentiable under JAX."""
        s_max = self.relation.progress_max
        gradient = xp.sqrt(sum(g ** 2 for g in xp.gradient(s)) + 1e-24)
        a = xp.minimum(self.spread * gradient, xp.minimum(s, s_max - s))
        target = 0.5 * (self.emission(s - a, h, xp) + self.emission(s + a, h, xp))
        if xp is np:
            return self.equivalent_progress(target, h)
        import jax

        stop = jax.lax.stop_gradient
        s0 = stop(self.equivalent_progress(stop(target), stop(h), xp))
        value, slope = jax.jvp(lambda u: self.emission(u, h, xp), (s0,), (xp.ones_like(s0),))
        return s0 - (value - target) / slope

    def equivalent_progress(self, target, h, xp=np):
        """The progress in [0, s_max] whose :meth:`emission` at factors ``h`` meets ``target``
        (bisection on the increasing proxy, in the array module ``xp``)."""
        low = xp.zeros_like(target)
        high = xp.full_like(target, self.relation.progress_max)
        for _ in range(BISECTIONS["numpy" if xp is np else "jax"]):
            mid = 0.5 * (low + high)
            above = self.emission(mid, h, xp) > target
            low, high = xp.where(above, low, mid), xp.where(above, mid, high)
        return 0.5 * (low + high)
