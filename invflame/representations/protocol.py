"""What every parameterization of the flame fields offers the solvers and the runner."""

from __future__ import annotations

from typing import Protocol

import numpy as np

import solvers


class Representation(Protocol):
    r"""A parameterization :math:`\theta \mapsto` fields of a scene's grid, and its problem.

    The representations subclass it (for :meth:`parameter_bytes`); any object with these
    members serves.

    Attributes
    ----------
    kind : str
        Name of the representation, a key of
        :data:`invflame.representations.REPRESENTATIONS` (``solvers.Problem.kind`` of its
        problems).
    iterations_per_epoch : int
        Solver iterations per pass over all pixels.
    """

    kind: str
    iterations_per_epoch: int

    def initial_parameters(self, fields, **options) -> np.ndarray:
        r"""Parameters :math:`\theta` for physical fields ``(4, nx, ny, nz)`` (T in K, mole
        fractions) on the grid."""
        ...

    def problem(self, data, regularizer: str = "none", lam: float = 1e-3, x0=None,
                sigma=None) -> solvers.Problem:
        r"""The inverse problem on :math:`\theta`: minimize
        :math:`\sum ((F(\theta) - d)/\sigma)^2 + \lambda \Phi(\theta)`.

        Parameters
        ----------
        data : ndarray, shape (n_rays, n_out)
            Measured pixel spectra in W/(m²·sr·cm⁻¹).
        regularizer : {"none", "tikhonov", "tv"}
            :math:`\Phi`, the voxel regularizer of the normalized fields.
        lam : float
            Weight λ (default 1e-3), on the scale of the noise-weighted sum of squares.
        x0 : ndarray, optional
            Starting parameters, e.g. from :meth:`initial_parameters`.
        sigma : float or array_like, optional
            Noise standard deviation in W/(m²·sr·cm⁻¹), a scalar or broadcastable to
            ``(n_rays, n_out)`` (see :mod:`invflame.representations.whitening`); None: an
            unweighted misfit.
        """
        ...

    def fields(self, theta) -> np.ndarray:
        """Physical fields ``(4, nx, ny, nz)`` (T in K, mole fractions) of parameters
        ``theta``."""
        ...

    def rendered_fields(self, theta) -> np.ndarray:
        """The physical fields the forward map renders for ``theta``: :meth:`fields`, unless
        the representation renders a voxel otherwise than its reported mean state (a
        sub-voxel emission model, :mod:`invflame.representations.subvoxel`)."""
        return self.fields(theta)

    @staticmethod
    def parameter_bytes(theta) -> int:
        """Memory of the parameters ``theta`` in bytes."""
        return int(np.asarray(theta).nbytes)
