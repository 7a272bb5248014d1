r"""Sample placement along rays for the neural renderer (coarse-to-fine, as in NeRF).

Every ray is clipped to the domain box, :math:`t \in [t_\mathrm{near}, t_\mathrm{far}]` (m).

* **Stratified samples**: the chord cut into :math:`n` equal bins, one sample per bin at
  :math:`t_i = t_\mathrm{near} + (i + u_i)\,\Delta`, :math:`u_i \in [0, 1)` random in training
  and :math:`1/2` (bin midpoints) for deterministic evaluation.
* **Sample lengths**: each sample stands for the part of the chord nearer to it than to its
  neighbours (boundaries half way between consecutive samples, the ends at
  :math:`t_\mathrm{near}` and :math:`t_\mathrm{far}`), so the lengths :math:`\delta_i` sum to
  the chord and the ray is a piecewise-homogeneous medium, as the emission kernel assumes. For
  bin midpoints this is the bin width.
* **Importance samples**: from the coarse fields, the opacity of sample :math:`i` is
  :math:`\alpha_i = 1 - e^{-\bar\kappa_i \delta_i}` with the Planck-mean absorption
  coefficient :math:`\bar\kappa` (:class:`PlanckMeanOpacity`), and its weight
  :math:`w_i = \alpha_i \prod_{j<i} (1 - \alpha_j)`, the fraction of the ray's grey emission
  that sample contributes at the camera. New samples are drawn from the piecewise-constant
  density proportional to :math:`w_i + \epsilon` over the samples' intervals (inverse CDF;
  :math:`\epsilon` keeps rays through cold gas sampled everywhere).

No gradient flows through the sample placement.
"""

from __future__ import annotations

import numpy as np
import torch

from invflame.spectroscopy.table_inputs import FIXED_SELF_FRACTION


