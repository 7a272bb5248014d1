"""The comparison's table: one row per method beside the paper's Table 1, the baselines that
fit no data, the table as Markdown, and the statements checked on its own numbers."""

from __future__ import annotations

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

STOP_RULES = {"misfit_target": "χ²/M level", "rtol_loss": "plateau", "rtol_x": "step",
              "gtol": "gradient", "converged": "solver's test", "scipy L-BFGS-B": "SciPy's test",
              "max_iter": "limit", "time_budget": "time budget", "diverged": "diverged",
              "non-finite": "non-finite"}
"""The table's name of each rule a run's ``stop_reason`` begins with
(:mod:`solvers.stopping`, :data:`solvers.history.CONVERGED`)."""


def stopped_by(stop_reason: str | None) -> str:
    """The table's name of the rule that ended a run (``stop_reason`` of its summary; "not
    recorded" for None, the reason's first words for a rule not in :data:`STOP_RULES`)."""
    if stop_reason is None:
        return "not recorded"
    return STOP_RULES.get(stop_reason.split(":")[0], stop_reason.split(":")[0])


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
            "stopped_by": stopped_by(summary.get("stop_reason")),
            "chi2_per_measurement": summary["chi2_per_measurement"]["final"],
            "MSE_T_initial": start_t,
            "MSE_CO2_initial": summary["mse_initial"]["CO2"],
            "MSE_H2O_initial": summary["mse_initial"]["H2O"],
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


def baseline_rows(truth: Field, start: Field, protocol: str, air,
                  uncalibrated: Field | None = None) -> list[dict]:
    """Rows that fit no data: the start, the start smoothed (Gaussian, σ = 1 voxel), ambient air.

    Under the honest protocol the start is made from the data, so it and its smoothing are
    labelled ``start`` (they use the data) and only ambient air is a no-data baseline; under the
    paper's, the start is the truth plus noise, and all three fit no data. ``air``: the
    ambient air, T in K and mole fractions of CO2, H2O, CH4. ``uncalibrated``: the band
    tomography before its two numbers were fitted to the spectra, a row of its own.
    """
    kind = "uses the data" if protocol == "honest" else "no data; knows the truth"
    fields = {"start": (start.values, kind),
              "start smoothed (σ = 1 voxel)": (smoothed(start.values), kind)}
    if uncalibrated is not None:
        fields["band tomography before calibration"] = (uncalibrated.values, kind)
    fields["ambient air (flat)"] = (ambient(truth.grid.shape, air), "no data")
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
        "noise-weighted misfit per measured value (≈ 1 fits to the noise); stopped by: the "
        "rule that ended the solve (χ²/M level: `solver.stop_chi2`; plateau: the objective's "
        "relative fall over `loss_window` iterations below `rtol_loss`; limit: "
        "`solver.iterations`). Paper: Table 1 "
        "(60³, 4 × 32² px, 2000 epochs, GPU, noisy-truth start).",
        "",
        "| row | λ | iterations | stopped by | χ²/M | MSE_T | MSE_T flame | MSE_CO2 | MSE_H2O | "
        "hot vol. | start MSE_T | gain | epoch [ms] | paper MSE_T |",
        "|---|---:|---:|:-:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['method']} | {r['lambda']:.3g}{'*' if r['lambda_from_data'] else ''} | "
            f"{r['iterations']} | {r['stopped_by']} | "
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
    check("every method stopped by a tolerance before its iteration limit"
          + (f"; stopped by the limit: {', '.join(stopped)}" if stopped else ""), not stopped)
    return "Checked on this run:\n" + "\n".join(checks) + "\n"
