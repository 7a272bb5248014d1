r"""The neural field: temperature and mole fractions as an MLP of encoded position.

Following the NeRF-like representation of Tricard, Chen & Deng (2026),

.. math::

    [T, X_\mathrm{CO_2}, X_\mathrm{H_2O}, X_\mathrm{CH_4}](x) = f_\theta(\gamma(p)),
    \qquad p = 2\,\frac{x - x_\mathrm{lower}}{x_\mathrm{upper} - x_\mathrm{lower}} - 1
    \in [-1, 1]^3,

    \gamma(p) = \big(p,\ \sin(2^k \pi p),\ \cos(2^k \pi p)\big)_{k = 0}^{L-1},

with :math:`L = 10` frequencies (a 63-dimensional encoding; with ``grid_levels`` a learned
multi-resolution feature grid joins it, :mod:`~invflame.representations.neural.feature_grid`),
4 hidden layers of 64 units with ReLU, and output activations that keep the fields in range:
:math:`T = T_\min + (T_\max - T_\min)\,\mathrm{sigmoid}(z_0)` (the absorption table's range,
250–2500 K by default) and :math:`X_s = \mathrm{sigmoid}(z_s)`. The last layer's biases start
at the values giving :math:`T = 300` K and :math:`X_s = 0.02` (close to ambient air).

With a state relation (:mod:`invflame.representations.state_relation`) the network has two
outputs instead, the progress :math:`s = s_\max\,\mathrm{sigmoid}(z_0)` and the temperature
factor :math:`h = h_\min + (h_\max - h_\min)\,\mathrm{sigmoid}(z_1)`, and the fields are the
relation's states: no temperature without products, so the network cannot heat transparent
air. Its biases start at :math:`s = 10^{-3}` and :math:`h = 1` (within its bounds).

The network can be evaluated with its own parameters (``network(points)``) or with any flat
parameter vector (:meth:`FieldNetwork.evaluate`, through :func:`torch.func.functional_call`),
which is how the representations differentiate with respect to the weights.
:func:`pretrain` fits a network to a voxel field (the paper's initialization);
:meth:`FieldNetwork.offset_by` starts it at a voxel field exactly instead: the network's output
is added to the field's own pre-activations, interpolated between the voxel centres, and its
last layer starts at zero, so the network learns the correction to the field.
"""

from __future__ import annotations

import numpy as np
import torch

from invflame.geometry import VoxelGrid
from invflame.representations.neural.feature_grid import FeatureGrid, interpolate
from invflame.representations.normalization import SCALES
from invflame.representations.state_relation import StateRelation
from operators.interop import TORCH_DTYPES
from solvers.progress import progress_bar

POINTS_PER_PASS = 2**14
"""Points per pass of the MLP: a pass's activations (64 units × 4 bytes per point in float32,
4 MiB per layer) stay in the processor's cache. At the 216 000 centres of a 60³ grid on two
cores, in passes of 2¹⁴ against one pass, the forward took 0.064–0.066 against 0.199–0.202 s,
the forward-mode product 0.19–0.20 against 0.65–0.72 s and the pullback 0.13–0.19 against
0.27–0.31 s; passes of 2¹² and 2¹³ points were as fast within the scatter of two runs, of 2¹¹
and 2¹⁶ slower (``python benchmarks/bench_network.py``)."""

OFFSET_MARGIN = 1e-3
"""Least share of its range an output takes in :meth:`FieldNetwork.preactivations`
(dimensionless): the progress of ambient air becomes 1e-3 of its bound, as an untrained
network's."""

AMBIENT_START = (300.0, 0.02, 0.02, 0.02)
"""Fields (T in K, mole fractions) of an untrained network: the last layer's bias values."""


def _logit(p: float) -> float:
    return float(np.log(p / (1.0 - p)))


