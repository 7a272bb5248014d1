r"""Rendering of measured pixel spectra from field functions along the sub-rays (NeRF style).

Every sub-ray of a pixel is rendered coarse to fine: stratified samples on its chord through
the domain box, fields from a coarse field function; more samples drawn by inverse CDF from
the coarse samples' emission weights (:mod:`~invflame.representations.neural.sampling`),
fields from a fine field function; each set of samples is a piecewise-homogeneous ray whose
radiance the JAX emission kernel (:func:`operators.rte.kernel.emission_radiance`, through
:func:`operators.torch_bridge.torch_function`) computes, the coarse and the fine sets of a
batch in one kernel call. A pixel's spectrum is the mean of its sub-rays' radiance convolved
with the instrument lineshape.

The scene's background and known soot enter as in its voxel forward map
(:class:`~invflame.scene.Scene`): every sub-ray ends on its camera's background radiance,
which the kernel adds through the ray's transmittance, and a sample's soot volume fraction is
that of the voxel holding it (the soot field is piecewise constant per voxel, as the voxel
map sees it), a fifth kernel field beside the networks' four.
"""

from __future__ import annotations

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
from operators.interop import TORCH_DTYPES, to_jax, to_torch
from operators.rte import batch_rays_for, emission_radiance, emission_radiance_jvp
from operators.torch_bridge import torch_function

POINTS_PER_CALL = 2**17
"""Default sample points (coarse and fine, over all sub-rays) per rendering call. The networks
keep about 2 kB per point for the backward pass (float32, the default network), so a call
holds about 250 MB (``benchmarks/bench_neural.py`` prints the peak memory)."""


def voxel_lookup(grid, values, dtype: torch.dtype | None = None):
    """Voxel values as a function of position, piecewise constant per voxel.

    Parameters
    ----------
    grid : invflame.geometry.VoxelGrid
        The voxels (m).
    values : ndarray, shape (..., nx, ny, nz)
        Per voxel, in any units.
    dtype : torch.dtype, optional
        Of the values and of the positions (default: that of ``values``).

    Returns
    -------
    callable
        ``points (..., 3) in m -> values (...leading of values, ...points)``; a point outside
        the grid takes the value of the nearest voxel along each axis.
    """
    values = torch.tensor(values, dtype=dtype)
    lower, spacing = (torch.tensor(a, dtype=values.dtype) for a in (grid.lower, grid.spacing))
    top = torch.tensor(grid.shape) - 1

    def at(points: torch.Tensor) -> torch.Tensor:
        index = torch.minimum(torch.floor((points - lower) / spacing).long().clamp_min(0), top)
        return values[..., index[..., 0], index[..., 1], index[..., 2]]

    return at


