"""Race the registered solvers on the same voxel problems: time and evaluations to a level.

Usage: python benchmarks/solver_race.py [--size quick|paper] [--protocol paper|honest]
       [--regularizer tikhonov|tv|both] [--solvers NAME ...] [--budget-s 90]
       [--clock cpu|wall] [--reference-iterations N | --reference-run DIR]
       [--lam KIND=VALUE ...] [--out results/solver_race]
       python benchmarks/solver_race.py --merge DIR ... --out DIR

The problems are the voxel methods VG/Tikh. and VG/TV of ``invflame reproduce`` (protocol
``paper``: truth + 20 % noise as the start, noise-free data from the reconstruction's model) or
of ``invflame study`` (protocol ``honest``: noisy data rendered from the truth on its native
grid, the band-tomography start), at the preset's size. One measurement and one start are built
once and shared by every run, and the forward model is compiled before the first one.

The reference is Adam with the protocol's voxel learning rate (the paper's 1e-2) for the
preset's iteration count (``solver.iterations`` of the method's configuration: 200 epochs at
the quick size under the paper protocol) or ``--reference-iterations``. Every other variant
(:data:`VARIANTS`: a solver and its options; ``--solvers`` takes variant or solver names) runs
for ``--budget-s`` seconds of ``--clock`` time and is cut off inside an iteration at 1.5 times
that. ``cpu`` (the default) counts the CPU seconds of the process, all threads: on a machine
shared with other jobs the wall time measures the neighbours as much as the solver. Along each
run the race records CPU and wall time, the evaluations of the forward operator F, of its
Jacobian (JVP) and of its transpose (VJP), the objective and MSE_T against the truth (this is a
benchmark: the truth chooses nothing). It prints, per problem, the time and evaluations each
variant needs to reach the reference's objective and MSE_T after 25, 50 and 100 % of its
iterations, and writes ``race.json``, ``race.md`` and ``race.png`` (MSE_T and objective against
time, one column per problem) into ``--out``. A variant whose solver refuses a problem is
skipped with the solver's reason; one that raises is reported as failed, with the error.
``--merge`` reports races run side by side (e.g. one regularizer each) as one.

At the paper's size the reference's 2000 Adam epochs take about an hour per problem on two CPU
cores. ``--reference-run DIR`` takes the reference from a finished ``invflame reproduce`` run of
the same method instead (``solver_race_reference.recorded_reference``): its objective and wall
time per iteration from ``history.csv``, its MSE_T at the start and the end
(``reconstruction.npz``, scored against the race's truth) and none in between. The race then
runs on wall time (``--clock wall``, on an idle machine), and a run whose start objective
differs from the race problem's is refused.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from solver_race_reference import recorded_reference, reference_levels
from solver_race_report import merged, report
from solver_race_runs import race
from timing import CLOCKS

import solvers
from invflame.experiments import reproduce, runner
from invflame.experiments.metrics import normalized_mse
from invflame.experiments.regularization import regularizer_weight

#: Variant name → (registered solver, options). A registered solver missing here races with
#: its defaults under its own name.
VARIANTS = {
    "adam": ("adam", {}),
    "adam lr=3e-2": ("adam", {"lr": 3e-2}),
    "gd": ("gd", {}),
    "lbfgs": ("lbfgs", {}),
    "jaxopt-lbfgs": ("jaxopt-lbfgs", {}),
    "gauss-newton inner=5": ("gauss-newton", {"inner_iter": 5}),
    "gauss-newton inner=20": ("gauss-newton", {"inner_iter": 20}),
    "gauss-newton": ("gauss-newton", {}),
    "pdhg inner=10": ("pdhg", {"inner_iter": 10, "norm_iter": 10}),
    "pdhg": ("pdhg", {}),
}
METHODS = {"tikhonov": "VG/Tikh.", "tv": "VG/TV"}


def build_problems(size: str, protocol: str, regularizers: list[str],
                   lams: dict[str, float] | None = None) -> dict:
    """The race's problems sharing one measurement, start and truth.

    ``lams`` (regularizer kind → λ on the configured scale) replaces the protocol's λ; it is
    needed where the protocol chooses λ from the data by a rule (the honest voxel rows), since
    a race compares solvers on one fixed problem.

    Returns
    -------
    dict
        ``problems`` (method label → :class:`solvers.Problem`), ``mse_t`` (parameters → MSE_T),
        ``mse_t_of_fields`` (physical fields ``(n_fields, nx, ny, nz)`` → MSE_T),
        ``iterations`` (the preset's iteration count) and ``lr`` (the protocol's Adam rate).
    """
    first = reproduce.method_config(size, METHODS[regularizers[0]], 0, protocol)
    scene, native = runner.build_scene(first), runner.load_truth(first)
    truth = native.resample(scene.grid)
    measurement = runner.measure(first, scene, native)
    start = runner.initial_fields(first, truth, scene, measurement)
    representation = runner.make_representation(first, scene)
    x0 = representation.initial_parameters(start)
    problems = {}
    for kind in regularizers:
        cfg = reproduce.method_config(size, METHODS[kind], 0, protocol)
        reg = cfg["regularizer"]
        lam = (lams or {}).get(kind, reg["lambda"])
        if isinstance(lam, str):
            raise SystemExit(f"the {protocol} protocol chooses the {kind} weight by the rule "
                             f"{lam!r}; race a fixed one: --lam {kind}=VALUE (e.g. the λ the "
                             "rule chose in the run's lambda_choice.json)")
        problems[METHODS[kind]] = representation.problem(
            measurement.data, regularizer=kind, x0=x0,
            lam=regularizer_weight(cfg, scene, measurement, lam),
            sigma=measurement.sigma if reg["scaling"] == "chi2" else None)

    def mse_t_of_fields(fields):
        return normalized_mse(truth.values, fields)["T"]

    def mse_t(x):
        return mse_t_of_fields(runner.physical_fields(scene, representation.fields(x)))

    print(f"scene: grid {scene.grid.shape}, {scene.n_rays} pixels x {scene.rays_per_pixel} "
          f"sub-rays, {scene.wavenumber.size} -> {scene.out_wavenumber.size} wavenumbers; "
          f"start MSE_T {mse_t(x0):.5f}", flush=True)
    return {"problems": problems, "mse_t": mse_t, "mse_t_of_fields": mse_t_of_fields,
            "iterations": first["solver"]["iterations"],
            "lr": reproduce.SOLVERS["voxel"]["options"]["lr"]}


def warm_up(problem: solvers.Problem) -> None:
    """Evaluate F, a JVP and a VJP at the start once, so that no run pays for compiling them."""
    evaluation = problem.evaluate(problem.x0, jacobians=True)
    evaluation.forward_jacobian(problem.x0)
    evaluation.grad.sum()


def run_race(args, variants: dict) -> dict:
    """Race the chosen variants on each problem; the record that :func:`report` writes, also
    saved to ``race.json`` in ``args.out`` after every run (a killed race leaves what it did)."""
    regularizers = ["tikhonov", "tv"] if args.regularizer == "both" else [args.regularizer]
    began = time.perf_counter()
    built = build_problems(args.size, args.protocol, regularizers, args.lam)
    n_ref = args.reference_iterations or built["iterations"]
    reference = f"adam lr={built['lr']:g} (reference)"
    recorded = None
    if args.reference_run:
        name, recorded = recorded_reference(args.reference_run, regularizers[0],
                                            *built["problems"].values(),
                                            built["mse_t_of_fields"])
        reference, n_ref = f"{name} (reference)", recorded["rows"][-1]["iteration"]
    record = {"size": args.size, "protocol": args.protocol, "clock": args.clock,
              "budget_s": args.budget_s, "reference": reference, "reference_iterations": n_ref,
              "seconds": 0.0, "problems": {}}
    args.out.mkdir(parents=True, exist_ok=True)
    for label, problem in built["problems"].items():
        warm_up(problem)
        print(f"{label}: {problem}", flush=True)
        runs = {reference: recorded or race(problem, built["mse_t"], "adam",
                                            {"lr": built["lr"]}, n_ref, args.clock, None)}
        record["problems"][label] = {"lambda": problem.lam, "runs": runs,
                                     "levels": reference_levels(runs[reference]["rows"], n_ref)}
        for variant, (name, options) in variants.items():
            record["seconds"] = time.perf_counter() - began
            (args.out / "race.json").write_text(json.dumps(
                record, indent=1, default=lambda value: value.tolist()))  # NumPy values
            runs[variant] = run = race(problem, built["mse_t"], name, options, 10**6,
                                       args.clock, args.budget_s)
            print(f"  {variant}: " + (f"skipped ({run['skipped']})" if "skipped" in run else
                                      f"{run['rows'][-1]['iteration']} iterations, "
                                      f"{run['seconds']['cpu']:.1f} CPU s, "
                                      f"{run['seconds']['wall']:.1f} wall s ({run['stop']})"),
                  flush=True)
    record["seconds"] = time.perf_counter() - began
    return record


def main():
    parser = argparse.ArgumentParser(prog="solver_race", description=__doc__.splitlines()[0])
    parser.add_argument("--size", choices=("quick", "paper"), default="quick")
    parser.add_argument("--protocol", choices=("paper", "honest"), default="paper")
    parser.add_argument("--regularizer", choices=("tikhonov", "tv", "both"), default="both")
    parser.add_argument("--solvers", nargs="+", default=None,
                        help="variant names or registered solver names (default: all)")
    parser.add_argument("--budget-s", type=float, default=90.0,
                        help="seconds of --clock per variant (the reference runs its "
                             "iterations)")
    parser.add_argument("--clock", choices=tuple(CLOCKS), default="cpu",
                        help="the clock of budgets, tables and plot: CPU seconds of the "
                             "process (default; robust to other jobs) or wall seconds")
    parser.add_argument("--reference-iterations", type=int, default=None,
                        help="iterations of the reference Adam (default: the preset's)")
    parser.add_argument("--reference-run", type=Path, default=None, metavar="DIR",
                        help="take the reference from this finished `invflame reproduce` run "
                             "of the raced method (one --regularizer, --clock wall) instead of "
                             "running it")
    parser.add_argument("--merge", type=Path, nargs="+", default=None, metavar="DIR",
                        help="race nothing: report the races in these --out folders as one "
                             "(e.g. one regularizer each, run side by side)")
    parser.add_argument("--lam", nargs="+", default=[], metavar="KIND=VALUE",
                        help="fixed λ per regularizer (e.g. tv=1e4), replacing the protocol's; "
                             "needed for the honest protocol, whose voxel rows choose λ by a "
                             "rule")
    parser.add_argument("--out", type=Path, default=Path("results/solver_race"))
    args = parser.parse_args()
    try:
        args.lam = {kind: float(value) for kind, value in
                    (item.split("=", 1) for item in args.lam)}
    except ValueError:
        parser.error(f"--lam takes KIND=VALUE pairs with KIND tikhonov or tv, got {args.lam}")
    if set(args.lam) - {"tikhonov", "tv"}:
        parser.error(f"--lam: unknown regularizer in {sorted(args.lam)}; use tikhonov or tv")
    if args.reference_run and (args.regularizer == "both" or args.clock != "wall"
                               or args.reference_iterations):
        parser.error("--reference-run records one method's run in wall time: give one "
                     "--regularizer, --clock wall and no --reference-iterations")
    if args.merge:
        report(merged([json.loads((d / "race.json").read_text()) for d in args.merge]),
               args.out)
        return

    variants = dict(VARIANTS)
    for name in solvers.available():
        if all(solver != name for solver, _ in variants.values()):
            variants[name] = (name, {})
    chosen = args.solvers or list(variants)
    unknown = [c for c in chosen if c not in variants and c not in solvers.available()]
    if unknown:
        parser.error(f"unknown variants {unknown}; choose from {', '.join(variants)}")
    report(run_race(args, {v: spec for v, spec in variants.items()
                           if v in chosen or spec[0] in chosen}), args.out)


if __name__ == "__main__":
    main()