class FieldNetwork(torch.nn.Module):
    r"""MLP from position (m) to physical fields ``(T [K], X_CO2, X_H2O, X_CH4)``.

    Parameters
    ----------
    grid : VoxelGrid
        Its box (m) maps to :math:`[-1, 1]^3` before the encoding.
    n_frequencies : int, optional
        Frequencies :math:`L` of the sinusoidal encoding (default 10).
    grid_levels : int, optional
        Levels of a learned feature grid whose features join the encoding
        (:class:`~invflame.representations.neural.feature_grid.FeatureGrid`, two features per
        node and level, the finest level at the grid's resolution); 0 (default): none, the
        paper's network.
    hidden : int, optional
        Units per hidden layer (default 64).
    depth : int, optional
        Number of hidden layers (default 4).
    temperature_range : tuple of float, optional
        :math:`(T_\min, T_\max)` in K of the output (default 250–2500 K).
    seed : int, optional
        Seed of the weight initialization (default 0).
    dtype : torch.dtype, optional
        float32 (default) or float64.
    state_relation : StateRelation, optional
        Output the progress and temperature factor of this relation and return its states
        (see the module docstring); None (default): the four fields directly.
    """

    n_fields = 4

    def __init__(self, grid: VoxelGrid, n_frequencies: int = 10, hidden: int = 64,
                 depth: int = 4, temperature_range=(250.0, 2500.0), seed: int = 0,
                 dtype=torch.float32, state_relation: StateRelation | None = None,
                 grid_levels: int = 0):
        super().__init__()
        t_min, t_max = (float(t) for t in temperature_range)
        if not 0 < t_min < AMBIENT_START[0] < t_max:
            raise ValueError(f"temperature_range must satisfy 0 < T_min < {AMBIENT_START[0]} K"
                             f" < T_max; got {temperature_range}")
        if n_frequencies < 0 or hidden < 1 or depth < 1 or grid_levels < 0:
            raise ValueError(f"need n_frequencies >= 0, hidden >= 1, depth >= 1, grid_levels "
                             f">= 0; got {n_frequencies}, {hidden}, {depth}, {grid_levels}")
        self.grid = grid
        self.n_frequencies = int(n_frequencies)
        self.temperature_range = (t_min, t_max)
        self.state_relation = state_relation
        generator = torch.Generator().manual_seed(int(seed))
        self.features = (FeatureGrid(grid.shape, grid_levels, generator, dtype)
                         if grid_levels else None)
        n_features = 0 if self.features is None else self.features.n_outputs
        widths = [3 * (1 + 2 * self.n_frequencies) + n_features] + [int(hidden)] * int(depth)
        layers = []
        for n_in, n_out in zip(widths[:-1], widths[1:], strict=True):
            layers += [_linear(n_in, n_out, generator, dtype), torch.nn.ReLU()]
        if state_relation is None:
            start = [(AMBIENT_START[0] - t_min) / (t_max - t_min), *AMBIENT_START[1:]]
        else:
            low, high = state_relation.factor_range
            start = [1e-3 / state_relation.progress_max,
                     min(max((1.0 - low) / (high - low), 0.01), 0.99) if high > low else 0.5]
        last = _linear(widths[-1], len(start), generator, dtype)
        with torch.no_grad():
            last.weight.mul_(0.1)
            last.bias.copy_(torch.tensor([_logit(p) for p in start], dtype=dtype))
        self.mlp = torch.nn.Sequential(*layers, last)
        self.register_buffer("lower", torch.tensor(grid.lower, dtype=dtype))
        self.register_buffer("extent", torch.tensor(grid.extent, dtype=dtype))
        self.register_buffer("frequencies", torch.pi * 2.0 ** torch.arange(
            self.n_frequencies, dtype=dtype))
        self.register_buffer("scales", torch.as_tensor(SCALES, dtype=dtype))
        self.register_buffer("offset", None)

    @classmethod
    def for_scene(cls, scene, n_frequencies: int = 10, hidden: int = 64, depth: int = 4,
                  seed: int = 0, state_relation: StateRelation | None = None,
                  grid_levels: int = 0) -> FieldNetwork:
        """A network on a scene's grid, with its absorption table's temperature range (K) and
        its dtype (float32 or float64); the other parameters as for :class:`FieldNetwork`."""
        return cls(scene.grid, n_frequencies, hidden, depth,
                   tuple(scene.table.temperatures[[0, -1]]), seed=seed,
                   dtype=TORCH_DTYPES[np.dtype(scene.dtype)], state_relation=state_relation,
                   grid_levels=grid_levels)

    # -- the map ------------------------------------------------------------------------------
    def unit(self, points: torch.Tensor) -> torch.Tensor:
        """Points ``(..., 3)`` in m mapped to the box :math:`[-1, 1]^3` (dimensionless)."""
        return 2.0 * (points - self.lower) / self.extent - 1.0

    def encode(self, points: torch.Tensor) -> torch.Tensor:
        r""":math:`\gamma(p)` of points ``(N, 3)`` in m, then the feature grid's encoding if
        the network has one: shape ``(N, 3 (1 + 2 L) + levels × features)``."""
        p = self.unit(points)
        angles = (p[..., None, :] * self.frequencies[:, None]).flatten(-2)
        parts = [p, torch.sin(angles), torch.cos(angles)]
        if self.features is not None:
            parts.append(self.features(p))
        return torch.cat(parts, dim=-1)

    def forward(self, points: torch.Tensor, relation_parameters: bool = False) -> torch.Tensor:
        """Physical fields at points ``(..., 3)`` in m: shape ``(4, ...)``, T in K; with
        ``relation_parameters`` the state relation's progress and factor, shape ``(2, ...)``.

        The MLP runs on :data:`POINTS_PER_PASS` points at a time (the same values as all at
        once: the map is pointwise).
        """
        flat = points.reshape(-1, points.shape[-1])
        z = torch.cat([self.mlp(self.encode(part)) for part in torch.split(flat, POINTS_PER_PASS)])
        if self.offset is not None:
            z = z + self._offset_at(flat)
        z = torch.movedim(z.reshape(*points.shape[:-1], z.shape[-1]), -1, 0)
        if self.state_relation is not None:
            relation = self.state_relation
            low, high = relation.factor_range
            s_h = (relation.progress_max * torch.sigmoid(z[0]),
                   low + (high - low) * torch.sigmoid(z[1]))
            return torch.stack(s_h if relation_parameters else relation.states(*s_h))
        t_min, t_max = self.temperature_range
        temperature = t_min + (t_max - t_min) * torch.sigmoid(z[:1])
        return torch.cat([temperature, torch.sigmoid(z[1:])])

    def preactivations(self, fields) -> np.ndarray:
        r"""The state relation's output pre-activations :math:`z` whose states are nearest to
        ``fields``.

        Parameters
        ----------
        fields : array_like, shape (4, ...)
            T in K and mole fractions of CO2, H2O, CH4.

        Returns
        -------
        ndarray, shape (2, ...)
            The logits of the progress and factor of :meth:`StateRelation.invert`, each as a
            share of its range, the shares clipped to [:data:`OFFSET_MARGIN`, 1 −
            :data:`OFFSET_MARGIN`] (ambient air, progress 0, sits where the sigmoid still has
            slope).

        Raises
        ------
        ValueError
            For a network without a state relation (its mole fractions span decades a logit
            margin would distort).
        """
        relation = self.state_relation
        if relation is None:
            raise ValueError("a network starts offset by fields only with a state relation "
                             "(representation.parameters = 'state-relation'); pretrain one "
                             "that outputs the four fields")
        s, h = relation.invert(np.asarray(fields, dtype=np.float64))
        low, high = relation.factor_range
        shares = np.stack([s / relation.progress_max,
                           (h - low) / (high - low) if high > low else np.full_like(h, 0.5)])
        shares = np.clip(shares, OFFSET_MARGIN, 1.0 - OFFSET_MARGIN)
        return np.log(shares / (1.0 - shares))

    def offset_by(self, fields) -> None:
        """Start the network at voxel fields: its output adds to their pre-activations.

        The pre-activations of ``fields`` (:meth:`preactivations`) become a buffer that the
        network's output is added to, interpolated trilinearly between the voxel centres
        (constant beyond the outermost centres), and the last layer's weights and biases are
        set to zero: at the voxel centres the network then gives ``fields`` (up to the
        clipping of :meth:`preactivations`) and its weights learn the correction.

        Parameters
        ----------
        fields : Field or array_like, shape (4, nx, ny, nz)
            Fields on the network's grid (T in K, mole fractions).

        Raises
        ------
        ValueError
            For fields on another grid, or a network without a state relation.
        """
        values = np.asarray(getattr(fields, "values", fields))
        if values.shape != (4, *self.grid.shape):
            raise ValueError(f"fields must have shape {(4, *self.grid.shape)} (on the network's "
                             f"grid); got {values.shape}")
        self.offset = torch.as_tensor(self.preactivations(values)[None],
                                      dtype=self.lower.dtype, device=self.lower.device)
        with torch.no_grad():
            self.mlp[-1].weight.zero_()
            self.mlp[-1].bias.zero_()

    def _offset_at(self, points: torch.Tensor) -> torch.Tensor:
        """The offset buffer at points ``(N, 3)`` in m, trilinear: shape ``(N, n_outputs)``."""
        return interpolate(self.offset, self.unit(points))

    def normalized(self, points: torch.Tensor) -> torch.Tensor:
        """Normalized fields :math:`u = f / s` at points ``(..., 3)``: shape ``(4, ...)``."""
        return self._normalize(self(points))

    def _normalize(self, fields: torch.Tensor) -> torch.Tensor:
        return fields / self.scales.reshape((4,) + (1,) * (fields.ndim - 1))

    # -- flat parameter vectors ---------------------------------------------------------------
    @property
    def n_parameters(self) -> int:
        """Number of trainable weights."""
        return sum(p.numel() for p in self.parameters())

    def parameter_vector(self) -> np.ndarray:
        """The current weights as a flat NumPy vector (in ``named_parameters`` order)."""
        return torch.nn.utils.parameters_to_vector(self.parameters()).detach().cpu().numpy()

    def load_vector(self, theta) -> None:
        """Copy a flat weight vector (shape ``(n_parameters,)``) into the module."""
        theta = self._check(torch.as_tensor(np.asarray(theta)))
        with torch.no_grad():
            torch.nn.utils.vector_to_parameters(theta.to(self.lower.dtype), self.parameters())

    def unflatten(self, theta: torch.Tensor) -> dict[str, torch.Tensor]:
        """Views of a flat weight tensor, by parameter name (for ``functional_call``)."""
        theta = self._check(theta)
        out, offset = {}, 0
        for name, p in self.named_parameters():
            out[name] = theta[offset:offset + p.numel()].view_as(p)
            offset += p.numel()
        return out

    def evaluate(self, theta: torch.Tensor, points: torch.Tensor, normalized: bool = False,
                 relation_parameters: bool = False) -> torch.Tensor:
        """Fields at ``points`` (m) with the weights ``theta`` (differentiable in both).

        Parameters
        ----------
        theta : torch.Tensor, shape (n_parameters,)
            Flat weights.
        points : torch.Tensor, shape (..., 3)
            Positions in m.
        normalized : bool, optional
            Return normalized fields :math:`u = f/s` instead of physical ones.
        relation_parameters : bool, optional
            Return the state relation's progress and factor, shape ``(2, ...)``.

        Returns
        -------
        torch.Tensor, shape (4, ...) (or (2, ...))
        """
        if relation_parameters and (normalized or self.state_relation is None):
            raise ValueError("relation_parameters needs a network with a state relation, "
                             "and gives them unnormalized")
        out = torch.func.functional_call(self, self.unflatten(theta), (points,),
                                         {"relation_parameters": relation_parameters})
        return self._normalize(out) if normalized else out

    def _check(self, theta: torch.Tensor) -> torch.Tensor:
        if theta.shape != (self.n_parameters,):
            raise ValueError(f"weight vector must have shape ({self.n_parameters},) for this "
                             f"network; got {tuple(theta.shape)}")
        return theta


