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
the same method instead (:func:`recorded_reference`): its objective and wall time per iteration
from ``history.csv``, its MSE_T at the start and the end (``reconstruction.npz``, scored against
the race's truth) and none in between. The race then runs on wall time (``--clock wall``, on an
idle machine), and a run whose start objective differs from the race problem's is refused.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import tomllib
from pathlib import Path

import matplotlib
import matplotlib.lines
import matplotlib.ticker
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from timing import CLOCKS  # noqa: E402

import operators  # noqa: E402
import solvers  # noqa: E402
from invflame.experiments import reproduce, runner  # noqa: E402
from invflame.experiments.figures import read_history  # noqa: E402
from invflame.experiments.metrics import normalized_mse  # noqa: E402
from invflame.experiments.regularization import regularizer_weight  # noqa: E402
from invflame.field import Field  # noqa: E402

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
FRACTIONS = (0.25, 0.5, 1.0)
COUNTS = ("forward", "jvp", "vjp")
GRACE = 1.5  # a run still inside an iteration at GRACE x its budget is cut off there
XLABELS = {"cpu": "CPU time of the process [s]", "wall": "wall time [s]"}


class OutOfTime(RuntimeError):
    """A counted evaluation asked for after the run's deadline."""


class CountingOperator(operators.Operator):
    """An operator whose evaluations are counted: values F(x), JVPs and VJPs, also those made
    through the Jacobians it returns.

    Parameters
    ----------
    op : operators.Operator
        The operator counted (same shapes, dtype and units).

    Attributes
    ----------
    counts : dict
        ``forward``, ``jvp`` and ``vjp``: evaluations so far.
    clock, deadline : callable, float or None
        A clock (:data:`CLOCKS`) and a time of it; an evaluation asked for later raises
        :class:`OutOfTime` and sets ``expired``.
    """

    def __init__(self, op: operators.Operator):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=op.name)
        self.op = op
        self.counts = dict.fromkeys(COUNTS, 0)
        self.clock, self.deadline = time.perf_counter, None
        self.expired = False

    def _count(self, kind: str) -> None:
        if self.deadline is not None and self.clock() > self.deadline:
            self.expired = True
            raise OutOfTime(f"cut off inside an iteration at {GRACE:g} x the budget")
        self.counts[kind] += 1

    def _forward(self, x):
        self._count("forward")
        return self.op(x)

    def _jvp(self, x, v):
        self._count("jvp")
        return self.op.jvp(x, v)

    def _vjp(self, x, w):
        self._count("vjp")
        return self.op.vjp(x, w)

    def linearize(self, x) -> operators.Jacobian:
        """The inner operator's Jacobian at ``x``, its products counted."""
        self._count("forward")
        jacobian = self.op.linearize(x)

        def jvp(v):
            self._count("jvp")
            return jacobian(v)

        def vjp(w):
            self._count("vjp")
            return jacobian.adjoint(w)

        return operators.Jacobian(self, x, jacobian.value, jvp=jvp, vjp=vjp)


class Trace(solvers.Callback):
    """One row per iteration (and the start): CPU and wall time since the trace began (before
    the run's first evaluation) without this callback's own time, evaluation counts, objective
    and MSE_T; asks the run to stop once ``budget`` seconds of ``clock`` are spent.

    Parameters
    ----------
    counter : CountingOperator
        The problem's counted forward operator.
    mse_t : callable
        Parameters → normalized MSE of the temperature against the truth.
    clock : {"cpu", "wall"}
        The clock of the budget (:data:`CLOCKS`).
    budget : float or None
        Seconds of ``clock``; None for no budget.
    """

    def __init__(self, counter: CountingOperator, mse_t, clock: str, budget: float | None):
        self.counter, self.mse_t, self.clock, self.budget = counter, mse_t, clock, budget
        self.rows: list[dict] = []
        self.overhead = dict.fromkeys(CLOCKS, 0.0)
        self.began = {key: read() for key, read in CLOCKS.items()}

    def elapsed(self, key: str) -> float:
        """Seconds of clock ``key`` spent by the run, this callback's own time excluded."""
        return CLOCKS[key]() - self.began[key] - self.overhead[key]

    def on_start(self, run):
        self._record(run)

    def __call__(self, run):
        self._record(run)
        return self.budget is not None and self.rows[-1][self.clock] >= self.budget

    def _record(self, run) -> None:
        now = {key: read() for key, read in CLOCKS.items()}
        self.rows.append({"iteration": run.iteration,
                          **{key: now[key] - self.began[key] - self.overhead[key]
                             for key in CLOCKS},
                          **self.counter.counts, "loss": run.current.loss,
                          "mse_t": self.mse_t(run.x)})
        for key, read in CLOCKS.items():
            self.overhead[key] += read() - now[key]


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


