"""Matrix-free operators with derivatives, pylops-compatible when linear.

Domain-agnostic: this package imports neither :mod:`solvers` nor :mod:`invflame`, and the
flame's radiative transfer has a subpackage of its own, :mod:`operators.rte`, whose
operator, kernel and tables are exported here too. Importing
it changes nothing in the process: it does not import torch (only building a
:class:`TorchOperator` or importing the torch-specific modules does) and does not turn on JAX's
64-bit mode; an operator of dtype float64 computes in float64 inside :func:`precision` only.
"""

from operators.adapters import aslinearoperator
from operators.algebra import linearize_together
from operators.averaging import RowMean
from operators.base import (
    Identity,
    Jacobian,
    JaxMap,
    JaxOperator,
    LinearOperator,
    Operator,
    TorchOperator,
    precision,
)
from operators.checks import (
    dottest,
    gradient_taylor_test,
    jacobian_dottest,
    taylor_test,
)
from operators.combinators import block_diag, vstack
from operators.derivatives import D_x, D_y, D_z, Gradient, derivative
from operators.diagonal import Diagonal
from operators.functionals import (
    L1,
    Composite,
    Functional,
    SquaredL2,
    tikhonov,
    total_variation,
)
from operators.ils import ILSConvolution
from operators.norm import operator_norm
from operators.rte import EmissionRTE, RTETables, emission_radiance, emission_radiance_jvp
from operators.rte.planck import planck
from operators.sampling import VoxelSampling, sample_voxels
from operators.screened_poisson import ScreenedPoissonSolve
from operators.tabulated import PiecewiseCubic

__all__ = [
    "Composite",
    "D_x",
    "D_y",
    "D_z",
    "Diagonal",
    "EmissionRTE",
    "Functional",
    "Gradient",
    "ILSConvolution",
    "Identity",
    "Jacobian",
    "JaxMap",
    "JaxOperator",
    "L1",
    "LinearOperator",
    "Operator",
    "PiecewiseCubic",
    "RTETables",
    "RowMean",
    "ScreenedPoissonSolve",
    "SquaredL2",
    "TorchOperator",
    "VoxelSampling",
    "aslinearoperator",
    "block_diag",
    "derivative",
    "dottest",
    "emission_radiance",
    "emission_radiance_jvp",
    "gradient_taylor_test",
    "jacobian_dottest",
    "linearize_together",
    "operator_norm",
    "planck",
    "precision",
    "sample_voxels",
    "taylor_test",
    "tikhonov",
    "total_variation",
    "vstack",
]
