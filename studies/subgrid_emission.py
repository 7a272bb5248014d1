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
from invflame.representations.subvoxel import SubvoxelEmission

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
    proxy = SubvoxelEmission(relation, 1.0)  # its emission and inverse serve any spread
    target = proxy.emission(s_fine, h_fine).reshape(n[0], 2, n[1], 2, n[2], 2).mean(
        axis=(1, 3, 5))

    def report(label, fields):
        prediction = scene.simulate(fields)
        chi2 = float(np.mean(((prediction - measurement.data) / sigma) ** 2))
        print(f"| {label} | {chi2:.4g} | {prediction.sum() / measurement.data.sum():.4f} |",
              flush=True)

    def row(label, s):
        fields = np.stack(relation.states(s, h_bar))
        report(label, np.where(s_bar > 1e-3, fields, coarse))  # air keeps its averaged state

    print(f"{args.truth} ({args.method}'s quick problem, grid {n}): χ²/M of the data against")
    print("| model of the truth | χ²/M | radiance / data's |")
    print("|---|---:|---:|")
    report("averaged onto the grid", coarse)
    row("its state relation (s̄, h̄)", s_bar)
    row("emission-equivalent progress of the 8 children",
        proxy.equivalent_progress(target, h_bar))
    for c in args.spread:
        row(f"two states s̄ ± {c:g}·|∇s̄|", SubvoxelEmission(relation, c).rendered(s_bar, h_bar))
