"""The study's comparison: voxel grid vs neural field, each with no regularizer, Tikhonov or TV.

:func:`reproduce` runs the six methods of Table 1 of Tricard, Chen & Deng, "3-D
Representations for Hyperspectral Flame Tomography" (ESSCI Spring Technical Meeting 2026) on a
preset, under one of two protocols, and writes, into one folder, a run folder per method
(:func:`invflame.experiments.runner.run_experiment`), the table with the no-data baselines and
the paper's figures beside ours (``table.md``, ``table.csv``, ``table.json``), the figures
(``figures.py``) and ``log.txt``.

Protocols
---------
``paper``
    The study's: start from the ground truth + 20 % noise, noise-free data made by the
    reconstruction's own model (one ray per pixel, same grid and line-by-line step), the
    paper's λ = 1e-3 read per pixel, Adam for a fixed number of epochs. The start knows the
    answer: smoothing it with no data at all is a strong baseline (printed beside the table).
``honest``
    What a researcher with real cameras can do (``invflame study``): start from the data
    (band-integrated tomography, :mod:`invflame.experiments.data_start`), data rendered on the
    truth's native grid with more sub-rays and a finer line-by-line step plus FTIR noise
    (:mod:`invflame.experiments.measurement`), λ on the noise-weighted scale, chosen from the
    data for the voxel rows (:data:`HONEST_RULE`) and fixed for the neural ones
    (:data:`HONEST_LAMBDA`), each method run until its objective stops falling
    (:data:`HONEST_SOLVERS`), and the table says how many iterations that took.

Presets
-------
``paper``
    The paper's size: 60³ voxels, four cameras of 32×32 pixels, 650–725 cm⁻¹ at 0.04 cm⁻¹,
    2000 epochs. Hours on a 2-core CPU; meant for a GPU or a cluster.
``quick``
    The same setup, smaller: 30³ voxels, 16×16 pixels, line-by-line step 0.08 cm⁻¹, fewer
    epochs.
"""

from __future__ import annotations

import copy
import time
from functools import partial
from pathlib import Path

from invflame.atomic_files import read_json, write_csv, write_json, write_text
from invflame.experiments import config as configuration
from invflame.experiments.initialization import ambient
from invflame.experiments.machine import in_words
from invflame.experiments.metrics import field_scores, smoothed
from invflame.field import Field

PAPER_TABLE = {
    # method: epoch [ms], memory [MB], MSE_T, MSE_CO2, MSE_H2O (2000 epochs, GPU)
    "VG/NR": (430, 3.0, 0.0295, 0.0436, 0.0416),
    "VG/Tikh.": (432, 3.0, 0.0203, 0.0391, 0.0384),
    "VG/TV": (431, 3.0, 0.0121, 0.0219, 0.0197),
    "NN/NR": (479, 65.0, 0.0571, 0.0871, 0.2569),
    "NN/Tikh.": (489, 66.0, 0.0268, 0.0705, 0.0946),
    "NN/TV": (493, 66.0, 0.0754, 0.1427, 0.4356),
}
"""Table 1 of the study: time per epoch (ms), memory (MB), normalized MSE of T, CO2, H2O."""

METHODS = {
    "VG/NR": ("voxel", "none"),
    "VG/Tikh.": ("voxel", "tikhonov"),
    "VG/TV": ("voxel", "tv"),
    "NN/NR": ("neural-field", "none"),
    "NN/Tikh.": ("neural-field", "tikhonov"),
    "NN/TV": ("neural-field", "tv"),
}
"""Method label → (representation kind, regularizer kind)."""

SOLVERS = {
    "voxel": {"name": "adam", "options": {"lr": 0.01}},
    "neural-field": {"name": "adam", "options": {"lr": 1e-3}},
}
"""The optimizer of each representation under the paper's protocol (it trains both with Adam
for a fixed number of epochs)."""

HONEST_SOLVERS = {
    "voxel": {"name": "lbfgs", "options": {"rtol_loss": 1e-3, "loss_window": 10}},
    "neural-field": {"name": "adam", "options": {"lr": 1e-3, "rtol_loss": 1e-3, "loss_window": 20}},
}
"""The optimizer of each representation under the honest protocol, with its convergence rule
(a plateau, not a fixed budget). Voxels: L-BFGS-B (a deterministic problem: curvature pays),
stopped when the objective falls by less than 0.1 % over 10 iterations; the network: Adam on
pixel batches, as the paper trains it, stopped when it falls by less than 0.1 % over 20
iterations (pixel batches)."""