def counted(problem: solvers.Problem) -> tuple[solvers.Problem, CountingOperator]:
    """A copy of ``problem`` whose forward operator counts its evaluations."""
    counter = CountingOperator(problem.forward)
    return solvers.Problem(counter, problem.data, regularizer=problem.regularizer,
                           lam=problem.lam, lower=problem.lower, upper=problem.upper,
                           x0=problem.x0, name=problem.name,
                           metadata=problem.metadata), counter


def race(problem, mse_t, name: str, options: dict, max_iter: int, clock: str,
         budget: float | None) -> dict:
    """One solver run on a counted copy of ``problem``; its trace, or why it was skipped."""
    solver = solvers.get(name)(max_iter=max_iter, **options)
    race_problem, counter = counted(problem)
    try:
        solver.check(race_problem)
    except solvers.UnsupportedProblemError as refusal:
        return {"skipped": str(refusal)}
    trace = Trace(counter, mse_t, clock, budget)
    if budget is not None:
        counter.clock = CLOCKS[clock]
        counter.deadline = counter.clock() + GRACE * budget
    try:
        stop = solver.run(race_problem, callbacks=[trace]).stop_reason
    except Exception as error:  # jaxopt's host callback wraps OutOfTime in an error of its own
        stop = (f"cut off: inside an iteration at {GRACE:g} x the budget" if counter.expired
                else f"failed: {type(error).__name__}: {str(error).strip().splitlines()[-1]}")
    if stop.startswith("callback"):
        stop = f"budget: {budget:g} s of {clock} time spent"
    return {"solver": name, "options": options, "stop": stop, "rows": trace.rows,
            "seconds": {key: trace.elapsed(key) for key in CLOCKS}}


