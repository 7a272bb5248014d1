r"""The NeRF-like representation: two neural fields rendered along the measurement rays.

The unknowns are the weights :math:`\theta = (\theta_c, \theta_f)` of a *coarse* and a *fine*
:class:`~invflame.representations.neural.network.FieldNetwork`. A measured spectrum belongs to a
camera pixel, the mean of the spectra of the pixel's ``scene.rays_per_pixel`` sub-rays
(rows ``p·s … p·s + s − 1`` of ``scene.segments`` for pixel ``p``). Every sub-ray is rendered
as in NeRF (Mildenhall et al. 2020), with the emission physics of the voxel path:

1. ``n_coarse`` stratified samples on the sub-ray's chord through the domain box
   (:mod:`~invflame.representations.neural.sampling`), fields from the coarse network;
2. ``n_fine`` more samples drawn by inverse CDF from the coarse samples' emission weights
   (opacity from the Planck-mean absorption coefficient), merged with the coarse ones and
   sorted; fields from the fine network;
3. each set of samples is a piecewise-homogeneous ray (sample lengths sum to the chord),
   rendered by the JAX emission kernel :func:`operators.rte.kernel.emission_radiance`
   through :func:`operators.torch_bridge.torch_function` (its backward pass is the kernel's
   VJP), the coarse and the fine set in one call, in front of the scene's background and
   with its known soot, as the voxel map renders them; the sub-ray spectra of a pixel are
   averaged, then convolved with the instrument lineshape (the scene's ILS matrix).

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
drawn from the iteration's ``rng``. The data term is a sum over pixels, so a batch is rendered
and back-propagated in chunks of ``renderer.chunk_rays`` pixels: the memory is that of one
chunk, the gradient that of the whole batch.

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

import numpy as np
import torch

import solvers
from invflame.representations.neural.network import FieldNetwork, centre_points
from invflame.representations.neural.regularizers import CentreRegularizer, regularizer_after
from invflame.representations.neural.renderer import NeuralRenderer
from invflame.representations.neural.sampling import PlanckMeanOpacity
from invflame.representations.neural.weights import NetworkWeights
from invflame.representations.state_relation import StateRelation
from invflame.representations.whitening import noise_weights, whitened
from operators import Operator, TorchOperator
from operators.interop import to_numpy


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
        """Per rendering call: (sub-rays, fine sample points, lengths), from the coarse
        network, no gradient."""
        rep, renderer = self.rep, self.rep.renderer
        theta_c, _ = rep.split(torch.as_tensor(theta, dtype=renderer.dtype))
        offsets, quantiles = renderer.deterministic_draws(renderer.chunk_rays)
        for pixels in renderer.batches():
            rays = renderer.sub_rays(pixels)
            with torch.no_grad():
                *_, t_fine, lengths = renderer.samples(
                    rays, partial(rep.coarse.evaluate, theta_c), offsets, quantiles)
            yield rays, renderer.points(rays, t_fine), lengths

    def _fine_fields(self, theta_f, points):
        """The kernel fields of the fine network at ``points``."""
        return self.rep.renderer.kernel_fields(self.rep.fine.evaluate(theta_f, points), points)

    def _forward(self, x):
        rep = self.rep
        theta_f = rep.split(torch.as_tensor(x, dtype=rep.renderer.dtype))[1]
        with torch.no_grad():
            out = [rep.renderer.measure(r, (self._fine_fields(theta_f, p), s))[0]
                   for r, p, s in self._fine_inputs(x)]
        return to_numpy(rep.renderer.unpad(out))

    def _jvp(self, x, v):
        rep, renderer = self.rep, self.rep.renderer
        theta_f = rep.split(torch.as_tensor(x, dtype=renderer.dtype))[1]
        v_f = rep.split(torch.as_tensor(v, dtype=renderer.dtype))[1]
        out = []
        for r, p, s in self._fine_inputs(x):
            fields, d_fields = torch.func.jvp(partial(self._fine_fields, points=p),
                                              (theta_f,), (v_f,))
            out.append(renderer.measure_jvp(r, fields, s, d_fields))
        return to_numpy(renderer.unpad(out))

    def _vjp(self, x, w):
        rep, renderer = self.rep, self.rep.renderer
        theta = torch.tensor(x, dtype=renderer.dtype, requires_grad=True)
        w = torch.as_tensor(w, dtype=renderer.dtype)
        pad = -renderer.n_rays % renderer.chunk_rays
        w = torch.cat([w, torch.zeros((pad, w.shape[1]), dtype=w.dtype)])
        for (r, p, s), w_part in zip(self._fine_inputs(x), w.split(renderer.chunk_rays),
                                     strict=True):
            fields = self._fine_fields(rep.split(theta)[1], p)
            torch.sum(renderer.measure(r, (fields, s))[0] * w_part).backward()
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

    def terms(self, theta: torch.Tensor, pixels: torch.Tensor, offsets: torch.Tensor,
              quantiles: torch.Tensor, centres: torch.Tensor | None):
        """The loss of one batch in parts that sum to it, each differentiable in ``theta``:
        the data term of every rendering call (:meth:`NeuralRenderer.chunks`), then the
        regularizer. A generator: a part's graph is built when it is drawn, so a caller that
        back-propagates each part before drawing the next holds one rendering call's graph.

        Parameters
        ----------
        theta : torch.Tensor, shape (n_parameters,)
            Coarse then fine weights.
        pixels : torch.Tensor of int, shape (B,)
            Pixel indices.
        offsets, quantiles : torch.Tensor
            Per sub-ray draws, see :meth:`NeuralRenderer.samples`.
        centres : torch.Tensor of int, shape (M,), or None
            Distinct flat voxel indices for the regularizer estimate (ignored without one).

        Yields
        ------
        torch.Tensor, scalar (dimensionless: residuals are in units of σ)
        """
        rep, renderer = self.rep, self.rep.renderer
        scale = renderer.n_rays / (2 * pixels.numel())
        for pixel_part, ray_part in renderer.chunks(pixels.numel()):
            theta_c, theta_f = rep.split(theta)
            part = pixels[pixel_part]
            coarse, fine = renderer.render(
                part, partial(rep.coarse.evaluate, theta_c), partial(rep.fine.evaluate, theta_f),
                offsets[ray_part], quantiles[ray_part])
            weights, target = self.weights[part], self.target[part]
            yield scale * (torch.sum((coarse * weights - target) ** 2)
                           + torch.sum((fine * weights - target) ** 2))
        if self.centre_regularizer is not None:
            u = partial(rep.fine.evaluate, rep.split(theta)[1], normalized=True)
            yield self.lam * self.centre_regularizer(u, centres)

    def loss(self, theta: torch.Tensor, pixels: torch.Tensor, offsets: torch.Tensor,
             quantiles: torch.Tensor, centres: torch.Tensor | None) -> torch.Tensor:
        """The loss of one batch (the sum of :meth:`terms`, same arguments), differentiable in
        ``theta``; dimensionless."""
        return sum(self.terms(theta, pixels, offsets, quantiles, centres))

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
        value = 0.0
        for term in self.terms(theta, pixels, offsets, quantiles, centres):
            term.backward()
            value += term.item()
        return value, to_numpy(theta.grad)


class NeuralFieldRepresentation(NetworkWeights):
    """Coarse and fine neural fields rendered along the rays: the paper's NN representation.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Grid (the networks' box; its voxel centres serve regularization and output), pixels
        and their sub-rays, spectroscopy and instrument; its dtype is the networks' dtype.
    n_coarse, n_fine : int, optional
        Samples per sub-ray (defaults 64 and 64), see :class:`NeuralRenderer`.
    batch_rays : int, optional
        Pixels (measured rays) per training iteration, each rendered with all its sub-rays
        (default 1024).
    batch_centres : int, optional
        Voxel centres per iteration for the regularizer estimate (default 4096).
    n_frequencies, hidden, depth, grid_levels : int, optional
        Network shape, see :class:`FieldNetwork` (defaults 10, 64, 4, 0).
    seed : int, optional
        Seed of the weight initialization (coarse ``seed``, fine ``seed + 1``) and of the
        pixel order of every epoch.
    opacity : PlanckMeanOpacity, optional
        See :class:`NeuralRenderer`.
    chunk_rays : int, optional
        Pixels per rendering call, see :class:`NeuralRenderer` (default from the memory of
        a call).
    state_relation : StateRelation, optional
        The networks output this relation's progress and temperature factor
        (:class:`FieldNetwork`); None (default): the four fields.
    """

    kind = "neural-field"

    def __init__(self, scene, n_coarse: int = 64, n_fine: int = 64, batch_rays: int = 1024,
                 batch_centres: int = 4096, n_frequencies: int = 10, hidden: int = 64,
                 depth: int = 4, seed: int = 0, opacity: PlanckMeanOpacity | None = None,
                 chunk_rays: int | None = None, state_relation: StateRelation | None = None,
                 grid_levels: int = 0):
        if batch_centres < 1:
            raise ValueError(f"batch_centres must be >= 1; got {batch_centres}")
        self.scene = scene
        self.grid = scene.grid
        self.seed = int(seed)
        self.renderer = NeuralRenderer(scene, n_coarse, n_fine, batch_rays, opacity, chunk_rays)
        network = partial(FieldNetwork.for_scene, scene, n_frequencies, hidden, depth,
                          state_relation=state_relation, grid_levels=grid_levels)
        self.coarse, self.fine = network(seed=seed), network(seed=seed + 1)
        self.networks = (self.coarse, self.fine)
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

    # -- the problem ----------------------------------------------------------------------
    def regularizer(self, kind: str) -> solvers.Regularizer | None:
        r""":math:`\Phi` over all voxel centres (the voxel regularizer of :meth:`fields`,
        normalized) for ``kind`` in {"none", "tikhonov", "tv"}; None for "none"."""
        shape = (4, *self.grid.shape)
        normalized = TorchOperator(
            lambda theta: self.fine.evaluate(self.split(theta)[1], self.centres, normalized=True),
            (self.n_parameters,), shape, dtype=self.scene.dtype, name="NormalizedFineAtCentres")
        return regularizer_after(kind, self.grid, normalized)

    def problem(self, data, regularizer: str = "none", lam: float = 1e-3, x0=None,
                sigma=None, stochastic: bool = True) -> solvers.Problem:
        """The inverse problem on network weights (kind ``"neural-field"``).

        ``data``, ``regularizer`` (of the fine network's normalized fields, see the module
        docstring), ``lam``, ``x0`` (network weights) and ``sigma`` are those of
        :meth:`~invflame.representations.protocol.Representation.problem`.

        Parameters
        ----------
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
            linearizable=False, advice="Use the voxel-centre network (representation "
            "'neural-centres'), whose Jacobian is a small network Jacobian times the voxel one.",
            name=f"neural-field/{regularizer}",
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
