r"""How a study row's fit moves along its iterations: misfit, smoothness and distance to the truth.

Usage: python studies/iteration_trace.py --truth FIELD.npz [--method VG/NR] [--lambda L]
       [--iterations 200] [--every 10] [--hold-out FRACTION] [--set SECTION.KEY=VALUE ...]
       python studies/iteration_trace.py --collect TRACE.txt ... [--levels 2 4 8] [--limit 100]

Solves one method of the honest quick problem
(:func:`invflame.experiments.method_problem.method_problem`: the study's data, calibrated
start, λ and solver) from its start and prints, every ``--every`` iterations, :math:`\chi^2/M`
(noise-weighted misfit per measured value), the unweighted regularizer :math:`\Phi`, MSE_T and
MSE_CO2 against the truth averaged onto the grid, the gain over the start and the hot-volume
ratio: where along its path a row is nearest the truth, and what its misfit is there.

``--hold-out FRACTION`` leaves that fraction of the pixels (drawn at random) out of the fit
and prints their :math:`\chi^2/M` too: whether data the fit did not see tell when it starts
to move away from the truth.

``--collect`` reads traces this script printed and prints, per trace, the gain over the
start where a stopping rule at each :math:`\chi^2/M` level (``solver.stop_chi2``) would have
ended the run (the first printed iterate at or below it, else the iteration limit), at the
limit itself and at the best printed iterate, with the geometric mean over the traces.
"""

import argparse
import dataclasses

import numpy as np

import solvers
from invflame.experiments import reproduce
from invflame.experiments.config_text import parse_setting
from invflame.experiments.method_problem import method_problem
from invflame.experiments.parameters import physical_fields


def trace(setup, lam, iterations, every, hold_out=0.0):
    """Solve the method's problem with its solver and print a row every ``every``
    iterations, with ``hold_out`` of the pixels left out of the fit."""
    full = setup.measurement
    sigma = np.array(np.broadcast_to(full.sigma, full.data.shape))
    held = np.random.default_rng(1).random(full.data.shape[0]) < hold_out
    fitted = dataclasses.replace(full, sigma=np.where(held[:, None], np.inf, sigma))
    problem = setup.problem(lam, fitted)
    m = fitted.n_measurements
    start = setup.scores(setup.x0)["mse"]["T"]
    print(f"start MSE_T {start:.5f}; solver {setup.cfg['solver']['name']}, λ "
          f"{setup.cfg['regularizer']['lambda'] if lam is None else lam:g}")
    print(f"{np.count_nonzero(held)} of {held.size} pixels held out")
    print("| iteration | χ²/M | held-out χ²/M | Φ | MSE_T | gain | MSE_CO2 | hot vol. |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")

    def held_out(x):
        if not held.any():
            return float("nan")
        simulated = setup.scene.simulate(physical_fields(setup.scene,
                                                         setup.representation.fields(x)))
        return float(np.mean(((simulated - full.data) / sigma)[held] ** 2))

    def row(run):
        if run.iteration % every:
            return
        scores = setup.scores(run.x)
        print(f"| {run.iteration} | {run.current.misfit / m:.4g} | {held_out(run.x):.4g} | "
              f"{run.current.regularizer:.4g} | {scores['mse']['T']:.5f} | "
              f"{start / scores['mse']['T']:.2f} | {scores['mse']['CO2']:.5f} | "
              f"{scores['hot_volume_ratio']:.2f} |", flush=True)

    options = {k: v for k, v in setup.cfg["solver"]["options"].items()
               if k not in ("rtol_loss", "loss_window")}
    result = solvers.solve(problem, setup.cfg["solver"]["name"], max_iter=iterations,
                           callbacks=[row], **options)
    print(f"stopped: {result.stop_reason}")


def read_trace(path):
    """A printed trace: its title line, and its rows as dicts of the table's columns."""
    lines = open(path, encoding="utf-8").read().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("| iteration"))
    names = [c.strip() for c in lines[header].strip("|").split("|")]
    rows = [dict(zip(names, map(float, line.strip("|").split("|")), strict=True))
            for line in lines[header + 2:] if line.startswith("| ")]
    return lines[0], rows


def collect(paths, levels, limit):
    """Print the gain each χ²/M level would have stopped at, per trace and their geometric
    mean (:func:`read_trace`)."""
    print(f"| trace | {' | '.join(f'χ²/M ≤ {lv:g}' for lv in levels)} | limit {limit} | best |")
    print("|---|" + "---:|" * (len(levels) + 2))
    table = []
    for path in paths:
        title, rows = read_trace(path)
        rows = [r for r in rows if r["iteration"] <= limit]
        picked = [next((r for r in rows if r["χ²/M"] <= level), rows[-1]) for level in levels]
        picked += [rows[-1], max(rows, key=lambda r: r["gain"])]
        table.append([r["gain"] for r in picked])
        print(f"| {title} | " + " | ".join(f"{r['gain']:.2f} (it. {r['iteration']:.0f})"
                                            for r in picked) + " |")
    mean = np.exp(np.mean(np.log(table), axis=0))
    print("| geometric mean | " + " | ".join(f"{g:.3f}" for g in mean) + " |")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="iteration_trace")
    parser.add_argument("--truth", default="poolfire")
    parser.add_argument("--collect", nargs="+", default=None, metavar="TRACE")
    parser.add_argument("--levels", type=float, nargs="+", default=[2.0, 4.0, 8.0])
    parser.add_argument("--limit", type=int, default=100)
    parser.add_argument("--method", default="VG/NR", choices=tuple(reproduce.METHODS))
    parser.add_argument("--lambda", dest="lam", type=float, default=None)
    parser.add_argument("--iterations", type=int, default=200)
    parser.add_argument("--every", type=int, default=10)
    parser.add_argument("--hold-out", type=float, default=0.0, metavar="FRACTION")
    parser.add_argument("--set", nargs="+", default=[], metavar="SECTION.KEY=VALUE",
                        help="other settings of the method's configuration (VALUE in TOML)")
    args = parser.parse_args()
    try:
        settings = {(section, key): value
                    for section, key, value in map(parse_setting, args.set)}
    except ValueError as error:
        parser.error(f"--set: {error}")
    if args.collect:
        collect(args.collect, args.levels, args.limit)
        raise SystemExit
    print(f"{args.method} on {args.truth}")
    trace(method_problem(args.method, args.truth, settings=settings), args.lam,
          args.iterations, args.every, args.hold_out)