HONEST_LAMBDA = {"none": 0.0, "tikhonov": 1.0, "tv": 30.0}
r"""Fixed λ of the honest protocol's neural rows per regularizer, on the noise-weighted scale
(:math:`\chi^2/M + \lambda\Phi`), chosen on the synthetic plume, never on the pool fire: TV's
is the best of a voxel sweep over 3, 10, 30, 100 at the quick size (``docs/honest.md``);
Tikhonov's makes :math:`\lambda\Phi` of the plume's true fields (Φ ≈ 13 m⁻², against
0.62 m⁻¹ for TV) of the same order as TV's. The voxel rows choose λ from the data instead
(:data:`HONEST_RULE`); a network would be trained once per trial λ, which the quick preset
cannot afford."""

HONEST_RULE = {"lambda": "discrepancy", "tau": "model-error"}
"""How the honest protocol's regularized voxel rows choose λ: the discrepancy principle with
τ = 1 + the model error of prior flames (:mod:`invflame.experiments.model_error`), which needs
no truth."""

HONEST_LAMBDA_RANGE = {"tikhonov": [0.1, 1e4], "tv": [1.0, 1e5]}
"""The range (1/Φ) in which :data:`HONEST_RULE` searches, per regularizer: from over-smoothing
down to below the fixed λ of :data:`HONEST_LAMBDA`, ten-fold steps, so that a ladder of at
most six solves brackets the choice."""

PROTOCOLS = {
    "paper": {"init": {"kind": "noisy-truth", "noise": 0.2}, "rig": {"rays_per_pixel": 1},
              "data": {"inverse_crime": True}, "noise": {"kind": "none"}},
    "honest": {"init": {"kind": "band-tomography"}, "data": {"inverse_crime": False},
               "noise": {"kind": "nesr"}},
}
"""Configuration sections that make each protocol (see the module docstring)."""

PRESETS = {
    "paper": {"truth": {"grid": 60}, "rig": {"pixels": 32}, "spectrum": {"step": 0.04},
              "epochs": 2000, "honest_epochs": {"voxel": 2000, "neural-field": 2000}},
    "quick": {"truth": {"grid": 30}, "rig": {"pixels": 16}, "spectrum": {"step": 0.08},
              "epochs": 200, "honest_epochs": {"voxel": 100, "neural-field": 30}},
}
"""Problem sizes. ``epochs``: the paper protocol's fixed number of epochs (passes over all
pixels); ``honest_epochs``: the honest protocol's limits per representation, which its
convergence rule may undercut. On a 2-core CPU an epoch of the neural field at the quick size
takes several seconds, so the quick preset stops it early; the table says whether each method
converged before its limit."""


def method_config(preset: str, method: str, seed: int = 0, protocol: str = "paper",
                  truth: str = "poolfire") -> dict:
    """The validated configuration of one method of the comparison.

    Parameters
    ----------
    preset : str
        A key of :data:`PRESETS`.
    method : str
        A key of :data:`METHODS`.
    seed : int, optional
        Seed of the noise, the start and stochastic solvers.
    protocol : {"paper", "honest"}, optional
        See the module docstring.
    truth : str, optional
        ``truth.source``: "poolfire", "synthetic" or a field ``.npz``.
    """
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; choose one of {', '.join(PRESETS)}")
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if protocol not in PROTOCOLS:
        raise ValueError(f"unknown protocol {protocol!r}; choose one of {', '.join(PROTOCOLS)}")
    representation, regularizer = METHODS[method]
    settings = copy.deepcopy(PRESETS[preset])
    epochs = settings.pop("epochs")
    honest_epochs = settings.pop("honest_epochs", {})
    settings.update(copy.deepcopy(PROTOCOLS[protocol]))
    settings["truth"]["source"] = str(truth)
    if protocol == "paper":
        solver = SOLVERS[representation]
        weight = {"lambda": 1e-3, "scaling": "paper"}
    else:
        solver = HONEST_SOLVERS[representation]
        weight = {"lambda": HONEST_LAMBDA[regularizer], "scaling": "chi2"}
        if representation == "voxel" and regularizer != "none":
            weight.update(HONEST_RULE, lambda_range=HONEST_LAMBDA_RANGE[regularizer])
        epochs = honest_epochs.get(representation, epochs)
    settings.update({
        "seed": seed,
        "representation": {"kind": representation},
        "regularizer": {"kind": regularizer, **weight},
        "solver": {"name": solver["name"], "iterations": epochs,
                   "options": dict(solver["options"])},
    })
    return configuration.validate(settings)


