r"""Rendering of measured pixel spectra from field functions along the sub-rays (NeRF style).

Every sub-ray of a pixel is rendered coarse to fine: stratified samples on its chord through
the domain box, fields from a coarse field function; more samples drawn by inverse CDF from
the coarse samples' emission weights (:mod:`~invflame.representations.neural.sampling`),
fields from a fine field function; each set of samples is a piecewise-homogeneous ray whose
radiance the JAX emission kernel (:func:`operators.emission_rte.emission_radiance`, through
:func:`operators.torch_bridge.torch_function`) computes. A pixel's spectrum is the mean of its
sub-rays' radiance convolved with the instrument lineshape.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import torch

from invflame.representations.neural.sampling import (
    PlanckMeanOpacity,
    emission_weights,
    importance,
    sample_bounds,
    sample_lengths,
    stratified,
)
from operators.emission_rte import batch_rays_for, emission_radiance, emission_radiance_jvp
from operators.interop import TORCH_DTYPES, to_jax, to_torch
from operators.torch_bridge import torch_function


class NeuralRenderer:
    """Coarse-to-fine rendering of measured pixel spectra from field functions.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Pixels (``scene.n_rays`` measured spectra, ``scene.rays_per_pixel`` sub-rays each,
        clipped to its grid's box, pixel-major in ``scene.segments``), emission tables, ILS
        matrix and dtype.
    n_coarse, n_fine : int, optional
        Stratified and importance samples per sub-ray (defaults 64 and 64).
    batch_rays : int, optional
        Pixels (measured rays) per rendering call, each with all its sub-rays (fixed, so the
        kernel compiles once); at most the scene's number of pixels.
    opacity : PlanckMeanOpacity, optional
        Planck-mean absorption coefficient for the sampling weights (default: tabulated from
        the scene's absorption table).
    """

    def __init__(self, scene, n_coarse: int = 64, n_fine: int = 64, batch_rays: int = 1024,
                 opacity: PlanckMeanOpacity | None = None):
        if n_coarse < 1 or n_fine < 0 or batch_rays < 1:
            raise ValueError(f"need n_coarse >= 1, n_fine >= 0 and batch_rays >= 1; got "
                             f"{n_coarse}, {n_fine}, {batch_rays}")
        if (getattr(scene, "background", None) is not None
                or getattr(scene, "soot", None) is not None):
            raise ValueError("the neural-field renderer models the gas alone: it has no background "
                             "radiance and no soot; use representation.kind = 'voxel' (or "
                             "'neural-centres') for a scene with [background] or soot")
        self.scene = scene
        self.n_coarse, self.n_fine = int(n_coarse), int(n_fine)
        self.n_rays = int(scene.n_rays)
        self.rays_per_pixel = int(getattr(scene, "rays_per_pixel", 1))
        seg = scene.segments
        if seg.n_rays != self.n_rays * self.rays_per_pixel:
            raise ValueError(f"the scene traced {seg.n_rays} sub-rays for {self.n_rays} pixels "
                             f"of {self.rays_per_pixel} sub-rays each; expected "
                             f"{self.n_rays * self.rays_per_pixel}")
        self.batch_rays = min(int(batch_rays), self.n_rays)
        self.batch_sub_rays = self.batch_rays * self.rays_per_pixel
        self.dtype = TORCH_DTYPES[np.dtype(scene.dtype)]
        self.origins, self.directions, self.t_near, self.t_far = (
            torch.tensor(a, dtype=self.dtype)
            for a in (seg.origins, seg.directions, seg.t_near, seg.t_far))
        self.ils = torch.tensor(scene.ils.matrix, dtype=self.dtype)
        self.opacity = PlanckMeanOpacity.from_table(scene.table) if opacity is None else opacity
        tables = scene.tables
        kernel_batch = batch_rays_for(tables, self.batch_sub_rays, scene.memory_budget)
        radiance = jax.jit(partial(emission_radiance, batch_rays=kernel_batch))
        self._radiance = torch_function(lambda f, s: radiance(tables, f, s))
        self._radiance_jvp = jax.jit(lambda f, s, df: emission_radiance_jvp(
            tables, f, s, df, jnp.zeros_like(s), kernel_batch)[1])

    def sub_rays(self, pixels: torch.Tensor) -> torch.Tensor:
        """Sub-ray indices ``(B · rays_per_pixel,)`` of pixels ``(B,)``, pixel-major."""
        s = self.rays_per_pixel
        return (pixels[:, None] * s + torch.arange(s, dtype=pixels.dtype)).reshape(-1)

    def batches(self) -> list[torch.Tensor]:
        """Pixel indices covering all pixels in order, in batches of ``batch_rays`` (the last
        one padded by repeating pixel 0; :meth:`unpad` drops the padding)."""
        index = torch.arange(self.n_rays)
        n_pad = -self.n_rays % self.batch_rays
        index = torch.cat([index, torch.zeros(n_pad, dtype=index.dtype)])
        return list(index.split(self.batch_rays))

    def deterministic_draws(self) -> tuple[torch.Tensor, torch.Tensor]:
        """Offsets (bin midpoints) and evenly spaced quantiles for a batch's sub-rays."""
        offsets = torch.full((self.batch_sub_rays, self.n_coarse), 0.5, dtype=self.dtype)
        quantiles = (torch.arange(self.n_fine, dtype=self.dtype) + 0.5) / self.n_fine
        return offsets, quantiles.expand(self.batch_sub_rays, -1)

    def random_draws(self, rng: np.random.Generator) -> tuple[torch.Tensor, torch.Tensor]:
        """Stratified offsets and quantiles for a batch's sub-rays, uniform in [0, 1)."""
        return (torch.tensor(rng.random((self.batch_sub_rays, self.n_coarse)), dtype=self.dtype),
                torch.tensor(rng.random((self.batch_sub_rays, self.n_fine)), dtype=self.dtype))

    def samples(self, rays: torch.Tensor, coarse, offsets, quantiles):
        """Sample distances and lengths (m) of a batch of sub-rays, and the coarse fields.

        Parameters
        ----------
        rays : torch.Tensor of int, shape (R,)
            Sub-ray indices (rows of ``scene.segments``).
        coarse : callable
            ``points (..., 3) in m -> fields (4, ...)`` (T in K, mole fractions).
        offsets, quantiles : torch.Tensor, shapes (R, n_coarse), (R, n_fine)
            Stratified offsets and inverse-CDF quantiles in [0, 1).

        Returns
        -------
        coarse_fields : torch.Tensor, shape (4, R, n_coarse)
        coarse_lengths : torch.Tensor, shape (R, n_coarse)
        t_fine, fine_lengths : torch.Tensor, shape (R, n_coarse + n_fine)
            Merged, sorted sample distances and their lengths, in m.
        """
        t_near, t_far = self.t_near[rays], self.t_far[rays]
        t_coarse = stratified(t_near, t_far, offsets)
        coarse_fields = coarse(self.points(rays, t_coarse))
        coarse_lengths = sample_lengths(t_coarse, t_near, t_far)
        with torch.no_grad():
            weights = emission_weights(self.opacity(coarse_fields.detach()), coarse_lengths)
            t_extra = importance(sample_bounds(t_coarse, t_near, t_far), weights, quantiles)
            t_fine = torch.sort(torch.cat([t_coarse, t_extra], dim=1), dim=1).values
        return coarse_fields, coarse_lengths, t_fine, sample_lengths(t_fine, t_near, t_far)

    def points(self, rays: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """Positions (m) ``(R, n, 3)`` at distances ``t`` ``(R, n)`` along sub-rays."""
        return self.origins[rays, None, :] + t[..., None] * self.directions[rays, None, :]

    def _pixels(self, radiance: torch.Tensor) -> torch.Tensor:
        """Sub-ray radiance ``(B · rays_per_pixel, n_eta)`` → pixel spectra ``(B, n_out)``:
        the mean over each pixel's sub-rays, then the ILS."""
        per_pixel = radiance.reshape(-1, self.rays_per_pixel, radiance.shape[-1]).mean(dim=1)
        return per_pixel @ self.ils.T

    def measure(self, fields: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """Measured spectra ``(B, n_out)`` in W/(m²·sr·cm⁻¹) of the sampled sub-rays of ``B``
        pixels (``fields`` ``(4, B · rays_per_pixel, n)``, ``lengths`` in m): the emission
        kernel (torch-differentiable in ``fields``), the mean over sub-rays and the ILS."""
        return self._pixels(self._radiance(fields.contiguous(), lengths.contiguous()))

    def measure_jvp(self, fields, lengths, d_fields) -> torch.Tensor:
        """Directional derivative of :meth:`measure` along ``d_fields`` (forward mode)."""
        d_radiance = self._radiance_jvp(to_jax(fields.contiguous()), to_jax(lengths.contiguous()),
                                        to_jax(d_fields.contiguous()))
        return self._pixels(to_torch(d_radiance))

    def render(self, pixels, coarse, fine, offsets, quantiles):
        """Coarse and fine spectra ``(B, n_out)`` (W/(m²·sr·cm⁻¹)) of a batch of pixels.

        ``pixels`` ``(B,)`` are pixel indices; ``coarse`` and ``fine`` map points ``(..., 3)``
        in m to fields ``(4, ...)``; ``offsets`` and ``quantiles`` are per sub-ray, as in
        :meth:`samples`. Differentiable through both field functions.
        """
        rays = self.sub_rays(pixels)
        coarse_fields, coarse_lengths, t_fine, fine_lengths = self.samples(
            rays, coarse, offsets, quantiles)
        fine_fields = fine(self.points(rays, t_fine))
        return (self.measure(coarse_fields, coarse_lengths),
                self.measure(fine_fields, fine_lengths))

    def unpad(self, values: list[torch.Tensor]) -> torch.Tensor:
        """Concatenate per-batch outputs of :meth:`batches` and drop the padding."""
        return torch.cat(values)[:self.n_rays]