def _linear(n_in: int, n_out: int, generator: torch.Generator, dtype) -> torch.nn.Linear:
    """A linear layer with PyTorch's default (Kaiming-uniform) initialization, seeded.

    The layer is made on torch's default device; its weights are drawn on the CPU by
    ``generator`` (a CPU generator), so that a seed gives the same network on every device.
    """
    layer = torch.nn.Linear(n_in, n_out, dtype=dtype)
    bound = 1.0 / np.sqrt(n_in)
    with torch.no_grad():
        for p in (layer.weight, layer.bias):
            p.copy_(torch.empty(p.shape, dtype=dtype, device="cpu").uniform_(
                -bound, bound, generator=generator))
    return layer


def centre_points(grid: VoxelGrid, dtype=torch.float32) -> torch.Tensor:
    """Voxel centres of ``grid`` in m as a tensor ``(nx, ny, nz, 3)``."""
    return torch.as_tensor(grid.centres(), dtype=dtype)


def pretrain(network: FieldNetwork, target, iterations: int = 2000, lr: float = 1e-3,
             seed: int = 0, batch_size: int = 2048, progress: bool = True) -> np.ndarray:
    """Fit a network to a voxel field at the voxel centres (the paper's initialization).

    Minimizes the mean squared error of the normalized fields over random batches of voxel
    centres with Adam, updating ``network`` in place.

    Parameters
    ----------
    network : FieldNetwork
        Network to fit; its grid defines the voxel centres.
    target : Field or ndarray, shape (4, nx, ny, nz)
        Fields on ``network.grid`` (T in K, mole fractions), e.g. the noisy initial field of
        the voxel run.
    iterations : int, optional
        Adam steps (default 2000).
    lr : float, optional
        Adam learning rate (default 1e-3).
    seed : int, optional
        Seed of the batch sampling.
    batch_size : int, optional
        Voxel centres per step (all of them when the grid is smaller).
    progress : bool, optional
        Show a tqdm progress bar.

    Returns
    -------
    ndarray, shape (iterations,)
        The batch loss (mean squared error of normalized fields) of every step.
    """
    values = np.asarray(getattr(target, "values", target))
    expected = (4, *network.grid.shape)
    if values.shape != expected:
        raise ValueError(f"target must have shape {expected} (fields on the network's grid); "
                         f"got {values.shape}")
    if iterations < 1 or not lr > 0:
        raise ValueError(f"need iterations >= 1 and lr > 0; got {iterations}, {lr}")
    dtype = network.lower.dtype
    points = centre_points(network.grid, dtype).reshape(-1, 3)
    u_target = torch.as_tensor(values.reshape(4, -1) / SCALES[:, None], dtype=dtype)
    generator = torch.Generator().manual_seed(int(seed))
    batch = min(int(batch_size), points.shape[0])
    optimizer = torch.optim.Adam(network.parameters(), lr=lr)
    losses = np.empty(int(iterations))
    for k in progress_bar(range(int(iterations)), disable=not progress,
                          desc="pretrain neural field"):
        index = torch.randperm(points.shape[0], generator=generator,
                               device="cpu")[:batch].to(points.device)
        optimizer.zero_grad()
        loss = torch.mean((network.normalized(points[index]) - u_target[:, index]) ** 2)
        loss.backward()
        optimizer.step()
        losses[k] = loss.item()
    return losses