def folder_name(method: str) -> str:
    """File-system name of a method's run folder (``VG/Tikh.`` → ``VG-Tikh``)."""
    return method.replace("/", "-").rstrip(".")


def _scores_row(label: str, scores: dict, kind: str) -> dict:
    mse, flame = scores["mse"], scores["mse_flame"]
    return {"method": label, "kind": kind, "MSE_T": mse["T"], "MSE_CO2": mse["CO2"],
            "MSE_H2O": mse["H2O"], "MSE_T_flame": flame.get("T"),
            "hot_volume_ratio": scores["hot_volume_ratio"]}


def table_rows(summaries: dict[str, dict]) -> list[dict]:
    """One row per method: our figures and the paper's, side by side."""
    rows = []
    for method, summary in summaries.items():
        paper = PAPER_TABLE[method]
        seconds = summary["seconds_per_epoch"]
        start_t = summary["mse_initial"]["T"]
        rows.append({
            **_scores_row(method, summary, "method"),
            "lambda": summary["lambda"],
            "lambda_from_data": isinstance(summary["config"]["regularizer"]["lambda"], str),
            "iterations": summary["iterations"],
            "converged": summary["converged"],
            "chi2_per_measurement": summary["chi2_per_measurement"]["final"],
            "MSE_T_initial": start_t,
            "improvement_T": start_t / summary["mse"]["T"] if summary["mse"]["T"] > 0 else None,
            "epoch_ms": None if seconds is None else round(1e3 * seconds, 1),
            "machine": in_words(summary.get("machine")),
            "param_mem_MB": round(summary["parameter_memory_mb"], 2),
            "paper_epoch_ms": paper[0],
            "paper_mem_MB": paper[1],
            "paper_MSE_T": paper[2],
            "paper_MSE_CO2": paper[3],
            "paper_MSE_H2O": paper[4],
        })
    return rows


def baseline_rows(truth: Field, start: Field, protocol: str, air) -> list[dict]:
    """Rows that fit no data: the start, the start smoothed (Gaussian, σ = 1 voxel), ambient air.

    Under the honest protocol the start is made from the data, so it and its smoothing are
    labelled ``start`` (they use the data) and only ambient air is a no-data baseline; under the
    paper's, the start is the truth plus noise, and all three fit no data. ``air``: the
    ambient air, T in K and mole fractions of CO2, H2O, CH4.
    """
    kind = "uses the data" if protocol == "honest" else "no data; knows the truth"
    fields = {"start": (start.values, kind),
              "start smoothed (σ = 1 voxel)": (smoothed(start.values), kind),
              "ambient air (flat)": (ambient(truth.grid.shape, air), "no data")}
    return [_scores_row(label, field_scores(truth.values, values), what)
            for label, (values, what) in fields.items()]


def _cell(value, fmt: str = ".4f") -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "NO"
    return f"{value:{fmt}}"