def recorded_reference(run_dir: Path, kind: str, problem: solvers.Problem,
                       mse_t_of_fields) -> tuple[str, dict]:
    """The reference from a finished ``invflame reproduce`` run of the race's problem.

    Parameters
    ----------
    run_dir : Path
        The run's folder (``config.toml``, ``history.csv``, ``summary.json``,
        ``reconstruction.npz``), e.g. ``results/paper/VG-Tikh``.
    kind : {"tikhonov", "tv"}
        The race problem's regularizer, which the run's must be.
    problem : solvers.Problem
        The race problem; the run's objective at its start must equal this problem's at ``x0``
        within 1e-4 relative, or the run solved another problem.
    mse_t_of_fields : callable
        Physical fields → MSE_T against the race's truth.

    Returns
    -------
    name : str
        The reference's name, from the run's solver and learning rate.
    run : dict
        As :func:`race` returns: one row per recorded iteration, wall seconds since the first
        iterate was evaluated (the run's compile excluded), F and VJP counts of one each per
        iterate (a gradient step's), the objective, and MSE_T at the start and the end only
        (NaN between: the run did not record it); CPU seconds are NaN.
    """
    paths = {name: run_dir / name for name in ("config.toml", "history.csv", "summary.json",
                                                "initial.npz", "reconstruction.npz")}
    missing = [name for name, path in paths.items() if not path.is_file()]
    if missing:
        raise SystemExit(f"--reference-run {run_dir}: no finished run there ({', '.join(missing)} "
                         "missing); finish it with `invflame reproduce ... --resume` first")
    cfg = tomllib.loads(paths["config.toml"].read_text())
    if cfg["regularizer"]["kind"] != kind:
        raise SystemExit(f"--reference-run {run_dir} regularizes with "
                         f"{cfg['regularizer']['kind']!r}, the race with {kind!r}: pass the run "
                         "of the raced method (--regularizer)")
    history = read_history(paths["history.csv"])
    start = problem.evaluate(problem.x0).loss
    if abs(history["loss"][0] - start) > 1e-4 * abs(start):
        raise SystemExit(f"--reference-run {run_dir} starts at objective "
                         f"{history['loss'][0]:.6g}, the race problem at {start:.6g}: the run "
                         "solved another problem (size, protocol, seed or λ differ)")
    mse_t = np.full(history["loss"].size, math.nan)
    mse_t[[0, -1]] = [mse_t_of_fields(Field.load(paths[name]).values)
                      for name in ("initial.npz", "reconstruction.npz")]
    rows = [{"iteration": int(k), "cpu": math.nan, "wall": float(t - history["time"][0]),
             "forward": int(k) + 1, "jvp": 0, "vjp": int(k) + 1, "loss": float(loss),
             "mse_t": float(error)}
            for k, t, loss, error in zip(np.rint(history["iteration"]), history["time"],
                                         history["loss"], mse_t, strict=True)]
    summary = json.loads(paths["summary.json"].read_text())
    options = cfg["solver"].get("options", {})
    name = (f"{cfg['solver']['name']}" + (f" lr={options['lr']:g}" if "lr" in options else "")
            + " (recorded)")
    return name, {"solver": cfg["solver"]["name"], "options": options,
                  "stop": summary["stop_reason"], "rows": rows,
                  "seconds": {"cpu": math.nan, "wall": rows[-1]["wall"]}}


def first_reach(rows: list[dict], key: str, level: float) -> dict | None:
    """The first row whose ``key`` is at most ``level``, or None (a NaN, not recorded, never
    is)."""
    return next((row for row in rows if row[key] <= level), None)


def reference_levels(rows: list[dict], n_iter: int) -> dict:
    """The reference's objective and MSE_T after each fraction of its ``n_iter`` iterations."""
    levels = {}
    for fraction in FRACTIONS:
        k = min(round(fraction * n_iter), rows[-1]["iteration"])
        row = next(r for r in rows if r["iteration"] == k)
        levels[f"{fraction:.0%}"] = {"iteration": k, "loss": row["loss"], "mse_t": row["mse_t"]}
    return levels


def _number(value: float, spec: str) -> str:
    return "–" if math.isnan(value) else format(value, spec)


def _cell(row: dict | None, clock: str) -> str:
    if row is None:
        return "–"
    return f"{row[clock]:.1f} s · {row['forward']}/{row['jvp']}/{row['vjp']}"


def markdown(label: str, runs: dict, levels: dict, clock: str) -> list[str]:
    """One problem's table: per variant, time and evaluations to each reference level."""
    heads = [f"{key} ≤ ref@{fraction}" for key in ("objective", "MSE_T") for fraction in levels]
    lines = [f"**{label}**: reference levels "
             + "; ".join(f"@{f} (iteration {v['iteration']}): objective {v['loss']:.4g}, "
                         f"MSE_T {_number(v['mse_t'], '.5f')}" for f, v in levels.items()),
             "",
             "| variant | iterations | F/JVP/VJP | CPU / wall [s] | final objective | "
             "final MSE_T | " + " | ".join(heads) + " | stop |",
             "|---|---:|---:|---:|---:|---:|" + "---:|" * len(heads) + "---|"]
    for variant, run in runs.items():
        if "skipped" in run:
            continue
        rows, last = run["rows"], run["rows"][-1]
        cells = [_cell(first_reach(rows, key, level[key]), clock)
                 if not math.isnan(level[key]) else "not recorded"
                 for key in ("loss", "mse_t") for level in levels.values()]
        seconds = run["seconds"]
        lines.append(f"| {variant} | {last['iteration']} | {last['forward']}/{last['jvp']}/"
                     f"{last['vjp']} | {_number(seconds['cpu'], '.0f')} / "
                     f"{seconds['wall']:.0f} | "
                     f"{last['loss']:.4g} | {last['mse_t']:.5f} | " + " | ".join(cells)
                     + f" | {run['stop'].split(':')[0]} |")
    lines += ["", *(f"- {variant} skipped: {run['skipped']}" for variant, run in runs.items()
                    if "skipped" in run),
              *(f"- {variant} failed after {run['rows'][-1]['iteration']} iterations: "
                f"{run['stop'].strip().splitlines()[-1]}" for variant, run in runs.items()
                if run.get("stop", "").startswith("failed"))]
    return lines


