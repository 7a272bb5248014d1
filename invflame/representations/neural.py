r"""The NeRF-like representation: two neural fields rendered along the measurement rays.

The unknowns are the weights :math:`\theta = (\theta_c, \theta_f)` of a *coarse* and a *fine*
:class:`~invflame.representations.neural_field.FieldNetwork`. A measured spectrum belongs to a
camera pixel, the mean of the spectra of the pixel's ``scene.rays_per_pixel`` sub-rays
(rows ``p·s … p·s + s − 1`` of ``scene.segments`` for pixel ``p``). Every sub-ray is rendered
as in NeRF (Mildenhall et al. 2020), with the emission physics of the voxel path:

1. ``n_coarse`` stratified samples on the sub-ray's chord through the domain box
   (:mod:`~invflame.representations.neural_sampling`), fields from the coarse network;
2. ``n_fine`` more samples drawn by inverse CDF from the coarse samples' emission weights
   (opacity from the Planck-mean absorption coefficient), merged with the coarse ones and
   sorted; fields from the fine network;
3. each set of samples is a piecewise-homogeneous ray (sample lengths sum to the chord),
   rendered by the JAX emission kernel :func:`operators.emission_rte.emission_radiance`
   through :func:`operators.torch_bridge.torch_function` (its backward pass is the kernel's
   VJP); the sub-ray spectra of a pixel are averaged, then convolved with the instrument
   lineshape (the scene's ILS matrix).

**Training.** Solver iteration :math:`k` belongs to epoch :math:`e = \lfloor k / E \rfloor`,
:math:`E` = :attr:`NeuralFieldRepresentation.iterations_per_epoch` :math:`= \lceil N / B
\rceil` for :math:`N` pixels in batches of :math:`B`: the iterations of an epoch take
consecutive batches of one permutation of the pixels (drawn from ``default_rng([seed, e])``;
the last batch is filled up with pixels from the start of the permutation), so an epoch is a
pass over all pixels without replacement, and every batch is a uniformly random set of
:math:`B` pixels. The loss of iteration :math:`k` with batch :math:`\mathcal{B}` is

.. math:: \frac{N}{B} \sum_{p \in \mathcal{B}} \tfrac12\Big(
          \Big\|\frac{g^c_p - d_p}{\sigma_p}\Big\|^2
          + \Big\|\frac{g^f_p - d_p}{\sigma_p}\Big\|^2\Big) + \lambda\,\hat\Phi(\theta_f),

with :math:`\sigma` the noise standard deviation (W/(m²·sr·cm⁻¹)). Both renderings enter the
data term (NeRF style; the coarse one is what places the fine samples), with weight one half
each, so that the data term is an unbiased estimate of a noise-weighted sum of squares over
all pixels on the same scale as the deterministic problem's (about the number of
measurements when the model fits to the noise), and λ weighs the regularizer against it as it
does for voxels. The sample jitter of the sub-rays and the regularizer's voxel centres are
drawn from the iteration's ``rng``.

**Regularizer.** :math:`\Phi` is the voxel regularizer
(:func:`~invflame.representations.voxel.regularizer_for`) of the fine network's normalized
fields :math:`u = f/s` at the voxel centres: forward differences per metre between a centre
and its +1 neighbour along each axis (zero on the last layer), Tikhonov
:math:`\sum_d \mathrm{mean}((D_d u)^2)` or TV :math:`\sum_d \mathrm{mean}(|D_d u|)`, the means
over fields and voxels. Training estimates it without bias on a random set of
``batch_centres`` voxel centres (:class:`CentreRegularizer`: the network at those centres and
their neighbours); on all centres the estimate is :math:`\Phi` itself. So
:math:`\Phi_\text{neural}(\theta) = \Phi_\text{voxel}(\text{fields}(\theta))` and λ means the
same for both representations.

**Evaluation.** The problem's forward operator renders all pixels deterministically
(stratified bin midpoints, evenly spaced quantiles) with the fine network, divided by σ:
:math:`F(\theta) = g^f / \sigma` against data :math:`d / \sigma`; its regularizer is
:math:`\Phi` over all voxel centres.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import torch

import solvers
from invflame.geometry import VoxelGrid
from invflame.representations.neural_field import (
    TORCH_DTYPES,
    FieldNetwork,
    centre_points,
    pretrain,
    regularizer_after,
)
from invflame.representations.neural_sampling import (
    PlanckMeanOpacity,
    emission_weights,
    importance,
    sample_bounds,
    sample_lengths,
    stratified,
)
from invflame.representations.whitening import noise_weights, whitened
from operators import Operator, TorchOperator
from operators.emission_rte import batch_rays_for, emission_radiance, emission_radiance_jvp
from operators.interop import to_jax, to_numpy, to_torch
from operators.torch_bridge import torch_function


class CentreRegularizer:
    """Tikhonov or TV of a field function from forward differences between voxel centres.

    For voxel centres :math:`c_v`, :math:`v \\in \\mathcal{V}` (a set of :math:`B` distinct
    voxels) and a function :math:`u` of position giving normalized fields,

    .. math:: \\hat\\Phi = \\frac{1}{n_f B} \\sum_{v \\in \\mathcal{V}} \\sum_{d, c}
              h\\Big(\\frac{u_c(c_{v + e_d}) - u_c(c_v)}{\\Delta_d}\\Big),

    :math:`h(x) = x^2` (Tikhonov) or :math:`|x|` (TV), with :math:`v + e_d` the next voxel
    along axis :math:`d` (:math:`v` itself on the last layer: the difference is zero). Over all
    voxels this is :func:`operators.tikhonov` / :func:`operators.total_variation` of the
    fields sampled at the centres; over a uniformly random set of voxels it is an unbiased
    estimate of it.

    Parameters
    ----------
    kind : {"tikhonov", "tv"}
        The regularizer.
    grid : VoxelGrid
        Voxel centres and spacing (m).
    dtype : torch.dtype, optional
        Of the centres (default float32).
    """

    def __init__(self, kind: str, grid: VoxelGrid, dtype=torch.float32):
        if kind not in ("tikhonov", "tv"):
            raise ValueError(f"CentreRegularizer is 'tikhonov' or 'tv'; got {kind!r}")
        self.kind = kind
        self.points = centre_points(grid, dtype).reshape(-1, 3)
        self.spacing = torch.tensor(grid.spacing, dtype=dtype)
        index = np.indices(grid.shape).reshape(3, -1)
        neighbours = []
        for axis, n in enumerate(grid.shape):
            shifted = index.copy()
            shifted[axis] = np.minimum(shifted[axis] + 1, n - 1)
            neighbours.append(np.ravel_multi_index(tuple(shifted), grid.shape))
        self.neighbours = torch.as_tensor(np.stack(neighbours))

    @property
    def n_centres(self) -> int:
        """Number of voxel centres."""
        return self.points.shape[0]

    def __call__(self, u, index: torch.Tensor) -> torch.Tensor:
        """:math:`\\hat\\Phi` over the voxels ``index`` (1/m² for Tikhonov, 1/m for TV).

        Parameters
        ----------
        u : callable
            Points ``(..., 3)`` in m to normalized fields ``(n_f, ...)`` (dimensionless),
            differentiable if a gradient is wanted.
        index : torch.Tensor of int, shape (B,)
            Distinct C-order flat voxel indices.

        Returns
        -------
        torch.Tensor, scalar
        """
        points = self.points[torch.cat([index[None], self.neighbours[:, index]])]  # (4, B, 3)
        values = u(points)  # (n_f, 4, B): the centre, then its neighbours along x, y, z
        differences = (values[:, 1:] - values[:, :1]) / self.spacing[:, None]
        terms = differences**2 if self.kind == "tikhonov" else differences.abs()
        return terms.sum() / (values.shape[0] * index.numel())


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


class NeuralRendering(Operator):
    """Deterministic forward map of the neural representation: weights → measured spectra.

    All pixels (each the mean of its sub-rays), stratified bin midpoints and evenly spaced
    inverse-CDF quantiles; the fine network's rendering, in W/(m²·sr·cm⁻¹), shape
    ``scene.data_shape``. The sample placement depends on the coarse weights but is not
    differentiated (as in training), so derivatives with respect to the coarse weights are 0.
    """

    def __init__(self, representation: NeuralFieldRepresentation):
        rep = representation
        super().__init__((rep.n_parameters,), rep.scene.data_shape, dtype=rep.scene.dtype,
                         name="NeuralRendering")
        self.rep = rep

    def _fine_inputs(self, theta):
        """Per pixel batch: (fine sample points, lengths), from the coarse network, no
        gradient."""
        rep, renderer = self.rep, self.rep.renderer
        theta_c, _ = rep.split(torch.as_tensor(theta, dtype=renderer.dtype))
        offsets, quantiles = renderer.deterministic_draws()
        for pixels in renderer.batches():
            rays = renderer.sub_rays(pixels)
            with torch.no_grad():
                *_, t_fine, lengths = renderer.samples(
                    rays, partial(rep.coarse.evaluate, theta_c), offsets, quantiles)
            yield renderer.points(rays, t_fine), lengths

    def _forward(self, x):
        rep = self.rep
        theta_f = rep.split(torch.as_tensor(x, dtype=rep.renderer.dtype))[1]
        with torch.no_grad():
            out = [rep.renderer.measure(rep.fine.evaluate(theta_f, p), s)
                   for p, s in self._fine_inputs(x)]
        return to_numpy(rep.renderer.unpad(out))

    def _jvp(self, x, v):
        rep, renderer = self.rep, self.rep.renderer
        theta_f = rep.split(torch.as_tensor(x, dtype=renderer.dtype))[1]
        v_f = rep.split(torch.as_tensor(v, dtype=renderer.dtype))[1]
        out = []
        for p, s in self._fine_inputs(x):
            fields, d_fields = torch.func.jvp(lambda t, p=p: rep.fine.evaluate(t, p),
                                              (theta_f,), (v_f,))
            out.append(renderer.measure_jvp(fields, s, d_fields))
        return to_numpy(renderer.unpad(out))

    def _vjp(self, x, w):
        rep, renderer = self.rep, self.rep.renderer
        theta = torch.tensor(x, dtype=renderer.dtype, requires_grad=True)
        w = torch.as_tensor(w, dtype=renderer.dtype)
        pad = -renderer.n_rays % renderer.batch_rays
        w = torch.cat([w, torch.zeros((pad, w.shape[1]), dtype=w.dtype)])
        for (p, s), w_batch in zip(self._fine_inputs(x), w.split(renderer.batch_rays),
                                   strict=True):
            fields = rep.fine.evaluate(rep.split(theta)[1], p)
            torch.sum(renderer.measure(fields, s) * w_batch).backward()
        return to_numpy(theta.grad)


class StochasticObjective:
    """The training objective, ``(theta, iteration, rng) -> (loss, grad)`` (see the module
    docstring): a pixel batch of the iteration's epoch, sample jitter and voxel centres from
    ``rng``.

    Parameters
    ----------
    representation : NeuralFieldRepresentation
    data : array_like, shape ``scene.data_shape``
        Measured spectra in W/(m²·sr·cm⁻¹).
    sigma : float, array_like or None
        Noise standard deviation (W/(m²·sr·cm⁻¹)), see
        :func:`~invflame.representations.whitening.noise_weights`; None means 1.
    regularizer : {"none", "tikhonov", "tv"}
    lam : float
        Weight λ of the regularizer.
    """

    def __init__(self, representation: NeuralFieldRepresentation, data, sigma,
                 regularizer: str, lam: float):
        rep = self.rep = representation
        dtype = rep.renderer.dtype
        shape = rep.scene.data_shape
        data = np.asarray(data)
        if data.size != int(np.prod(shape)):
            raise ValueError(f"data has shape {data.shape}; the scene measures {shape} "
                             "(pixels, output wavenumbers)")
        weights = noise_weights(1.0 if sigma is None else sigma, shape)
        self.target = torch.tensor(data.reshape(shape) * weights, dtype=dtype)
        self.weights = torch.tensor(weights, dtype=dtype)
        self.lam = float(lam)
        self.centre_regularizer = (CentreRegularizer(regularizer, rep.grid, dtype)
                                   if regularizer != "none" and self.lam > 0 else None)

    def loss(self, theta: torch.Tensor, pixels: torch.Tensor, offsets: torch.Tensor,
             quantiles: torch.Tensor, centres: torch.Tensor | None) -> torch.Tensor:
        """The loss of one batch, differentiable in ``theta``.

        Parameters
        ----------
        theta : torch.Tensor, shape (n_parameters,)
            Coarse then fine weights.
        pixels : torch.Tensor of int, shape (batch_rays,)
            Pixel indices.
        offsets, quantiles : torch.Tensor
            Per sub-ray draws, see :meth:`NeuralRenderer.samples`.
        centres : torch.Tensor of int, shape (M,), or None
            Distinct flat voxel indices for the regularizer estimate (ignored without one).

        Returns
        -------
        torch.Tensor, scalar (dimensionless: residuals are in units of σ)
        """
        rep, renderer = self.rep, self.rep.renderer
        theta_c, theta_f = rep.split(theta)
        coarse, fine = renderer.render(pixels, partial(rep.coarse.evaluate, theta_c),
                                       partial(rep.fine.evaluate, theta_f), offsets, quantiles)
        weights, target = self.weights[pixels], self.target[pixels]
        misfit = (torch.sum((coarse * weights - target) ** 2)
                  + torch.sum((fine * weights - target) ** 2))
        loss = renderer.n_rays / (2 * pixels.numel()) * misfit
        if self.centre_regularizer is not None:
            u = partial(rep.fine.evaluate, theta_f, normalized=True)
            loss = loss + self.lam * self.centre_regularizer(u, centres)
        return loss

    def __call__(self, theta, iteration: int, rng: np.random.Generator):
        rep, renderer = self.rep, self.rep.renderer
        theta = torch.tensor(np.asarray(theta).ravel(), dtype=renderer.dtype,
                             requires_grad=True)
        epoch, position = divmod(int(iteration), rep.iterations_per_epoch)
        pixels = torch.as_tensor(rep.epoch_batches(epoch)[position])
        offsets, quantiles = renderer.random_draws(rng)
        centres = None
        if self.centre_regularizer is not None:
            centres = torch.as_tensor(rng.choice(self.centre_regularizer.n_centres,
                                                 rep.batch_centres, replace=False))
        loss = self.loss(theta, pixels, offsets, quantiles, centres)
        loss.backward()
        return loss.item(), to_numpy(theta.grad)


class NeuralFieldRepresentation:
    """Coarse and fine neural fields rendered along the rays: the paper's NN representation.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Grid (the networks' box; its voxel centres serve regularization and output), pixels
        and their sub-rays, spectroscopy and instrument; its dtype is the networks' dtype.
    n_coarse, n_fine : int, optional
        Samples per sub-ray (defaults 64 and 64), see :class:`NeuralRenderer`.
    batch_rays : int, optional
        Pixels (measured rays) per training iteration and per rendering call, each rendered
        with all its sub-rays (default 1024).
    batch_centres : int, optional
        Voxel centres per iteration for the regularizer estimate (default 4096).
    n_frequencies, hidden, depth : int, optional
        Network shape, see :class:`FieldNetwork` (defaults 10, 64, 4).
    seed : int, optional
        Seed of the weight initialization (coarse ``seed``, fine ``seed + 1``) and of the
        pixel order of every epoch.
    opacity : PlanckMeanOpacity, optional
        See :class:`NeuralRenderer`.
    """

    kind = "neural-field"

    def __init__(self, scene, n_coarse: int = 64, n_fine: int = 64, batch_rays: int = 1024,
                 batch_centres: int = 4096, n_frequencies: int = 10, hidden: int = 64,
                 depth: int = 4, seed: int = 0, opacity: PlanckMeanOpacity | None = None):
        if batch_centres < 1:
            raise ValueError(f"batch_centres must be >= 1; got {batch_centres}")
        self.scene = scene
        self.grid = scene.grid
        self.seed = int(seed)
        self.renderer = NeuralRenderer(scene, n_coarse, n_fine, batch_rays, opacity)
        network = partial(FieldNetwork, scene.grid, n_frequencies, hidden, depth,
                          tuple(scene.table.temperatures[[0, -1]]), dtype=self.renderer.dtype)
        self.coarse, self.fine = network(seed=seed), network(seed=seed + 1)
        self.n_parameters = self.coarse.n_parameters + self.fine.n_parameters
        self.centres = centre_points(scene.grid, self.renderer.dtype)
        self.batch_centres = min(int(batch_centres), self.grid.n_voxels)

    @property
    def iterations_per_epoch(self) -> int:
        """Solver iterations per epoch (one pass over all pixels): ``ceil(n_pixels /
        batch_rays)``."""
        return -(-self.renderer.n_rays // self.renderer.batch_rays)

    def epoch_batches(self, epoch: int) -> np.ndarray:
        """Pixel batches of an epoch, shape ``(iterations_per_epoch, batch_rays)``.

        A permutation of all pixels from ``default_rng([seed, epoch])``, cut into batches;
        the last batch is filled up with the permutation's first pixels (so no batch repeats
        a pixel, and each is a uniformly random set of pixels).
        """
        n, size = self.renderer.n_rays, self.renderer.batch_rays
        order = np.random.default_rng([self.seed, int(epoch)]).permutation(n)
        order = np.concatenate([order, order[:self.iterations_per_epoch * size - n]])
        return order.reshape(self.iterations_per_epoch, size)

    def split(self, theta: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Coarse and fine weights of a flat parameter tensor (views)."""
        if theta.shape != (self.n_parameters,):
            raise ValueError(f"parameters must have shape ({self.n_parameters},) (coarse then "
                             f"fine weights); got {tuple(theta.shape)}")
        return theta[:self.coarse.n_parameters], theta[self.coarse.n_parameters:]

    def initial_parameters(self, fields=None, iterations: int = 1000, lr: float = 1e-3,
                           seed: int = 0, progress: bool = True) -> np.ndarray:
        """Starting weights: both networks pretrained on ``fields`` (or as initialized).

        Parameters
        ----------
        fields : Field or ndarray, shape (4, nx, ny, nz), optional
            Voxel fields on the scene's grid (T in K, mole fractions), e.g. the noisy initial
            field of the voxel run; None keeps the networks' current weights.
        iterations, lr, seed, progress
            Passed to :func:`~invflame.representations.neural_field.pretrain`.

        Returns
        -------
        ndarray, shape (n_parameters,)
        """
        if fields is not None:
            for network in (self.coarse, self.fine):
                pretrain(network, fields, iterations, lr, seed, progress=progress)
        return np.concatenate([self.coarse.parameter_vector(), self.fine.parameter_vector()])

    # -- the problem ----------------------------------------------------------------------
    def regularizer(self, kind: str) -> solvers.Regularizer | None:
        """:math:`\\Phi` over all voxel centres (the voxel regularizer of :meth:`fields`,
        normalized) for ``kind`` in {"none", "tikhonov", "tv"}; None for "none"."""
        shape = (4, *self.grid.shape)
        normalized = TorchOperator(
            lambda theta: self.fine.evaluate(self.split(theta)[1], self.centres, normalized=True),
            (self.n_parameters,), shape, dtype=self.scene.dtype, name="NormalizedFineAtCentres")
        return regularizer_after(kind, self.grid, normalized)

    def problem(self, data, regularizer: str = "none", lam: float = 1e-3, x0=None,
                sigma=None, stochastic: bool = True) -> solvers.Problem:
        """The inverse problem on network weights (kind ``"neural-field"``).

        Parameters
        ----------
        data : ndarray, shape (n_rays, n_out)
            Measured pixel spectra in W/(m²·sr·cm⁻¹).
        regularizer : {"none", "tikhonov", "tv"}
            Regularizer of the fine network's normalized fields (see the module docstring).
        lam : float
            Weight λ (default 1e-3), on the scale of the noise-weighted sum of squares.
        x0 : ndarray, optional
            Starting weights, e.g. from :meth:`initial_parameters`.
        sigma : float or array_like, optional
            Noise standard deviation in W/(m²·sr·cm⁻¹), a scalar or broadcastable to
            ``(n_rays, n_out)`` (e.g. per output wavenumber); None means 1.
        stochastic : bool, optional
            Attach the stochastic :class:`StochasticObjective` (default; one solver iteration
            is one pixel batch, :attr:`iterations_per_epoch` of them one epoch). Without it,
            solvers see the deterministic objective (fine rendering of all pixels, regularizer
            over all voxel centres), which quasi-Newton solvers need; much slower per
            iteration.

        Returns
        -------
        solvers.Problem
            With the deterministic :class:`NeuralRendering` divided by σ as forward operator
            and data divided by σ.
        """
        forward, weighted = whitened(NeuralRendering(self), data, sigma)
        renderer = self.renderer
        return solvers.Problem(
            forward, weighted, regularizer=self.regularizer(regularizer), lam=lam, x0=x0,
            kind=self.kind, name=f"neural-field/{regularizer}",
            metadata={"representation": self.kind, "regularizer": regularizer, "lambda": lam,
                      "noise_weighted": sigma is not None, "n_coarse": renderer.n_coarse,
                      "n_fine": renderer.n_fine, "batch_rays": renderer.batch_rays,
                      "rays_per_pixel": renderer.rays_per_pixel,
                      "iterations_per_epoch": self.iterations_per_epoch,
                      "batch_centres": self.batch_centres, "stochastic": stochastic},
            value_and_grad=(StochasticObjective(self, data, sigma, regularizer, lam)
                            if stochastic else None),
        )

    # -- results --------------------------------------------------------------------------
    def fields(self, theta) -> np.ndarray:
        """Physical fields ``(4, nx, ny, nz)`` (T in K, mole fractions) of the fine network at
        the voxel centres (one evaluation, no gradient)."""
        theta_f = self.split(torch.as_tensor(np.asarray(theta), dtype=self.renderer.dtype))[1]
        with torch.no_grad():
            return to_numpy(self.fine.evaluate(theta_f, self.centres))

    @staticmethod
    def parameter_bytes(theta) -> int:
        """Memory of the parameters (both networks' weights) in bytes."""
        return int(np.asarray(theta).nbytes)