def markdown_table(rows: list[dict], baselines: list[dict], preset: str, protocol: str,
                   truth: str, described: dict) -> str:
    """The comparison and its baselines as Markdown, with the truth and what made the data."""
    lines = [
        f"Preset `{preset}`, protocol `{protocol}`, truth `{truth}`.",
        "",
        *(f"- {what}: {how}" for what, how in described.items() if what != "lambda"),
        "",
        "λ: the regularizer's weight (on the scale of the run's `regularizer.scaling`; "
        "marked * where the run chose it from the data by the discrepancy principle, its "
        "trials in the run's `lambda_choice.json`). "
        "MSE over voxel centres, each field min–max normalized by the ground truth's range; "
        "MSE_T flame: the same over the voxels above 500 K in the truth or the estimate; hot "
        "vol.: volume above 500 K over the truth's (near 0: the flame was lost); gain: MSE_T "
        "of the method's own start over its final MSE_T (> 1: the data improved it); χ²/M: "
        "noise-weighted misfit per measured value (≈ 1 fits to the noise). Paper: Table 1 "
        "(60³, 4 × 32² px, 2000 epochs, GPU, noisy-truth start).",
        "",
        "| row | λ | iterations | converged | χ²/M | MSE_T | MSE_T flame | MSE_CO2 | MSE_H2O | "
        "hot vol. | start MSE_T | gain | epoch [ms] | paper MSE_T |",
        "|---|---:|---:|:-:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['method']} | {r['lambda']:.3g}{'*' if r['lambda_from_data'] else ''} | "
            f"{r['iterations']} | {_cell(r['converged'])} | "
            f"{_cell(r['chi2_per_measurement'], '.3g')} | {_cell(r['MSE_T'])} | "
            f"{_cell(r['MSE_T_flame'])} | {_cell(r['MSE_CO2'])} | {_cell(r['MSE_H2O'])} | "
            f"{_cell(r['hot_volume_ratio'], '.2f')} | {_cell(r['MSE_T_initial'])} | "
            f"{_cell(r['improvement_T'], '.2f')} | {_cell(r['epoch_ms'], '.0f')} | "
            f"{r['paper_MSE_T']:.4f} |")
    for b in baselines:
        lines.append(
            f"| *{b['method']}* ({b['kind']}) | – | – | – | – | {_cell(b['MSE_T'])} | "
            f"{_cell(b['MSE_T_flame'])} | {_cell(b['MSE_CO2'])} | {_cell(b['MSE_H2O'])} | "
            f"{_cell(b['hot_volume_ratio'], '.2f')} | – | – | – | – |")
    machines = {}
    for r in rows:
        machines.setdefault(r["machine"], []).append(r["method"])
    lines += ["", "Epoch times measured on:",
              *(f"- {', '.join(methods)}: {machine}" for machine, methods in machines.items())]
    return "\n".join(lines) + "\n"


def findings(rows: list[dict], baselines: list[dict]) -> str:
    """What this run shows, each statement checked on its own numbers."""
    by = {r["method"]: r for r in rows}
    checks = []

    def check(statement, holds):
        checks.append(f"- {statement}: {'yes' if holds else 'NO'}")

    def t(method):
        return by[method]["MSE_T"]

    no_data = [b for b in baselines if b["kind"].startswith("no data")]
    if no_data:
        best = min(no_data, key=lambda b: b["MSE_T"])
        for r in rows:
            ratio = best["MSE_T"] / r["MSE_T"]
            check(f"{r['method']} beats the best no-data baseline ({best['method']}, MSE_T "
                  f"{best['MSE_T']:.4f}) by {ratio:.2f}x", ratio > 1)
    if all(m in by for m in ("VG/NR", "VG/TV", "VG/Tikh.")):
        check("voxels: TV gives the lowest temperature error of the three (paper: yes)",
              t("VG/TV") < min(t("VG/NR"), t("VG/Tikh.")))
        check("voxels: Tikhonov improves on no regularizer (paper: yes)",
              t("VG/Tikh.") < t("VG/NR"))
    if all(m in by for m in ("NN/NR", "NN/Tikh.")):
        check("neural field: Tikhonov improves on no regularizer (paper: yes)",
              t("NN/Tikh.") < t("NN/NR"))
    if all(m in by for m in ("NN/TV", "NN/Tikh.")):
        check("neural field: TV does worse than Tikhonov (paper: yes)", t("NN/TV") > t("NN/Tikh."))
    voxel = [m for m in by if m.startswith("VG")]
    neural = [m for m in by if m.startswith("NN")]
    if voxel and neural:
        check("the best voxel method beats the best neural one (temperature; paper: yes)",
              min(map(t, voxel)) < min(map(t, neural)))
    lost = [m for m, r in by.items()
            if r["hot_volume_ratio"] is not None and not 0.7 <= r["hot_volume_ratio"] <= 1.4]
    check("every reconstruction keeps the flame (hot volume within 0.7-1.4x of the truth's)"
          + (f"; lost or distorted: {', '.join(lost)}" if lost else ""), not lost)
    worse = [m for m, r in by.items() if r["MSE_T"] >= r["MSE_T_initial"]]
    check("every method improves on its own start (temperature)"
          + (f"; worse than their start: {', '.join(worse)}" if worse else ""), not worse)
    stopped = [m for m, r in by.items() if not r["converged"]]
    check("every method converged before its iteration limit"
          + (f"; stopped by the limit: {', '.join(stopped)}" if stopped else ""), not stopped)
    return "Checked on this run:\n" + "\n".join(checks) + "\n"