def verdict(label: str, runs: dict, reference: str, levels: dict, clock: str) -> list[str]:
    """Which variant reaches the reference's final MSE_T, and its final objective, first, and
    how much sooner than the reference itself."""
    lines = []
    for key, name in (("mse_t", "MSE_T"), ("loss", "objective")):
        level = levels["100%"][key]
        rows = runs[reference]["rows"]
        own = first_reach(rows, key, level)[clock]
        if any(math.isnan(row[key]) for row in rows):
            ratio_note = (f" (at most: the reference's {name} was recorded only at its start "
                          "and end)")
        else:
            ratio_note = ""
        reached = {variant: first_reach(run["rows"], key, level) for variant, run in runs.items()
                   if "skipped" not in run and variant != reference}
        reached = {variant: row for variant, row in reached.items() if row is not None}
        if not reached:
            lines.append(f"- {label}: no variant reaches the reference's final {name} "
                         f"{level:.4g} (the reference: {own:.1f} s of {clock} time)")
            continue
        winner = min(reached, key=lambda variant: reached[variant][clock])
        time_won = reached[winner][clock]
        ratio = (f"{own / time_won:.1f}x sooner{ratio_note}" if time_won < own
                 else "no sooner")
        lines.append(f"- {label}: {winner} reaches the reference's final {name} {level:.4g} "
                     f"first, in {time_won:.1f} s of {clock} time against the reference's "
                     f"{own:.1f} s ({ratio})")
    return lines