class NeuralRenderer:
    """Coarse-to-fine rendering of measured pixel spectra from field functions.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Pixels (``scene.n_rays`` measured spectra, ``scene.rays_per_pixel`` sub-rays each,
        clipped to its grid's box, pixel-major in ``scene.segments``), emission tables, ILS
        matrix, dtype, and optionally a background (``scene.background``) and a known soot
        field (``scene.soot``).
    n_coarse, n_fine : int, optional
        Stratified and importance samples per sub-ray (defaults 64 and 64).
    batch_rays : int, optional
        Pixels (measured rays) per training batch, each with all its sub-rays; at most the
        scene's number of pixels.
    opacity : PlanckMeanOpacity, optional
        Planck-mean absorption coefficient for the sampling weights (default: tabulated from
        the scene's absorption table).
    chunk_rays : int, optional
        Pixels per rendering call (fixed, so the kernel compiles once): a training batch is
        rendered and differentiated in chunks of about this many pixels (equal parts of the
        batch), which bounds the memory of the networks' backward pass. Default:
        :data:`POINTS_PER_CALL` sample points per call; at most ``batch_rays``.

    Raises
    ------
    ValueError
        For a scene whose soot volume fraction is an unknown (``scene.soot_input``): the
        networks give temperature and mole fractions only.
    """

    def __init__(self, scene, n_coarse: int = 64, n_fine: int = 64, batch_rays: int = 1024,
                 opacity: PlanckMeanOpacity | None = None, chunk_rays: int | None = None):
        if (n_coarse < 1 or n_fine < 0 or batch_rays < 1
                or (chunk_rays is not None and chunk_rays < 1)):
            raise ValueError(f"need n_coarse >= 1, n_fine >= 0, batch_rays >= 1 and "
                             f"chunk_rays >= 1; got {n_coarse}, {n_fine}, {batch_rays}, "
                             f"{chunk_rays}")
        if getattr(scene, "soot_input", False):
            raise ValueError("the neural field gives temperature and mole fractions only, so "
                             "it cannot reconstruct soot: use representation.kind = 'voxel' "
                             "to reconstruct the soot volume fraction, or give a known soot "
                             "field (Scene(soot=...), which the neural field renders)")
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
        points_per_pixel = self.rays_per_pixel * (2 * self.n_coarse + self.n_fine)
        largest = min(int(chunk_rays or max(1, POINTS_PER_CALL // points_per_pixel)),
                      self.batch_rays)
        n_chunks = -(-self.batch_rays // largest)
        self.chunk_rays = -(-self.batch_rays // n_chunks)
        self.dtype = TORCH_DTYPES[np.dtype(scene.dtype)]
        self.origins, self.directions, self.t_near, self.t_far = (
            torch.tensor(a, dtype=self.dtype)
            for a in (seg.origins, seg.directions, seg.t_near, seg.t_far))
        self.ils = torch.tensor(scene.ils.matrix, dtype=self.dtype)
        self.opacity = PlanckMeanOpacity.from_table(scene.table) if opacity is None else opacity
        self._background, self._camera = self._background_per_camera(scene)
        self._soot = (None if getattr(scene, "soot", None) is None
                      else voxel_lookup(scene.grid, scene.soot, self.dtype))
        tables = scene.tables
        kernel_batch = batch_rays_for(tables, 2 * self.chunk_rays * self.rays_per_pixel,
                                      scene.memory_budget)
        self._radiance = torch_function(jax.jit(
            lambda f, s, *background: emission_radiance(tables, f, s, kernel_batch,
                                                        *background)))
        self._radiance_jvp = jax.jit(lambda f, s, df, *background: emission_radiance_jvp(
            tables, f, s, df, jnp.zeros_like(s), kernel_batch, *background)[1])

    def _background_per_camera(self, scene):
        """The background ``(n_cameras, n_eta)`` in W/(m²·sr·cm⁻¹) and the camera of every
        sub-ray, or ``(None, None)`` without a background."""
        background = getattr(scene, "background", None)
        if background is None:
            return None, None
        spectra = background.on_grid(scene.wavenumber, scene.rig.n_cameras)
        return (torch.tensor(spectra, dtype=self.dtype),
                torch.as_tensor(scene._sub_ray_camera()))

    def sub_rays(self, pixels: torch.Tensor) -> torch.Tensor:
        """Sub-ray indices ``(B · rays_per_pixel,)`` of pixels ``(B,)``, pixel-major."""
        s = self.rays_per_pixel
        return (pixels[:, None] * s + torch.arange(s, dtype=pixels.dtype)).reshape(-1)

    def chunks(self, n_pixels: int) -> list[tuple[slice, slice]]:
        """Pixel and sub-ray slices of ``n_pixels`` pixels in rendering calls of at most
        :attr:`chunk_rays` pixels."""
        s = self.rays_per_pixel
        return [(slice(p, p + self.chunk_rays), slice(p * s, (p + self.chunk_rays) * s))
                for p in range(0, n_pixels, self.chunk_rays)]

    def batches(self) -> list[torch.Tensor]:
        """Pixel indices covering all pixels in order, in rendering calls of
        :attr:`chunk_rays` (the last one padded by repeating pixel 0; :meth:`unpad` drops the
        padding)."""
        index = torch.arange(self.n_rays)
        n_pad = -self.n_rays % self.chunk_rays
        index = torch.cat([index, torch.zeros(n_pad, dtype=index.dtype)])
        return list(index.split(self.chunk_rays))

    def deterministic_draws(self, n_pixels: int | None = None
                            ) -> tuple[torch.Tensor, torch.Tensor]:
        """Offsets (bin midpoints) and evenly spaced quantiles for the sub-rays of
        ``n_pixels`` pixels (default ``batch_rays``)."""
        n = (self.batch_rays if n_pixels is None else int(n_pixels)) * self.rays_per_pixel
        offsets = torch.full((n, self.n_coarse), 0.5, dtype=self.dtype)
        quantiles = (torch.arange(self.n_fine, dtype=self.dtype) + 0.5) / self.n_fine
        return offsets, quantiles.expand(n, -1)

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
        t_coarse : torch.Tensor, shape (R, n_coarse)
            Stratified sample distances in m.
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
        return (t_coarse, coarse_fields, coarse_lengths, t_fine,
                sample_lengths(t_fine, t_near, t_far))

    def points(self, rays: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """Positions (m) ``(R, n, 3)`` at distances ``t`` ``(R, n)`` along sub-rays."""
        return self.origins[rays, None, :] + t[..., None] * self.directions[rays, None, :]

    def kernel_fields(self, fields: torch.Tensor, points: torch.Tensor) -> torch.Tensor:
        """The kernel's fields at samples: ``fields`` ``(4, R, n)``, with the scene's soot
        volume fraction at ``points`` ``(R, n, 3)`` (m) appended when it has soot."""
        if self._soot is None:
            return fields
        return torch.cat([fields, self._soot(points)[None]])

    def _background_of(self, rays: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """The kernel's background argument for sub-rays ``rays``: ``()`` without one."""
        return () if self._background is None else (self._background[self._camera[rays]],)

    def _pixels(self, radiance: torch.Tensor) -> torch.Tensor:
        """Sub-ray radiance ``(B · rays_per_pixel, n_eta)`` → pixel spectra ``(B, n_out)``:
        the mean over each pixel's sub-rays, then the ILS."""
        per_pixel = radiance.reshape(-1, self.rays_per_pixel, radiance.shape[-1]).mean(dim=1)
        return per_pixel @ self.ils.T

    def measure(self, rays: torch.Tensor, *sample_sets) -> list[torch.Tensor]:
        """Measured spectra ``(B, n_out)`` in W/(m²·sr·cm⁻¹) of sets of samples along the
        sub-rays ``rays`` of ``B`` pixels, all sets in one kernel call.

        Parameters
        ----------
        rays : torch.Tensor of int, shape (B · rays_per_pixel,)
            Sub-ray indices, pixel-major (:meth:`sub_rays`).
        *sample_sets : (fields, lengths)
            Per set, kernel fields ``(n_fields, B · rays_per_pixel, n)``
            (:meth:`kernel_fields`) and sample lengths ``(B · rays_per_pixel, n)`` in m; sets
            with fewer samples are padded with samples of zero length.

        Returns
        -------
        list of torch.Tensor
            The spectra of each set (the emission kernel, the mean over sub-rays, the ILS),
            differentiable in the fields.
        """
        n = max(lengths.shape[1] for _, lengths in sample_sets)
        fields = torch.cat([torch.cat([f, f[..., -1:].expand(-1, -1, n - f.shape[2])], dim=2)
                            for f, _ in sample_sets], dim=1)
        lengths = torch.cat([torch.nn.functional.pad(s, (0, n - s.shape[1]))
                             for _, s in sample_sets])
        background = self._background_of(rays.repeat(len(sample_sets)))
        radiance = self._radiance(fields, lengths, *background)
        return [self._pixels(r) for r in radiance.split(rays.numel())]

    def measure_jvp(self, rays, fields, lengths, d_fields) -> torch.Tensor:
        """Directional derivative of :meth:`measure` (one set of samples) along the tangent
        ``d_fields`` of its kernel fields (forward mode)."""
        d_radiance = self._radiance_jvp(to_jax(fields), to_jax(lengths), to_jax(d_fields),
                                        *(to_jax(b) for b in self._background_of(rays)))
        return self._pixels(to_torch(d_radiance))

    def render(self, pixels, coarse, fine, offsets, quantiles):
        """Coarse and fine spectra ``(B, n_out)`` (W/(m²·sr·cm⁻¹)) of a batch of pixels.

        ``pixels`` ``(B,)`` are pixel indices; ``coarse`` and ``fine`` map points ``(..., 3)``
        in m to fields ``(4, ...)``; ``offsets`` and ``quantiles`` are per sub-ray, as in
        :meth:`samples`. Differentiable through both field functions; one kernel call.
        """
        rays = self.sub_rays(pixels)
        t_coarse, coarse_fields, coarse_lengths, t_fine, fine_lengths = self.samples(
            rays, coarse, offsets, quantiles)
        fine_points = self.points(rays, t_fine)
        return tuple(self.measure(
            rays,
            (self.kernel_fields(coarse_fields, self.points(rays, t_coarse)), coarse_lengths),
            (self.kernel_fields(fine(fine_points), fine_points), fine_lengths)))

    def unpad(self, values: list[torch.Tensor]) -> torch.Tensor:
        """Concatenate per-call outputs of :meth:`batches` and drop the padding."""
        return torch.cat(values)[:self.n_rays]
