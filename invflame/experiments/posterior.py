r"""The linearized Gaussian (Laplace) posterior of a voxel problem around its solution.

**The posterior.** A voxel problem (:class:`solvers.Problem`, built by
:func:`~invflame.experiments.regularization.configured_problem` under the default ``"chi2"``
weighting) minimizes

.. math:: L(\theta) = \Big\|\frac{F(\theta) - d}{\sigma}\Big\|^2 + \lambda\,\Phi(\theta),

which is :math:`-2 \log` of a posterior density: a Gaussian likelihood of the data with noise
standard deviation :math:`\sigma` (weights :math:`W = 1/\sigma^2`, 0 for a masked value) times
the prior :math:`\exp(-\lambda\Phi/2)`. Linearized at the solution :math:`\hat\theta`, the
posterior is Gaussian with covariance :math:`\Gamma_\text{post} = H^{-1}`, the inverse of the
Gauss–Newton Hessian of :math:`L/2`,

.. math:: H = J^\mathsf{T} W J + \Gamma^{-1}, \qquad \Gamma^{-1} = a\,D^\mathsf{T} D + \delta I,

with :math:`J` the forward map's Jacobian at :math:`\hat\theta` (applied only through JVPs and
VJPs), :math:`D` the regularizer's forward differences and :math:`a` its weight:

- Tikhonov, :math:`\Phi = s\|D\theta\|^2`: exact, :math:`a = \lambda s`.
- Total variation, :math:`\Phi = s\sum|D\theta|`: its Hessian is zero wherever a difference
  is not, and undefined where one is; it is replaced by the quadratic that touches each
  :math:`|t|` at the median non-zero :math:`|D\hat\theta| = \tau`, :math:`a = \lambda s /
  (2\tau)` (:func:`~invflame.representations.curvature.quadratic_weight`, the curvature that
  ``preconditioned-lbfgs`` uses too): a Gaussian smoothness prior as stiff as TV at a typical
  difference.
- No regularizer: :math:`a = 0`.

The **floor** :math:`\delta = 1/s_0^2` is an independent Gaussian of standard deviation
:math:`s_0` (``prior_std``, default 1 in the parameters' units: the width of the progress's
bounds, about that of the temperature factor's and of a normalized field's range) on every
parameter. It makes the prior proper (:math:`D^\mathsf{T}D` does not see a field's mean), and
bounds the variance of what neither the data nor the regularizer sees: every direction
without a regularizer, a field's mean in a region no ray crosses.

**Low rank plus diagonal** (Flath et al., SIAM J. Sci. Comput. 33, 2011; Bui-Thanh et al.,
SIAM J. Sci. Comput. 35, 2013). With :math:`\Gamma^{1/2}` the symmetric square root, the
eigenpairs :math:`(d_i, v_i)` of the prior-preconditioned misfit Hessian
:math:`\hat H = \Gamma^{1/2} J^\mathsf{T} W J\, \Gamma^{1/2}` give, by Sherman–Morrison–Woodbury,

.. math:: \Gamma_\text{post} = \Gamma - \sum_i \frac{d_i}{1 + d_i}\,
   (\Gamma^{1/2} v_i)(\Gamma^{1/2} v_i)^\mathsf{T}.

:math:`\Gamma` is diagonal in the orthonormal cosine basis of the Neumann differences
(:class:`operators.ScreenedPoissonSolve`), so :math:`\Gamma^{1/2}` costs two cosine transforms
and :math:`\mathrm{diag}(\Gamma)` follows exactly from the basis. The leading eigenpairs come
from a randomized eigendecomposition with subspace iteration (Halko, Martinsson & Tropp, SIAM
Rev. 53, 2011, algorithms 4.4 and 5.3). Keeping the ``rank`` largest leaves out terms that
would only lower the variances further: the standard deviations are an upper bound of the
linearized posterior's, close to it when the last kept :math:`d_k \ll 1`
(:attr:`LaplacePosterior.truncation`).

**Cost.** :math:`(q + 2)(k + p)` Hessian products (each a JVP and a VJP of the forward map, as
much as about one solver iteration) for rank :math:`k`, oversampling :math:`p` and :math:`q`
power iterations; memory :math:`O((k + p) N)` float64 numbers for :math:`N` unknowns (the
probes, their basis and the factor :math:`\Gamma^{1/2} V`), plus :math:`O(n^4)` operations
once for :math:`\mathrm{diag}(\Gamma)` on an :math:`n^3` grid.

**Bounds.** The Hessian is that of the unconstrained objective at :math:`\hat\theta`. Where a
parameter sits at a bound (the progress of ambient air at :math:`s = 0`), the posterior is that
Gaussian cut at the bound: with its mode on the bound, :math:`[\hat\theta, \hat\theta +
k\sigma]` holds the same probability as :math:`\hat\theta \pm k\sigma` for an interior
parameter, so :math:`\sigma` is kept and reads as the half-width of a one-sided interval
(conservative where the gradient pushes against the bound).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.fft import dct

from invflame.representations.curvature import quadratic_weight
from operators import ScreenedPoissonSolve
from operators.derivatives import ForwardDifferences
from solvers.progress import progress_bar

SPATIAL_AXES = (1, 2, 3)


class SmoothnessPrior:
    r"""The Gaussian :math:`N(\hat\theta, \Gamma)`, :math:`\Gamma = (a D^\mathsf{T} D +
    \delta I)^{-1}`, on parameters ``(n_fields, nx, ny, nz)``.

    Parameters
    ----------
    dims : tuple of 4 int
        ``(n_fields, nx, ny, nz)``.
    spacing : tuple of 3 float
        Grid spacing of the differences :math:`D`, in m.
    weight : float
        :math:`a \ge 0`, in parameter units⁻² m².
    floor : float
        :math:`\delta > 0`, in parameter units⁻².
    """

    def __init__(self, dims, spacing, weight: float, floor: float):
        self.solve = ScreenedPoissonSolve(dims, spacing, weight, floor)
        self.dims = tuple(self.solve.dims)
        self.weight, self.floor = float(weight), float(floor)
        self.eigenvalues = np.broadcast_to(self.solve.inverse_eigenvalues, self.dims)
        """Eigenvalues of :math:`\\Gamma` in the cosine basis, shape ``dims``."""

    def apply(self, v, power: float = 1.0) -> np.ndarray:
        r""":math:`\Gamma^{p} v` (``power`` :math:`p`: 1, 1/2 for the square root, -1 for the
        precision), float64 of shape ``dims`` (:meth:`operators.ScreenedPoissonSolve.power`)."""
        return self.solve.power(np.asarray(v).reshape(self.dims), power)

    def variance(self) -> np.ndarray:
        r""":math:`\mathrm{diag}(\Gamma)`, shape ``dims`` (parameter units²): for the
        orthonormal cosine matrices :math:`C_x, C_y, C_z`, :math:`\Gamma_{ii} = \sum_k
        C_{k,i}^2 \mu_k`, contracted axis by axis."""
        out = self.eigenvalues
        for axis in SPATIAL_AXES:
            n = self.dims[axis]
            squared = dct(np.eye(n), type=2, axis=0, norm="ortho") ** 2  # [k, i]
            out = np.moveaxis(np.tensordot(out, squared, axes=([axis], [0])), -1, axis)
        return out


def regularizer_prior(problem, x, prior_std: float = 1.0) -> SmoothnessPrior:
    r"""The prior of a voxel problem's regularizer at ``x`` (the module docstring).

    Parameters
    ----------
    problem : solvers.Problem
        Parameters ``(n_fields, nx, ny, nz)``; its regularizer, if any, after the stacked
        forward differences of :func:`operators.Gradient` (Tikhonov or TV of a voxel grid).
    x : ndarray
        The solution, ``problem.dims`` (needed for TV's weight).
    prior_std : float, optional
        :math:`s_0 > 0`, the floor's standard deviation in the parameters' units (default 1).

    Raises
    ------
    ValueError
        For a bad ``prior_std``, parameters that are not a grid, or a regularizer that is not
        a function of the forward differences along x, y and z.
    """
    if not (np.isfinite(prior_std) and prior_std > 0):
        raise ValueError(f"prior_std must be a finite number > 0 (parameter units), got "
                         f"{prior_std}")
    if len(problem.dims) != 4:
        raise ValueError(f"the posterior needs voxel parameters (n_fields, nx, ny, nz); the "
                         f"problem's have shape {problem.dims}")
    regularizer, spacing, weight = problem.regularizer, (1.0, 1.0, 1.0), 0.0
    if regularizer is not None and problem.lam > 0:
        differences = regularizer.op
        if not (isinstance(differences, ForwardDifferences)
                and differences.axes == SPATIAL_AXES and differences.stacked):
            raise ValueError(f"the regularizer's operator {differences.name} is not the "
                             "voxel grid's forward differences (operators.Gradient): the "
                             "posterior covers Tikhonov and TV of voxel parameters")
        spacing = tuple(1.0 / step for step in differences.inverse_steps)
        weight = quadratic_weight(regularizer, problem.lam, x)
    return SmoothnessPrior(problem.dims, spacing, weight, 1.0 / prior_std**2)


def misfit_hessian(problem, x) -> Callable[[np.ndarray], np.ndarray]:
    r""":math:`v \mapsto J^\mathsf{T} W J v`, the Gauss–Newton Hessian of half the data term
    of ``problem`` (its forward map is noise-whitened) at ``x``.

    Parameters
    ----------
    problem : solvers.Problem
    x : ndarray
        The point, ``problem.dims``.

    Returns
    -------
    callable
        Taking and returning float64 arrays of ``problem.dims`` (parameter units⁻² times
        parameter units); the products run in the forward map's dtype.
    """
    jacobian = problem.forward.linearize(x)

    def apply(v):
        flat = np.asarray(v, problem.dtype).ravel()
        return np.asarray(jacobian.rmatvec(jacobian.matvec(flat)), np.float64).reshape(
            problem.dims)

    return apply


def randomized_eigenpairs(apply, n: int, rank: int, oversampling: int = 10,
                          power_iterations: int = 1, seed: int = 0,
                          progress: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The ``rank`` largest eigenpairs of a symmetric positive semidefinite operator.

    Randomized range finder with subspace iteration, then the eigenpairs of the projected
    matrix (Halko, Martinsson & Tropp 2011, algorithms 4.4 and 5.3):
    ``(power_iterations + 2) * (rank + oversampling)`` products, at most ``n`` probes.

    Parameters
    ----------
    apply : callable
        ``v -> A v`` for float64 vectors of length ``n``.
    n : int
        Dimension.
    rank : int
        Eigenpairs wanted, 1 <= rank <= n.
    oversampling : int, optional
        Extra probes (default 10).
    power_iterations : int, optional
        Subspace iterations (default 1); each sharpens the leading eigenpairs when the
        spectrum decays slowly.
    seed : int, optional
        Of the Gaussian probes.
    progress : bool, optional
        Show a progress bar of the products.

    Returns
    -------
    eigenvalues : ndarray, shape (rank,)
        Descending, clipped at 0.
    vectors : ndarray, shape (n, rank)
        Orthonormal eigenvectors.
    """
    if not 1 <= rank <= n:
        raise ValueError(f"rank must lie in 1..{n} (the number of unknowns), got {rank}")
    if oversampling < 0 or power_iterations < 0:
        raise ValueError(f"oversampling and power_iterations must be >= 0, got "
                         f"{oversampling} and {power_iterations}")
    probes = min(rank + oversampling, n)
    bar = progress_bar(total=(power_iterations + 2) * probes, desc="Hessian products",
                       unit="product", disable=not progress)

    def columns(block):
        out = np.empty_like(block)
        for j in range(block.shape[1]):
            out[:, j] = apply(block[:, j])
            bar.update()
        return out

    with bar:
        basis = np.linalg.qr(columns(np.random.default_rng(seed).standard_normal((n, probes))))[0]
        for _ in range(power_iterations):
            basis = np.linalg.qr(columns(basis))[0]
        projected = basis.T @ columns(basis)
    values, small = np.linalg.eigh((projected + projected.T) / 2)
    order = np.argsort(values)[::-1][:rank]
    return np.maximum(values[order], 0.0), basis @ small[:, order]


@dataclass(frozen=True)
class LaplacePosterior:
    r"""The low-rank plus diagonal posterior covariance (the module docstring).

    Attributes
    ----------
    prior : SmoothnessPrior
        :math:`\Gamma`.
    eigenvalues : ndarray, shape (k,)
        :math:`d_i` of the prior-preconditioned misfit Hessian, descending (dimensionless).
    factor : ndarray, shape (k, n_fields, nx, ny, nz)
        :math:`\Gamma^{1/2} v_i`, parameter units.
    """

    prior: SmoothnessPrior
    eigenvalues: np.ndarray
    factor: np.ndarray

    @property
    def reduction(self) -> np.ndarray:
        r""":math:`d_i / (1 + d_i)`, the share of each direction's prior variance that the
        data remove."""
        return self.eigenvalues / (1.0 + self.eigenvalues)

    @property
    def truncation(self) -> float:
        r""":math:`d_k / (1 + d_k)` of the last kept eigenvalue: the most that any left-out
        direction would remove of its prior variance (small: the rank suffices)."""
        return float(self.reduction[-1])

    def voxel_covariance(self) -> np.ndarray:
        r"""The posterior covariance of each voxel's parameters, shape
        ``(n_fields, n_fields, nx, ny, nz)`` (parameter units²): :math:`\mathrm{diag}(\Gamma)`
        on the diagonal (the prior couples no two fields) minus the low-rank part's block."""
        low_rank = np.einsum("i,iaxyz,ibxyz->abxyz", self.reduction, self.factor, self.factor)
        prior = np.einsum("ab,axyz->abxyz", np.eye(self.prior.dims[0]), self.prior.variance())
        return prior - low_rank

    def variance(self) -> np.ndarray:
        r""":math:`\mathrm{diag}(\Gamma_\text{post})`, shape ``(n_fields, nx, ny, nz)``
        (parameter units²)."""
        return np.einsum("aaxyz->axyz", self.voxel_covariance())


def laplace_posterior(problem, x, rank: int = 100, oversampling: int = 10,
                      power_iterations: int = 1, prior_std: float = 1.0, seed: int = 0,
                      progress: bool = False) -> LaplacePosterior:
    r"""The linearized posterior of a voxel problem at its solution ``x``.

    Parameters
    ----------
    problem : solvers.Problem
        Noise-whitened data term, Tikhonov, TV or no regularizer on voxel parameters
        (:func:`regularizer_prior`).
    x : ndarray
        The solution, ``problem.dims``.
    rank, oversampling, power_iterations, seed, progress
        Of :func:`randomized_eigenpairs` (``rank`` is capped at the number of unknowns).
    prior_std : float, optional
        The floor's standard deviation, parameter units (default 1).

    Returns
    -------
    LaplacePosterior
    """
    x = np.asarray(x).reshape(problem.dims)
    prior = regularizer_prior(problem, x, prior_std)
    misfit = misfit_hessian(problem, x)
    n = int(np.prod(problem.dims))

    def preconditioned(v):
        return prior.apply(misfit(prior.apply(v, 0.5)), 0.5).ravel()

    values, vectors = randomized_eigenpairs(preconditioned, n, min(rank, n), oversampling,
                                            power_iterations, seed, progress)
    factor = np.stack([prior.apply(v, 0.5) for v in vectors.T])
    return LaplacePosterior(prior, values, factor)
