"""Matrix-free operators with derivatives, pylops-compatible when linear.

Domain-agnostic: this package imports neither :mod:`solvers` nor :mod:`invflame`.
Importing it enables float64 in JAX (``jax_enable_x64``) so that derivative and adjoint checks
can run in double precision; arrays keep the dtype they are given.
"""

import jax

jax.config.update("jax_enable_x64", True)

from operators.averaging import RowMean  # noqa: E402
from operators.base import (  # noqa: E402
    Jacobian,
    LinearOperator,
    Operator,
    aslinearoperator,
    block_diag,
    vstack,
)
from operators.checks import (  # noqa: E402
    dottest,
    gradient_taylor_test,
    jacobian_dottest,
    taylor_test,
)
from operators.derivatives import D_x, D_y, D_z, Gradient, derivative  # noqa: E402
from operators.diagonal import Diagonal  # noqa: E402
from operators.emission_rte import (  # noqa: E402
    EmissionRTE,
    RTETables,
    emission_radiance,
    emission_radiance_jvp,
)
from operators.functionals import (  # noqa: E402
    L1,
    Composite,
    Functional,
    SquaredL2,
    tikhonov,
    total_variation,
)
from operators.ils import ILSConvolution  # noqa: E402
from operators.jax_operator import JaxOperator  # noqa: E402
from operators.planck import planck  # noqa: E402
from operators.sampling import VoxelSampling, sample_voxels  # noqa: E402
from operators.tabulated import PiecewiseCubic  # noqa: E402
from operators.torch_operator import TorchOperator  # noqa: E402

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
    "Jacobian",
    "JaxOperator",
    "L1",
    "LinearOperator",
    "Operator",
    "PiecewiseCubic",
    "RTETables",
    "RowMean",
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
    "planck",
    "sample_voxels",
    "taylor_test",
    "tikhonov",
    "total_variation",
    "vstack",
]
