r"""The NeRF-like representation: two neural fields rendered along the measurement rays.

The unknowns are the weights :math:`\theta = (\theta_c, \theta_f)` of a *coarse* and a *fine*
:class:`~invflame.representations.neural_field.FieldNetwork`. A ray batch is rendered as in
NeRF (Mildenhall et al. 2020), with the emission physics of the voxel path:

1. ``n_coarse`` stratified samples on each ray's chord through the domain box
   (:mod:`~invflame.representations.neural_sampling`), fields from the coarse network;
2. ``n_fine`` more samples drawn by inverse CDF from the coarse samples' emission weights
   (opacity from the Planck-mean absorption coefficient), merged with the coarse ones and
   sorted; fields from the fine network;
3. each set of samples is a piecewise-homogeneous ray (sample lengths sum to the chord),
   rendered by the JAX emission kernel :func:`operators.emission_rte.emission_radiance`
   through :func:`operators.torch_bridge.torch_function` (its backward pass is the kernel's
   VJP), then convolved with the instrument lineshape (the scene's ILS matrix).

The training loss of a batch of :math:`B` of the :math:`N` rays is

.. math:: \frac{N}{B} \sum_{r \in \text{batch}} \big(\|g^c_r - d_r\|^2 + \|g^f_r - d_r\|^2\big)
          + \lambda\,\hat\Phi(\theta_f),

both renderings entering the data term (NeRF style), and :math:`\hat\Phi` the regularizer of
the fine network's normalized fields :math:`u = f/s` estimated on a random batch of voxel
centres: Tikhonov :math:`\sum_d \mathrm{mean}((\partial u/\partial x_d)^2)` or TV
:math:`\sum_d \mathrm{mean}(|\partial u/\partial x_d|)`, with the spatial derivatives (1/m)
of the network from automatic differentiation (no voxel grid is materialized). The same
scaling as :func:`operators.tikhonov` / :func:`operators.total_variation` makes λ mean the
same as for voxels.

For evaluation, the problem's forward operator renders all rays deterministically (stratified
bin midpoints, evenly spaced quantiles) with the fine network: :math:`F(\theta) = g^f`.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import torch

import solvers
from invflame.representations.neural_field import FieldNetwork, centre_points, pretrain
from invflame.representations.neural_sampling import (
    PlanckMeanOpacity,
    emission_weights,
    importance,
    sample_bounds,
    sample_lengths,
    stratified,
)
from invflame.representations.voxel import REGULARIZERS
from operators import L1, Operator, SquaredL2, TorchOperator
from operators.emission_rte import batch_rays_for, emission_radiance, emission_radiance_jvp
from operators.interop import to_jax, to_numpy, to_torch
from operators.torch_bridge import torch_function

TORCH_DTYPES = {np.dtype(np.float32): torch.float32, np.dtype(np.float64): torch.float64}


class NeuralRenderer:
    """Coarse-to-fine rendering of measured spectra from field functions along a scene's rays.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Rays (clipped to its grid's box), emission tables, ILS matrix and dtype.
    n_coarse, n_fine : int, optional
        Stratified and importance samples per ray (defaults 64 and 64).
    batch_rays : int, optional
        Rays per rendering call (fixed, so the kernel compiles once); at most the scene's
        number of rays.
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
        self.batch_rays = min(int(batch_rays), scene.n_rays)
        self.dtype = TORCH_DTYPES[np.dtype(scene.dtype)]
        seg = scene.segments
        self.origins, self.directions, self.t_near, self.t_far = (
            torch.tensor(a, dtype=self.dtype)
            for a in (seg.origins, seg.directions, seg.t_near, seg.t_far))
        self.ils = torch.tensor(scene.ils.matrix, dtype=self.dtype)
        self.opacity = PlanckMeanOpacity.from_table(scene.table) if opacity is None else opacity
        tables = scene.tables
        kernel_batch = batch_rays_for(tables, self.batch_rays, scene.memory_budget)
        radiance = jax.jit(partial(emission_radiance, batch_rays=kernel_batch))
        self._radiance = torch_function(lambda f, s: radiance(tables, f, s))
        self._radiance_jvp = jax.jit(lambda f, s, df: emission_radiance_jvp(
            tables, f, s, df, jnp.zeros_like(s), kernel_batch)[1])

    @property
    def n_rays(self) -> int:
        """Number of rays of the scene."""
        return self.t_near.shape[0]

    def batches(self) -> list[torch.Tensor]:
        """Ray indices covering all rays in order, in batches of ``batch_rays`` (the last one
        padded by repeating ray 0; :meth:`unpad` drops the padding)."""
        index = torch.arange(self.n_rays)
        n_pad = -self.n_rays % self.batch_rays
        index = torch.cat([index, torch.zeros(n_pad, dtype=index.dtype)])
        return list(index.split(self.batch_rays))

    def deterministic_draws(self) -> tuple[torch.Tensor, torch.Tensor]:
        """Offsets (bin midpoints) and evenly spaced quantiles for a batch, no jitter."""
        offsets = torch.full((self.batch_rays, self.n_coarse), 0.5, dtype=self.dtype)
        quantiles = (torch.arange(self.n_fine, dtype=self.dtype) + 0.5) / self.n_fine
        return offsets, quantiles.expand(self.batch_rays, -1)

    def random_draws(self, rng: np.random.Generator) -> tuple[torch.Tensor, torch.Tensor]:
        """Stratified offsets and quantiles for a batch, uniform in [0, 1) from ``rng``."""
        return (torch.tensor(rng.random((self.batch_rays, self.n_coarse)), dtype=self.dtype),
                torch.tensor(rng.random((self.batch_rays, self.n_fine)), dtype=self.dtype))

    def samples(self, rays: torch.Tensor, coarse, offsets, quantiles):
        """Sample distances and lengths (m) of a ray batch, and the coarse fields.

        Parameters
        ----------
        rays : torch.Tensor of int, shape (B,)
            Ray indices.
        coarse : callable
            ``points (..., 3) in m -> fields (4, ...)`` (T in K, mole fractions).
        offsets, quantiles : torch.Tensor, shapes (B, n_coarse), (B, n_fine)
            Stratified offsets and inverse-CDF quantiles in [0, 1).

        Returns
        -------
        coarse_fields : torch.Tensor, shape (4, B, n_coarse)
        coarse_lengths : torch.Tensor, shape (B, n_coarse)
        t_fine, fine_lengths : torch.Tensor, shape (B, n_coarse + n_fine)
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
        """Positions (m) ``(B, n, 3)`` at distances ``t`` ``(B, n)`` along rays."""
        return self.origins[rays, None, :] + t[..., None] * self.directions[rays, None, :]

    def measure(self, fields: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """Measured spectra ``(B, n_out)`` in W/(m²·sr·cm⁻¹) of sampled rays: the emission
        kernel (torch-differentiable in ``fields``) followed by the ILS."""
        return self._radiance(fields.contiguous(), lengths.contiguous()) @ self.ils.T

    def measure_jvp(self, fields, lengths, d_fields) -> torch.Tensor:
        """Directional derivative of :meth:`measure` along ``d_fields`` (forward mode)."""
        d_radiance = self._radiance_jvp(to_jax(fields.contiguous()), to_jax(lengths.contiguous()),
                                        to_jax(d_fields.contiguous()))
        return to_torch(d_radiance) @ self.ils.T

    def render(self, rays, coarse, fine, offsets, quantiles):
        """Coarse and fine spectra ``(B, n_out)`` (W/(m²·sr·cm⁻¹)) of a ray batch.

        ``coarse`` and ``fine`` map points ``(..., 3)`` in m to fields ``(4, ...)``; the other
        arguments are as in :meth:`samples`. Differentiable through both field functions.
        """
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

    All rays, stratified bin midpoints and evenly spaced inverse-CDF quantiles; the fine
    network's rendering. The sample placement depends on the coarse weights but is not
    differentiated (as in training), so derivatives with respect to the coarse weights are 0.
    """

    def __init__(self, representation: NeuralFieldRepresentation):
        rep = representation
        super().__init__((rep.n_parameters,), rep.scene.data_shape, dtype=rep.scene.dtype,
                         name="NeuralRendering")
        self.rep = rep

    def _fine_inputs(self, theta):
        """Per batch: (fine sample points, lengths), from the coarse network, no gradient."""
        rep, renderer = self.rep, self.rep.renderer
        theta_c, _ = rep.split(torch.as_tensor(theta, dtype=renderer.dtype))
        offsets, quantiles = renderer.deterministic_draws()
        for rays in renderer.batches():
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


