"""Time the voxel regularizers' value and gradient against the same built from pylops.

Run: ``python benchmarks/bench_regularizer.py [--cells 60] [--fields 4] [--repeats 20]``.

On ``(fields, cells, cells, cells)`` float32 parameters over a 1 m cube, the Tikhonov and TV
regularizers (:func:`operators.tikhonov`, :func:`operators.total_variation`) as a voxel
reconstruction evaluates them every epoch: the value at a point and the gradient there, i.e.
the forward differences, the functional and its gradient, and the adjoint differences. Each
once with :class:`operators.derivatives.ForwardDifferences` (what :func:`operators.Gradient`
builds) and once with the same differences as three :class:`pylops.FirstDerivative`
(``kind="forward"``, ``edge=False``) stacked by :func:`operators.vstack`. Prints the best wall
time of ``--repeats`` and the ratio of the two, measured in one run.
"""

import argparse

import numpy as np
from timing import best_time

import operators as op
from operators.functionals import L1, Composite, SquaredL2
from operators.pylops_import import pylops


def pylops_gradient(dims, spacing, dtype):
    """The stacked forward differences built from pylops operators."""
    return op.vstack([op.aslinearoperator(pylops.FirstDerivative(
        dims, axis=axis, sampling=step, kind="forward", edge=False, dtype=dtype))
        for axis, step in zip((1, 2, 3), spacing, strict=True)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=60, help="voxels per grid axis")
    parser.add_argument("--fields", type=int, default=4, help="fields per voxel")
    parser.add_argument("--repeats", type=int, default=20, help="timed repetitions")
    args = parser.parse_args()
    dims = (args.fields, *(3 * [args.cells]))
    spacing = (1.0 / args.cells,) * 3
    x = np.random.default_rng(0).random(dims, dtype=np.float32)
    n = np.prod(dims)
    print(f"parameters {dims} float32, best of {args.repeats}")
    for name, functional in (("Tikhonov", SquaredL2(scale=1.0 / n)),
                             ("TV", L1(scale=1.0 / n))):
        times = {}
        for label, gradient in (("ForwardDifferences", op.Gradient(dims, spacing, np.float32)),
                                ("pylops stack", pylops_gradient(dims, spacing, np.float32))):
            reg = Composite(functional, gradient)

            def value_and_gradient(reg=reg, gradient=gradient):
                jacobian = gradient.linearize(x)
                return reg.functional(jacobian.value), jacobian.adjoint(
                    reg.functional.grad(jacobian.value))

            times[label] = 1e3 * best_time(value_and_gradient, args.repeats)
        print(f"{name:>9}: value and gradient {times['ForwardDifferences']:6.1f} ms "
              f"(pylops stack {times['pylops stack']:6.1f} ms, "
              f"{times['pylops stack'] / times['ForwardDifferences']:.1f}x)")


if __name__ == "__main__":
    main()