def stratified(t_near: torch.Tensor, t_far: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """Stratified distances (m), shape ``(n_rays, n)``, for ``offsets`` ``(n_rays, n)`` in
    [0, 1) (0.5 for bin midpoints)."""
    n = offsets.shape[-1]
    bins = torch.arange(n, dtype=offsets.dtype, device=offsets.device)
    return t_near[:, None] + (bins + offsets) * ((t_far - t_near) / n)[:, None]


def sample_bounds(t: torch.Tensor, t_near: torch.Tensor, t_far: torch.Tensor) -> torch.Tensor:
    """Boundaries ``(n_rays, n + 1)`` of the chord parts of sorted samples ``t`` (m)."""
    middle = 0.5 * (t[:, 1:] + t[:, :-1])
    return torch.cat([t_near[:, None], middle, t_far[:, None]], dim=1)


def sample_lengths(t: torch.Tensor, t_near: torch.Tensor, t_far: torch.Tensor) -> torch.Tensor:
    """Lengths (m) of the chord parts of sorted samples ``t`` ``(n_rays, n)``; rows sum to
    ``t_far - t_near``."""
    return torch.diff(sample_bounds(t, t_near, t_far), dim=1)


def emission_weights(kappa: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
    r""":math:`w_i = \alpha_i \prod_{j<i}(1 - \alpha_j)`, :math:`\alpha = 1 -
    e^{-\kappa\delta}`, for ``kappa`` (m⁻¹) and ``lengths`` (m) ``(n_rays, n)``."""
    tau = kappa * lengths
    before = torch.cumsum(tau, dim=1) - tau
    return -torch.expm1(-tau) * torch.exp(-before)


def importance(bounds: torch.Tensor, weights: torch.Tensor, u: torch.Tensor,
               floor: float = 1e-3) -> torch.Tensor:
    """Distances (m) drawn by inverse CDF from the piecewise-constant density ∝ weights.

    Parameters
    ----------
    bounds : torch.Tensor, shape (n_rays, n + 1)
        Interval boundaries in m (increasing along each row).
    weights : torch.Tensor, shape (n_rays, n)
        Non-negative weight of each interval.
    u : torch.Tensor, shape (n_rays, m)
        Quantiles in [0, 1).
    floor : float, optional
        Added to the normalized weights so that every interval keeps some probability.

    Returns
    -------
    torch.Tensor, shape (n_rays, m)
    """
    pdf = weights / weights.sum(dim=1, keepdim=True).clamp_min(1e-30) + floor
    cdf = torch.cumsum(pdf, dim=1)
    cdf = torch.cat([torch.zeros_like(cdf[:, :1]), cdf / cdf[:, -1:]], dim=1)
    index = torch.searchsorted(cdf, u.contiguous(), right=True).clamp(1, pdf.shape[1])
    c0, c1 = cdf.gather(1, index - 1), cdf.gather(1, index)
    b0, b1 = bounds.gather(1, index - 1), bounds.gather(1, index)
    fraction = ((u - c0) / (c1 - c0).clamp_min(1e-30)).clamp(0.0, 1.0)
    return b0 + fraction * (b1 - b0)


class PlanckMeanOpacity:
    r"""Planck-mean absorption coefficient :math:`\bar\kappa(T, X)` in m⁻¹, tabulated in T.

    :math:`\bar\kappa = \sum_s X_s\, k_s(T)`, linear in the mole fractions: the
    per-species coefficients :math:`k_s(T)` (m⁻¹ per unit mole fraction, from
    :meth:`AbsorptionTable.planck_mean_kappa`) are tabulated on a temperature grid, with each
    species' lines broadened at the fixed fractions of
    :data:`~invflame.spectroscopy.table_inputs.FIXED_SELF_FRACTION` (the forward model
    broadens them by each point's own gas; for drawing samples along rays the fixed ones do),
    and interpolated linearly in T.

    Parameters
    ----------
    temperatures : array_like, shape (n_T,)
        Increasing temperature grid in K.
    per_species : array_like, shape (n_species, n_T)
        :math:`k_s(T)` in m⁻¹.
    """

    def __init__(self, temperatures, per_species):
        self.temperatures = torch.as_tensor(np.asarray(temperatures, dtype=np.float64))
        self.per_species = torch.as_tensor(np.asarray(per_species, dtype=np.float64))
        if self.per_species.shape[1:] != self.temperatures.shape:
            raise ValueError(f"per_species must have shape (n_species, {self.temperatures.numel()})"
                             f"; got {tuple(self.per_species.shape)}")

    @classmethod
    def from_table(cls, table, n_temperatures: int = 256) -> PlanckMeanOpacity:
        """Tabulate from an :class:`~invflame.spectroscopy.absorption_table.AbsorptionTable`
        over its temperature range (``n_temperatures`` points)."""
        temperatures = np.linspace(table.temperatures[0], table.temperatures[-1],
                                   int(n_temperatures))
        n_species = len(table.species)
        fractions = [FIXED_SELF_FRACTION.get(name) or 1.0 for name in table.species]
        per_species = [
            table.planck_mean_kappa(temperatures, np.broadcast_to(
                (fractions[s] * np.eye(n_species)[s])[:, None], (n_species, temperatures.size))
            ) / fractions[s]
            for s in range(n_species)
        ]
        return cls(temperatures, np.stack(per_species))

    def __call__(self, fields: torch.Tensor) -> torch.Tensor:
        r""":math:`\bar\kappa` in m⁻¹ for fields ``(1 + n_species, ...)`` (T in K, then mole
        fractions): shape ``fields.shape[1:]``."""
        nodes = self.temperatures.to(fields.dtype)
        table = self.per_species.to(fields.dtype)
        temperature = fields[0].clamp(nodes[0], nodes[-1])
        index = torch.searchsorted(nodes, temperature.contiguous(), right=True)
        index = index.clamp(1, nodes.numel() - 1)
        t0, t1 = nodes[index - 1], nodes[index]
        weight = (temperature - t0) / (t1 - t0)
        k = table[:, index - 1] * (1 - weight) + table[:, index] * weight
        return torch.sum(fields[1:1 + table.shape[0]] * k, dim=0)