class NeuralFieldRepresentation:
    """Coarse and fine neural fields rendered along the rays: the paper's NN representation.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Grid (the networks' box; its voxel centres serve regularization and output), rays,
        spectroscopy and instrument; its dtype is the networks' dtype.
    n_coarse, n_fine : int, optional
        Samples per ray (defaults 64 and 64), see :class:`NeuralRenderer`.
    batch_rays : int, optional
        Rays per training iteration and per rendering call (default 1024).
    batch_centres : int, optional
        Voxel centres per iteration for the regularizer (default 4096).
    n_frequencies, hidden, depth : int, optional
        Network shape, see :class:`FieldNetwork` (defaults 10, 64, 4).
    seed : int, optional
        Seed of the weight initialization (coarse ``seed``, fine ``seed + 1``).
    opacity : PlanckMeanOpacity, optional
        See :class:`NeuralRenderer`.
    """

    kind = "neural-field"

    def __init__(self, scene, n_coarse: int = 64, n_fine: int = 64, batch_rays: int = 1024,
                 batch_centres: int = 4096, n_frequencies: int = 10, hidden: int = 64,
                 depth: int = 4, seed: int = 0, opacity: PlanckMeanOpacity | None = None):
        self.scene = scene
        self.grid = scene.grid
        self.renderer = NeuralRenderer(scene, n_coarse, n_fine, batch_rays, opacity)
        network = partial(FieldNetwork, scene.grid, n_frequencies, hidden, depth,
                          tuple(scene.table.temperatures[[0, -1]]), dtype=self.renderer.dtype)
        self.coarse, self.fine = network(seed=seed), network(seed=seed + 1)
        self.n_parameters = self.coarse.n_parameters + self.fine.n_parameters
        self.centres = centre_points(scene.grid, self.renderer.dtype).reshape(-1, 3)
        self.batch_centres = min(int(batch_centres), self.centres.shape[0])

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
    def regularizer_terms(self, theta_f: torch.Tensor, points: torch.Tensor,
                          regularizer: str) -> torch.Tensor:
        """:math:`\\hat\\Phi`: mean of ``(∂u/∂x_d)²`` ("tikhonov") or ``|∂u/∂x_d|`` ("tv")
        over fields and ``points`` ``(M, 3)`` (m), summed over the axes d (1/m² or 1/m)."""
        grads = self.fine.spatial_gradient(theta_f, points)
        values = grads**2 if regularizer == "tikhonov" else grads.abs()
        return values.sum() / (grads.shape[1] * grads.shape[2])

    def _regularizer(self, regularizer: str):
        """Deterministic :math:`\\Phi = g \\circ K` over all voxel centres, for evaluation."""
        if regularizer == "none":
            return None
        shape = (3, 4, *self.grid.shape)
        gradient = TorchOperator(
            lambda theta: self.fine.spatial_gradient(self.split(theta)[1], self.centres)
            .reshape(shape),
            (self.n_parameters,), shape, dtype=self.scene.dtype, name="NetworkGradient")
        scale = 1.0 / (4 * self.grid.n_voxels)
        functional = SquaredL2(scale) if regularizer == "tikhonov" else L1(scale)
        return solvers.Regularizer(functional, gradient)

    def value_and_grad(self, data, regularizer: str, lam: float):
        """The stochastic training objective ``(theta, iteration, rng) -> (loss, grad)``.

        One random batch of ``batch_rays`` rays (with random stratified offsets and quantiles)
        and one of ``batch_centres`` voxel centres per call, all drawn from ``rng``.
        """
        renderer = self.renderer
        data = torch.tensor(np.asarray(data).reshape(self.scene.data_shape),
                               dtype=renderer.dtype)
        weight = renderer.n_rays / renderer.batch_rays

        def value_and_grad(theta, iteration, rng):
            theta = torch.tensor(np.asarray(theta).ravel(), dtype=renderer.dtype,
                                 requires_grad=True)
            theta_c, theta_f = self.split(theta)
            rays = torch.as_tensor(rng.choice(renderer.n_rays, renderer.batch_rays,
                                              replace=False))
            offsets, quantiles = renderer.random_draws(rng)
            coarse, fine = renderer.render(rays, partial(self.coarse.evaluate, theta_c),
                                           partial(self.fine.evaluate, theta_f),
                                           offsets, quantiles)
            target = data[rays]
            loss = weight * (torch.sum((coarse - target) ** 2)
                             + torch.sum((fine - target) ** 2))
            if regularizer != "none" and lam > 0:
                centres = self.centres[torch.as_tensor(
                    rng.choice(self.centres.shape[0], self.batch_centres, replace=False))]
                loss = loss + lam * self.regularizer_terms(theta_f, centres, regularizer)
            loss.backward()
            return loss.item(), to_numpy(theta.grad)

        return value_and_grad

    def problem(self, data, regularizer: str = "none", lam: float = 1e-3, x0=None,
                stochastic: bool = True) -> solvers.Problem:
        """The inverse problem on network weights (kind ``"neural-field"``).

        Parameters
        ----------
        data : ndarray, shape (n_rays, n_out)
            Measured spectra in W/(m²·sr·cm⁻¹).
        regularizer : {"none", "tikhonov", "tv"}
            Regularizer of the fine network's normalized fields (see the module docstring).
        lam : float
            Weight λ (default 1e-3).
        x0 : ndarray, optional
            Starting weights, e.g. from :meth:`initial_parameters`.
        stochastic : bool, optional
            Attach the stochastic :meth:`value_and_grad` (default). Without it, solvers see
            the deterministic objective (fine rendering of all rays, regularizer over all
            voxel centres), which quasi-Newton solvers need; much slower per iteration.

        Returns
        -------
        solvers.Problem
            With the deterministic :class:`NeuralRendering` as forward operator.
        """
        if regularizer not in REGULARIZERS:
            raise ValueError(f"unknown regularizer {regularizer!r}; choose one of "
                             f"{', '.join(REGULARIZERS)}")
        return solvers.Problem(
            NeuralRendering(self), data, regularizer=self._regularizer(regularizer), lam=lam,
            x0=x0, kind=self.kind, name=f"neural-field/{regularizer}",
            metadata={"representation": self.kind, "regularizer": regularizer, "lambda": lam,
                      "n_coarse": self.renderer.n_coarse, "n_fine": self.renderer.n_fine,
                      "batch_rays": self.renderer.batch_rays,
                      "batch_centres": self.batch_centres, "stochastic": stochastic},
            value_and_grad=self.value_and_grad(data, regularizer, lam) if stochastic else None,
        )

    # -- results --------------------------------------------------------------------------
    def fields(self, theta) -> np.ndarray:
        """Physical fields ``(4, nx, ny, nz)`` (T in K, mole fractions) of the fine network at
        the voxel centres."""
        theta_f = self.split(torch.as_tensor(np.asarray(theta), dtype=self.renderer.dtype))[1]
        with torch.no_grad():
            values = self.fine.evaluate(theta_f, self.centres)
        return to_numpy(values).reshape(4, *self.grid.shape)

    @staticmethod
    def parameter_bytes(theta) -> int:
        """Memory of the parameters (both networks' weights) in bytes."""
        return int(np.asarray(theta).nbytes)
