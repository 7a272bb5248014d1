"""``invflame demo``: compose a small forward map and check its derivatives."""

from __future__ import annotations

import argparse


def add_parser(subparsers) -> None:
    """Register ``invflame demo``."""
    parser = subparsers.add_parser(
        "demo",
        help="compose operators (gradient, nonlinearity, instrument lineshape) and run their "
        "dot-product and Taylor tests",
        description="Builds D_x/D_y/D_z on a small non-cubic grid, the FTIR instrument "
        "lineshape for 650-725 cm-1 at 8 cm-1 resolution, and a composed nonlinear map, "
        "and prints their dot-product and Taylor tests (float64).",
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the checks; exit code 1 if any fails."""
    import jax.numpy as jnp
    import numpy as np

    import operators as op

    rng = np.random.default_rng(args.seed)
    dims = (4, 6, 5, 3)
    eta = np.arange(650.0, 725.0 + 1e-9, 0.04)
    ils = op.ILSConvolution(eta, n_rays=3, resolution=8.0)
    emission = op.Operator.from_jax(lambda t: 1e-3 * jnp.exp(t / 400.0), ils.dims, ils.dims,
                                    name="exp")
    forward = ils @ emission
    results = [op.dottest(op.Gradient(dims, 0.1), seed=rng), op.dottest(ils, seed=rng),
               op.jacobian_dottest(forward, 1000.0 + 100 * rng.random(ils.dims), seed=rng),
               op.taylor_test(forward, 1000.0 + 100 * rng.random(ils.dims), seed=rng)]
    for result in results:
        print(result, end="\n\n")
    return 0 if all(r.passed for r in results) else 1
