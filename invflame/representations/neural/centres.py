r"""A cheap neural reparameterization: the network evaluated at voxel centres.

The unknowns are the weights :math:`\theta` of one
:class:`~invflame.representations.neural.network.FieldNetwork`; the fields are the network at
the voxel centres :math:`c_v`, and the data come from the scene's voxel forward map :math:`H`:

.. math:: F(\theta) = H\big(N_\theta(c)\big), \qquad
          \Phi(\theta) = g\big(D\, u_\theta(c)\big), \quad u_\theta = N_\theta / s,

with :math:`D` the forward-difference gradient (1/m) and :math:`g` the squared L2 (Tikhonov)
or L1 (TV) norm scaled as in :func:`operators.tikhonov` / :func:`operators.total_variation`,
so λ means what it means for voxels. Both maps are compositions of operators, the network part
a :class:`operators.TorchOperator`: every solver of the registry applies, Gauss–Newton and
PDHG included (their Jacobians are the voxel Jacobians times the small network Jacobian).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import solvers
from invflame.representations.curvature import group_curvature, quadratic_weight
from invflame.representations.neural.network import FieldNetwork, centre_points
from invflame.representations.neural.regularizers import regularizer_after
from invflame.representations.neural.weights import NetworkWeights
from invflame.representations.normalization import field_scales, per_field
from invflame.representations.state_relation import StateRelation
from invflame.representations.subvoxel import SubvoxelEmission
from invflame.representations.voxel import relation_fields
from invflame.representations.whitening import whitened
from operators import Diagonal, JaxOperator, Operator, TorchOperator


class NeuralCentresRepresentation(NetworkWeights):
    """Network weights as unknowns, the network sampled at the voxel centres.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Grid (the network's box and the centres), voxel forward map
        (:attr:`~invflame.scene.Scene.operator`) and dtype.
    n_frequencies, hidden, depth, grid_levels : int, optional
        Network shape, see :class:`FieldNetwork` (defaults 10, 64, 4, 0).
    seed : int, optional
        Seed of the weight initialization.
    forward : operators.Operator, optional
        Voxel forward map from physical fields ``(4, nx, ny, nz)`` to data (default the
        scene's).
    state_relation : StateRelation, optional
        The network outputs this relation's progress and temperature factor
        (:class:`FieldNetwork`); None (default): the four fields.
    subvoxel : SubvoxelEmission, optional
        Render each voxel at the emission-equivalent progress of a presumed spread about the
        network's progress at its centre (:mod:`invflame.representations.subvoxel`, as for
        voxels); the regularizer and :meth:`fields` keep the network's mean state. Needs
        ``state_relation``.
    """

    kind = "neural-centres"
    iterations_per_epoch = 1
    """Every solver iteration uses all pixels."""

    def __init__(self, scene, n_frequencies: int = 10, hidden: int = 64, depth: int = 4,
                 seed: int = 0, forward: Operator | None = None,
                 state_relation: StateRelation | None = None, grid_levels: int = 0,
                 subvoxel: SubvoxelEmission | None = None):
        if subvoxel is not None and state_relation is None:
            raise ValueError("a sub-voxel emission model renders the state relation's progress: "
                             "give state_relation too")
        self.scene = scene
        self.subvoxel = subvoxel
        self.grid = scene.grid
        self.dtype = np.dtype(scene.dtype)
        self.network = FieldNetwork.for_scene(scene, n_frequencies, hidden, depth, seed,
                                              state_relation, grid_levels)
        self.networks = (self.network,)
        self.centres = centre_points(scene.grid, self.network.lower.dtype)
        shape = (4, *self.grid.shape)

        forward = scene.operator if forward is None else forward
        if subvoxel is None:
            self.at_centres = TorchOperator(
                lambda theta: self.network.evaluate(theta, self.centres), (self.n_parameters,),
                shape, dtype=self.dtype, name="NetworkAtCentres")
            rendered = self.at_centres
        else:  # the network's (s, h) once, then its mean states and its rendered states
            self.relation_parameters = TorchOperator(
                lambda theta: self.network.evaluate(theta, self.centres, relation_parameters=True),
                (self.n_parameters,), (2, *self.grid.shape), dtype=self.dtype,
                name="NetworkAtCentres")
            self.at_centres, rendered = (JaxOperator(
                lambda s_h, model=model: relation_fields(state_relation, s_h, jnp, model),
                (2, *self.grid.shape), shape, dtype=self.dtype, name=name,
            ) @ self.relation_parameters for model, name in ((None, "state relation"),
                                                             (subvoxel, "rendered states")))
        # the regularizer after the same operator object as the data map: an evaluation runs
        # the network once (solvers.Problem.evaluate)
        self.normalized_at_centres = Diagonal(1.0 / per_field(field_scales(), shape),
                                              dtype=self.dtype, name="normalize") @ self.at_centres
        self.forward = forward @ rendered

    def regularizer(self, kind: str) -> solvers.Regularizer | None:
        r""":math:`\Phi = g \circ (D \circ u_\theta(c))` for ``kind`` in {"none", "tikhonov",
        "tv"} (None for "none"): the voxel regularizer after the normalized network."""
        return regularizer_after(kind, self.grid, self.normalized_at_centres)

    def problem(self, data, regularizer: str = "none", lam: float = 1e-3, x0=None,
                sigma=None) -> solvers.Problem:
        r"""The inverse problem on network weights (kind ``"neural-centres"``): minimize
        :math:`\sum ((F(\theta) - d)/\sigma)^2 + \lambda \Phi(\theta)`.

        The parameters are those of
        :meth:`~invflame.representations.protocol.Representation.problem`, the regularizer
        that of :meth:`regularizer`, the starting parameters network weights.
        """
        forward, weighted = whitened(self.forward, data, sigma)
        penalty = self.regularizer(regularizer)
        return solvers.Problem(
            forward, weighted, regularizer=penalty, lam=lam, x0=x0,
            name=f"neural-centres/{regularizer}",
            metadata={"representation": self.kind, "regularizer": regularizer, "lambda": lam,
                      "noise_weighted": sigma is not None},
            preconditioner=lambda: self._preconditioner(forward, penalty, lam, x0),
        )

    def _preconditioner(self, forward, penalty, lam: float, x0) -> Diagonal | None:
        r"""For ``preconditioned-lbfgs``: the inverse of the objective's mean Gauss–Newton
        curvature per weight tensor (:func:`~invflame.representations.curvature.
        group_curvature`, the regularizer by its quadratic model), the same for every weight
        of a tensor. A network's tensors differ in curvature by orders of magnitude (this
        estimate for the honest study's network pretrained on the start of the pool fire's LES
        at t = 1.2 s, quick preset, λ = 30: 4.5e8 for the last layer's weights, 3.2e5 for the
        third hidden layer's), which a step along the plain gradient cannot bridge. None
        without a start. Costs two Jacobian-vector products per tensor (28 for the study's
        network), so the problem builds it only when a solver asks."""
        if x0 is None:
            return None
        sizes = [p.numel() for p in self.network.parameters()]
        groups = np.repeat(np.arange(len(sizes)), sizes)
        curvature = group_curvature(
            forward, x0, groups, regularizer=None if penalty is None else penalty.op,
            weight=0.0 if penalty is None else quadratic_weight(penalty, lam, x0))
        return Diagonal((1.0 / curvature[groups]).astype(self.dtype), dtype=self.dtype,
                        name="inverse curvature per tensor")

    def fields(self, theta) -> np.ndarray:
        """Physical fields ``(4, nx, ny, nz)`` (T in K, mole fractions) at the voxel centres."""
        return self.at_centres(theta)

    def rendered_fields(self, theta) -> np.ndarray:
        """The physical fields the forward map renders: :meth:`fields`, with a sub-voxel
        model at each voxel's emission-equivalent progress."""
        if self.subvoxel is None:
            return self.fields(theta)
        s_h = np.asarray(self.relation_parameters(theta), dtype=np.float64)
        return relation_fields(self.network.state_relation, s_h, np, self.subvoxel)