def plot(results: dict, path: Path, protocol: str, reference: str, clock: str) -> None:
    """MSE_T (top) and objective (bottom) against ``clock`` time, one column per problem; a cross
    ends a run that failed or was cut off inside an iteration."""
    variants = list(dict.fromkeys(v for runs in results.values() for v in runs["runs"]))
    colors = dict(zip([v for v in variants if v != reference],
                      plt.get_cmap("tab10").colors, strict=False))
    colors[reference] = "black"
    fig, axes = plt.subplots(2, len(results), figsize=(5.5 * len(results) + 2.4, 8),
                             squeeze=False, sharex="col")
    for column, (label, problem) in enumerate(results.items()):
        for variant, run in problem["runs"].items():
            if "skipped" in run:
                continue
            times = [row[clock] for row in run["rows"]] + [run["seconds"][clock]]
            for row, key in ((0, "mse_t"), (1, "loss")):
                values = [r[key] for r in run["rows"]] + [run["rows"][-1][key]]
                kept = [(t, v) for t, v in zip(times, values, strict=True) if not math.isnan(v)]
                gaps = len(kept) < len(values)  # recorded at the ends only: dashed, big dots
                axes[row, column].plot(*zip(*kept, strict=True), marker="o" if gaps else ".",
                                       ms=6 if gaps else 3, ls="--" if gaps else "-",
                                       color=colors[variant],
                                       lw=2.2 if variant == reference else 1.3)
                if run["stop"].startswith(("failed", "cut off")):
                    axes[row, column].plot(times[-1], values[-1], "x", ms=8, mew=2,
                                           color=colors[variant])
        final = problem["levels"]["100%"]
        for row, key in ((0, "mse_t"), (1, "loss")):
            axis = axes[row, column]
            axis.axhline(final[key], color="grey", ls=":", lw=1.2)
            axis.set_yscale("log")
            axis.yaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%.4g"))
            low, high = axis.get_ylim()
            axis.yaxis.set_minor_formatter(  # label minor ticks only within a decade
                matplotlib.ticker.FormatStrFormatter("%.4g") if high < 10 * low
                else matplotlib.ticker.NullFormatter())
            axis.tick_params(axis="y", which="both", labelsize=8)
            axis.grid(True, which="both", alpha=0.3)
        axes[0, column].set_title(f"{label}, {protocol} protocol")
        axes[0, column].set_ylabel("MSE_T (normalized)")
        axes[1, column].set_ylabel("objective")
        axes[1, column].set_xlabel(XLABELS[clock])
    handles = [matplotlib.lines.Line2D([], [], color=colors[v], lw=2.2 if v == reference else 1.3,
                                       label=v) for v in variants]
    handles += [matplotlib.lines.Line2D([], [], color="grey", ls=":",
                                        label="reference's final level"),
                matplotlib.lines.Line2D([], [], color="grey", marker="x", ls="",
                                        label="failed or cut off")]
    fig.legend(handles=handles, loc="center right", frameon=False, fontsize=9)
    fig.tight_layout(rect=(0, 0, 1 - 2.4 / (5.5 * len(results) + 2.4), 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


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
            (args.out / "race.json").write_text(json.dumps(record, indent=1))
            runs[variant] = run = race(problem, built["mse_t"], name, options, 10**6,
                                       args.clock, args.budget_s)
            print(f"  {variant}: " + (f"skipped ({run['skipped']})" if "skipped" in run else
                                      f"{run['rows'][-1]['iteration']} iterations, "
                                      f"{run['seconds']['cpu']:.1f} CPU s, "
                                      f"{run['seconds']['wall']:.1f} wall s ({run['stop']})"),
                  flush=True)
    record["seconds"] = time.perf_counter() - began
    return record


def merged(records: list[dict]) -> dict:
    """One record of the problems of several races of the same size, protocol and reference."""
    keys = ("size", "protocol", "clock", "budget_s", "reference", "reference_iterations")
    differ = [key for key in keys if len({json.dumps(r[key]) for r in records}) > 1]
    if differ:
        raise SystemExit(f"the races differ in {', '.join(differ)}: merge only like races")
    return {**{key: records[0][key] for key in keys},
            "seconds": sum(r["seconds"] for r in records),
            "problems": {k: v for r in records for k, v in r["problems"].items()}}


def report(record: dict, out: Path) -> None:
    """Print the tables and verdicts and write ``race.md``, ``race.json``, ``race.png``."""
    reference = record["reference"]
    lines = [f"Size `{record['size']}`, protocol `{record['protocol']}`; reference: "
             f"{reference.removesuffix(' (reference)')} for {record['reference_iterations']} "
             f"iterations; every other variant {record['budget_s']:g} s of {record['clock']} "
             f"time (cut off at {GRACE:g}x inside an iteration). Cells: {record['clock']} "
             "time and F/JVP/VJP evaluations when the variant first reaches the reference's "
             "objective or MSE_T after 25/50/100 % of its iterations; –: not within its "
             f"budget. The races took {record['seconds']:.0f} s of wall time in all.", ""]
    for label, problem in record["problems"].items():
        lines += [*markdown(label, problem["runs"], problem["levels"], record["clock"]),
                  *verdict(label, problem["runs"], reference, problem["levels"],
                           record["clock"]), ""]
    text = "\n".join(lines)
    print(text)
    out.mkdir(parents=True, exist_ok=True)
    (out / "race.md").write_text(text)
    (out / "race.json").write_text(json.dumps(record, indent=1))
    plot(record["problems"], out / "race.png", record["protocol"], reference, record["clock"])
    print(f"wrote {out / 'race.md'}, race.json, race.png")


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