def reproduce(preset: str = "quick", out_dir="results", resume: bool = False,
              progress: bool = True, methods=None, seed: int = 0, run=None,
              protocol: str = "paper", truth: str = "poolfire") -> list[dict]:
    """Run the comparison and write the table, baselines, figures and logs into ``out_dir``.

    Parameters
    ----------
    preset : {"quick", "paper"}
        Problem size (module docstring).
    out_dir : str or Path
        Output folder.
    resume : bool
        Reuse finished methods and continue interrupted ones from their checkpoints.
    progress : bool
        Progress bars and log echo.
    methods : sequence of str, optional
        Subset of :data:`METHODS` (default all six).
    seed : int
        Seed of the noise, the start and stochastic solvers.
    run : callable, optional
        ``run(cfg, folder, resume, progress) -> summary``; default
        :func:`invflame.experiments.runner.run_experiment` with one measurement shared by the
        methods (a cluster runner may be given).
    protocol : {"paper", "honest"}
        See the module docstring.
    truth : str
        Ground truth: "poolfire" (default), "synthetic" or a field ``.npz`` file.

    Returns
    -------
    list of dict
        The table rows (also written as ``table.csv``/``.json``/``.md``).
    """
    from invflame.experiments.figures import comparison_figures
    from invflame.experiments.inputs import absorption_table, load_truth
    from invflame.experiments.resume import check_resumable
    from invflame.experiments.runner import build_scene, initial_fields, measure, run_experiment

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    methods = list(METHODS) if methods is None else list(methods)
    configs = {m: method_config(preset, m, seed, protocol, truth) for m in methods}
    first = next(iter(configs.values()))
    begin = time.perf_counter()
    pending = [m for m in methods if not (resume and (out / folder_name(m) / "summary.json")
                                          .is_file())]
    if run is None and pending:  # one measurement and one start shared by the methods
        table = absorption_table(first)
        scene, native = build_scene(first, table), load_truth(first)
        measurement = measure(first, scene, native)
        start = initial_fields(first, native.resample(scene.grid), scene, measurement)
        run = partial(run_experiment, table=table, measurement=measurement, start=start)
    summaries = {}
    for method, cfg in configs.items():
        folder = out / folder_name(method)
        if method not in pending:
            check_resumable(cfg, folder)
            summaries[method] = read_json(folder / "summary.json")
            continue
        summaries[method] = run(cfg, folder, resume, progress)
    rows = table_rows(summaries)
    base = next((m for m in methods if m.startswith("VG")), methods[0])
    truth_field = Field.load(out / folder_name(base) / "truth.npz")
    baselines = baseline_rows(truth_field, Field.load(out / folder_name(base) / "initial.npz"),
                              protocol, first["init"]["ambient"])
    described = summaries[base]["protocol"]
    write_csv(out / "table.csv", rows + baselines)
    write_json(out / "table.json", {"preset": preset, "protocol": protocol, "seed": seed,
                                    "truth": str(truth), "made_by": described, "rows": rows,
                                    "baselines": baselines,
                                    "coverage": summaries[base]["coverage"]})
    text = (markdown_table(rows, baselines, preset, protocol, str(truth), described) + "\n"
            + findings(rows, baselines))
    write_text(out / "table.md", text)
    comparison_figures(out, {m: out / folder_name(m) for m in methods})
    write_text(out / "log.txt", f"preset {preset}, protocol {protocol}, truth {truth}, seed "
               f"{seed}, methods {methods}, {time.perf_counter() - begin:.1f} s\n")
    if progress:
        print(text)
    return rows
