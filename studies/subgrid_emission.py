"""Can a voxel's mean state be made to emit as its parts do? The grid's model error, and an
emission-equivalent state that removes it.

Usage: python studies/subgrid_emission.py [--truth poolfire] [--method VG/Tikh.]

A 30³ voxel of a flame holds a thin hot sheet and cool gas; emission grows faster than
linearly with temperature, so the voxel's mean state emits less than its parts (the truth
averaged onto the study's grid sums to 8–12 % less radiance than the data,
``studies/grid_model_error.py``). This prints χ²/M of the data against the model of

- the truth averaged onto the reconstruction grid (the study's model);
- the same with each voxel's progress raised to the *emission-equivalent* progress of its
  eight children on the twice finer grid: the progress whose state, at the voxel's own
  temperature factor, emits the children's mean of a thin-gas emission proxy
  ``X_CO2 · B_ν(T) / T`` at 690 cm⁻¹ (mole fraction × Planck × number density); an upper
  bound of what a sub-voxel model of the progress can do;
- the same with a presumed sub-voxel spread of the progress from the averaged field alone:
  two states, ``s̄ ± a``, with ``a = c · Δ |∇s̄|`` (the central-difference gradient over one
  voxel ``Δ``), kept inside ``[0, s_max]`` about the mean, for each ``c`` of ``--spread``.

and the radiance each sums to against the data's. Uses the truth (a diagnosis of the model,
not a reconstruction).
"""

import argparse

import numpy as np

from invflame.experiments import config, reproduce, runner
from invflame.experiments.parameters import state_relation
from invflame.geometry import VoxelGrid

C2 = 1.4387769  # second radiation constant, cm K
NU0 = 690.0  # cm-1


def proxy(relation, s, h):
    """Thin-gas emission per unit volume, up to a constant: X_CO2 · B_ν0(T) / T."""
    t, co2, _, _ = relation.states(s, h)
    return co2 / np.expm1(C2 * NU0 / t) / t


def equivalent_progress(relation, target, h, n_points: int = 2049):
    """The progress whose state at factor ``h`` emits ``target`` (bisection on the monotone
    proxy, vectorized)."""
    lo = np.zeros_like(target)
    hi = np.full_like(target, relation.progress_max)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        above = proxy(relation, mid, h) > target
        hi = np.where(above, mid, hi)
        lo = np.where(above, lo, mid)
    return 0.5 * (lo + hi)


def two_state_target(relation, s, h, c):
    """Mean proxy of the two states ``s ± a`` with ``a = c·|∇s|`` (gradient per voxel)."""
    gradient = np.sqrt(sum(np.gradient(s, axis=k) ** 2 for k in range(3)))
    a = np.minimum(c * gradient, np.minimum(s, relation.progress_max - s))
    return 0.5 * (proxy(relation, s - a, h) + proxy(relation, s + a, h))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="subgrid_emission")
    parser.add_argument("--truth", default="poolfire")
    parser.add_argument("--method", default="VG/Tikh.")
    parser.add_argument("--spread", type=float, nargs="*", default=[0.5, 1.0, 2.0])
    args = parser.parse_args()
    cfg = config.validate(reproduce.method_config("quick", args.method, 0, "honest",
                                                  args.truth))
    scene, native = runner.build_scene(cfg, progress=False), runner.load_truth(cfg)
    measurement = runner.measure(cfg, scene, native, progress=False)
    sigma = np.broadcast_to(measurement.sigma, measurement.data.shape)
    relation = state_relation(cfg, scene)
    n = scene.grid.shape
    grid = scene.grid
    fine = native.resample(VoxelGrid(grid.lower, grid.upper, tuple(2 * k for k in n)))
    coarse = native.resample(scene.grid).values
    s_bar, h_bar = relation.invert(coarse)
    s_fine, h_fine = relation.invert(fine.values)
    children = proxy(relation, s_fine, h_fine).reshape(n[0], 2, n[1], 2, n[2], 2)
    target = children.mean(axis=(1, 3, 5))

    def row(label, s):
        fields = np.stack(relation.states(s, h_bar))
        fields = np.where(s_bar > 1e-3, fields, coarse)  # air keeps its averaged state
        prediction = scene.simulate(fields)
        chi2 = float(np.mean(((prediction - measurement.data) / sigma) ** 2))
        print(f"| {label} | {chi2:.4g} | {prediction.sum() / measurement.data.sum():.4f} |",
              flush=True)

    print(f"{args.truth} ({args.method}'s quick problem, grid {n}): χ²/M of the data against")
    print("| model of the truth | χ²/M | radiance / data's |")
    print("|---|---:|---:|")
    prediction = scene.simulate(coarse)
    print(f"| averaged onto the grid | "
          f"{np.mean(((prediction - measurement.data) / sigma) ** 2):.4g} | "
          f"{prediction.sum() / measurement.data.sum():.4f} |", flush=True)
    row("its state relation (s̄, h̄)", s_bar)
    row("emission-equivalent progress of the 8 children", equivalent_progress(
        relation, target, h_bar))
    for c in args.spread:
        row(f"two states s̄ ± {c:g}·|∇s̄|", equivalent_progress(
            relation, two_state_target(relation, s_bar, h_bar, c), h_bar))
