"""The solver race's report: per problem a table of the time and evaluations each variant needs
to reach the reference's levels, the verdicts, and the figure of MSE_T and objective against
time (:func:`report`); :func:`merged` joins races run side by side."""

from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib
import matplotlib.lines
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from solver_race_reference import first_reach  # noqa: E402
from solver_race_runs import GRACE  # noqa: E402

XLABELS = {"cpu": "CPU time of the process [s]", "wall": "wall time [s]"}


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
