"""The voxel parameterization: normalized field values on the reconstruction grid."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import operators as op
import solvers
from invflame.geometry import VoxelGrid
from invflame.representations.curvature import by_field, group_curvature, quadratic_weight
from invflame.representations.normalization import (
    SOOT_MAX,
    SOOT_SCALE,
    denormalize,
    field_scales,
    normalize,
    per_field,
    physical_bounds,
)
from invflame.representations.protocol import Representation
from invflame.representations.state_relation import StateRelation
from invflame.representations.subvoxel import SubvoxelEmission
from invflame.representations.whitening import whitened

REGULARIZERS = ("none", "tikhonov", "tv")


def regularizer_for(kind: str, grid: VoxelGrid, n_fields: int = 4, tv_smoothing: float = 0.0,
                    dtype=np.float64):
    r"""The voxel regularizer Φ on normalized fields, as an ``operators.Composite`` or None.

    Parameters
    ----------
    kind : {"none", "tikhonov", "tv"}
        No regularizer, :math:`\sum_d \mathrm{mean}((D_d u)^2)` or
        :math:`\sum_d \mathrm{mean}(|D_d u|)` with forward differences per metre.
    grid : VoxelGrid
        Gives the shape and spacing (m).
    n_fields : int, optional
        Number of fields (default 4).
    tv_smoothing : float, optional
        Huber smoothing of TV's absolute values (:func:`operators.total_variation`), in 1/m
        (normalized field per metre); 0 (default): exact TV.
    dtype : numpy dtype, optional
        Of the differences (default float64); a voxel problem takes its forward map's, so that
        float32 parameters are not differenced in float64. The value is summed in float64
        either way.
    """
    if kind not in REGULARIZERS:
        raise ValueError(f"unknown regularizer {kind!r}; choose one of {', '.join(REGULARIZERS)}")
    if kind == "none":
        return None
    dims = (n_fields, *grid.shape)
    if kind == "tikhonov":
        return op.tikhonov(dims, tuple(grid.spacing), dtype)
    return op.total_variation(dims, tuple(grid.spacing), dtype, smoothing=tv_smoothing)


class VoxelRepresentation(Representation):
    r"""Normalized fields per voxel as the unknowns: :math:`\theta = u = f / s` (see
    :mod:`invflame.representations.normalization`); or, with a ``state_relation``, the
    progress and temperature factor :math:`\theta = (s, h)` per voxel from which the fields
    follow (:mod:`invflame.representations.state_relation`).

    Parameters
    ----------
    grid : VoxelGrid
        Reconstruction grid.
    forward : operators.Operator
        Voxel forward map from physical fields ``(4, nx, ny, nz)`` (T in K, mole fractions) to
        data, e.g. the scene's :attr:`~invflame.scene.Scene.operator`; or from
        ``(5, nx, ny, nz)``, the soot volume fraction last (a scene with ``soot_input``): soot
        is then reconstructed too.
    temperature_range : tuple of float, optional
        Physical bounds on T in K (default 250–2500 K, the absorption table's range).
    soot_max : float, optional
        Upper bound of the soot volume fraction when the map takes one (dimensionless,
        default :data:`~invflame.representations.normalization.SOOT_MAX`); its lower bound
        is 0.
    tv_smoothing : float, optional
        Huber smoothing of the TV regularizer in 1/m (:func:`regularizer_for`); 0 (default):
        exact TV.
    state_relation : StateRelation, optional
        Parameterize each voxel by its progress :math:`s \in [0, 1]` and temperature factor
        :math:`h` (two fields, both of order 1, regularized like the four), the fields being
        ``state_relation.states(s, h)``, and with soot its normalized volume fraction a third
        field; None (default): the normalized fields. Its ``temperature_max`` should not
        exceed ``temperature_range[1]``.
    subvoxel : SubvoxelEmission, optional
        With a ``state_relation``: render each voxel at the emission-equivalent progress of a
        presumed spread inside it (:mod:`invflame.representations.subvoxel`), the mean
        progress staying the parameter and the reported field; None (default): render the
        mean state.
    """

    kind = "voxel"
    iterations_per_epoch = 1

    def __init__(self, grid: VoxelGrid, forward: op.Operator,
                 temperature_range=(250.0, 2500.0), soot_max: float = SOOT_MAX,
                 tv_smoothing: float = 0.0, state_relation: StateRelation | None = None,
                 subvoxel: SubvoxelEmission | None = None):
        if tuple(forward.dims) not in ((4, *grid.shape), (5, *grid.shape)):
            raise ValueError(f"forward map takes {forward.dims}, expected {(4, *grid.shape)} "
                             f"(or 5 fields with soot) for a {grid.shape} grid")
        if subvoxel is not None and state_relation is None:
            raise ValueError("a sub-voxel emission model renders the state relation's progress: "
                             "give state_relation too")
        self.grid = grid
        self.tv_smoothing = float(tv_smoothing)
        self.state_relation = state_relation
        self.subvoxel = subvoxel
        self.field_dims = tuple(forward.dims)
        n_fields = forward.dims[0]
        bounds = physical_bounds(*temperature_range, soot_max if n_fields == 5 else None)
        lower, upper = (normalize(bound) for bound in bounds)
        if state_relation is None:
            dims = tuple(forward.dims)
            self.forward = forward @ op.Diagonal(per_field(field_scales(n_fields), dims),
                                                 dtype=forward.dtype, name="denormalize")
        else:  # (s, h) and, with soot, its normalized volume fraction
            dims = (n_fields - 2, *grid.shape)
            self.forward = forward @ op.JaxOperator(
                lambda theta: relation_fields(state_relation, theta, jnp, subvoxel), dims,
                forward.dims,
                dtype=forward.dtype, name="state relation")
            low, high = state_relation.factor_range
            lower = np.concatenate([[0.0, low], lower[4:]])
            upper = np.concatenate([[state_relation.progress_max, high], upper[4:]])
        self.dims = dims
        self.lower, self.upper = (np.broadcast_to(b.reshape(-1, 1, 1, 1), dims)
                                  for b in (lower, upper))

    def initial_parameters(self, fields) -> np.ndarray:
        """Parameters for physical fields ``(4, nx, ny, nz)`` (``(5, nx, ny, nz)`` with soot),
        clipped to the bounds."""
        fields = np.asarray(fields)
        if fields.shape != self.field_dims:
            raise ValueError(f"fields must have shape {self.field_dims}, got {fields.shape}")
        values = normalize(fields)
        if self.state_relation is not None:
            values = np.concatenate([np.stack(self.state_relation.invert(fields[:4])),
                                     values[4:]])
        return np.clip(values, self.lower, self.upper).astype(self.forward.dtype)

    def problem(self, data, regularizer: str = "none", lam: float = 1e-3,
                x0=None, sigma=None) -> solvers.Problem:
        r"""The inverse problem on voxel values: minimize
        :math:`\sum ((H(\theta) - d)/\sigma)^2 + \lambda \Phi(\theta)`.

        Parameters
        ----------
        data : ndarray
            Measured spectra, shape ``forward.dimsd``, W/(m²·sr·cm⁻¹).
        regularizer : {"none", "tikhonov", "tv"}
            See :func:`regularizer_for`.
        lam : float
            Weight λ on the sum-of-squares scale (default 1e-3).
        x0 : ndarray, optional
            Starting parameters (normalized), e.g. from :meth:`initial_parameters`.
        sigma : float or array_like, optional
            Noise standard deviation in W/(m²·sr·cm⁻¹) (scalar, per wavenumber or per value);
            None: unweighted misfit. See :mod:`invflame.representations.whitening`.
        """
        forward, data = whitened(self.forward, data, sigma)
        regularizer_op = regularizer_for(regularizer, self.grid, self.dims[0], self.tv_smoothing,
                                         self.forward.dtype)
        return solvers.Problem(
            forward, data, regularizer=regularizer_op, lam=lam,
            lower=self.lower, upper=self.upper, x0=x0,
            name=f"voxel/{regularizer}",
            metadata={"representation": self.kind, "regularizer": regularizer, "lambda": lam},
            preconditioner=lambda: self._preconditioner(forward, regularizer_op, lam, x0),
        )

    def _preconditioner(self, forward, regularizer, lam: float, x0):
        r"""For ``preconditioned-lbfgs``: :math:`(c_f I + a D^\mathsf{T} D)^{-1}`
        (:class:`operators.ScreenedPoissonSolve`), with :math:`c_f` the misfit's mean
        curvature per parameter of field :math:`f` at ``x0``
        (:func:`~invflame.representations.curvature.group_curvature`) and :math:`a
        D^\mathsf{T} D` the regularizer's
        (:func:`~invflame.representations.curvature.quadratic_weight`: :math:`a = \lambda s`
        for Tikhonov, :math:`\lambda s / (2\tau)` for TV). None (the identity) without a
        regularizer or a start. Costs two Jacobian-vector products of the forward map per
        field, so the problem builds it only when a solver asks."""
        if regularizer is None or lam == 0 or x0 is None:
            return None
        return op.ScreenedPoissonSolve(self.dims, tuple(self.grid.spacing),
                                       quadratic_weight(regularizer, lam, x0),
                                       group_curvature(forward, x0, by_field(self.dims)))

    def fields(self, theta) -> np.ndarray:
        """Physical fields ``(4, nx, ny, nz)`` (T in K, mole fractions; with soot a fifth,
        the soot volume fraction) at voxel centres."""
        theta = np.asarray(theta).reshape(self.dims)
        if self.state_relation is None:
            return denormalize(theta)
        return relation_fields(self.state_relation, theta.astype(np.float64), np)

    def rendered_fields(self, theta) -> np.ndarray:
        """The physical fields the forward map renders: :meth:`fields`, with a sub-voxel
        model at each voxel's emission-equivalent progress."""
        if self.subvoxel is None:
            return self.fields(theta)
        theta = np.asarray(theta, dtype=np.float64).reshape(self.dims)
        return relation_fields(self.state_relation, theta, np, self.subvoxel)


def relation_fields(relation: StateRelation, theta, xp, subvoxel=None):
    """Physical fields of state-relation parameters ``(s, h[, u_soot])`` per voxel, in the
    array module ``xp`` (NumPy or ``jax.numpy``): the relation's states (at the rendered
    progress of ``subvoxel`` when given), then the soot volume fraction from its normalized
    value."""
    progress = theta[0] if subvoxel is None else subvoxel.rendered(theta[0], theta[1], xp)
    return xp.concatenate([xp.stack(relation.states(progress, theta[1])),
                           theta[2:] * SOOT_SCALE])
