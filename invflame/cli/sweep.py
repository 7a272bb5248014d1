"""``invflame sweep``: one configuration, a grid of parameter values, one run per combination.

``invflame sweep base.toml --param regularizer.lambda=1e-4,1e-3,1e-2 --param
solver.name=adam,gd --out DIR`` runs every combination (here 3 × 2) as an independent
reconstruction on a Dask cluster (:mod:`invflame.experiments.cluster`) and writes into DIR

``NNN_key=value_...``  one run folder per combination (as ``invflame run`` writes)
``summary.csv``        one row per combination: its values, status, metrics, error if it failed
``summary.md``         the same as a Markdown table
``sweep.json``         the parameters swept and the rows
"""

from __future__ import annotations

import argparse
import copy
import itertools
import math
import sys
import tomllib
from pathlib import Path

from invflame.cli import arguments
from invflame.cli.experiment import CONFIG_HELP
from invflame.cli.reproduce import add_cluster_arguments


def add_parser(subparsers) -> None:
    """Register ``invflame sweep``."""
    parser = subparsers.add_parser(
        "sweep", help="run a configuration over a grid of parameter values",
        description="Run one reconstruction per combination of the --param values (their "
        "Cartesian product), in parallel on a Dask cluster, and write a run folder per "
        "combination and a summary table (summary.csv, summary.md) of their metrics into "
        "--out. A failed run is retried (--retries), reported, and listed as failed; the "
        "others keep their results. Exit status 1 if any run failed.")
    parser.add_argument("config", type=Path, help=CONFIG_HELP)
    parser.add_argument("--param", action="append", required=True, metavar="KEY=V1,V2,...",
                        help="a configuration key as section.key (e.g. regularizer.lambda, "
                        "solver.name, solver.options.lr) and its values, comma-separated; "
                        "values are read as TOML (1e-3, 20, true, [0.9, 0.99]) or else as "
                        "text; repeat --param for more keys")
    parser.add_argument("--out", type=arguments.folder, default="results/sweep",
                        help="output folder (default results/sweep)")
    parser.add_argument("--resume", action="store_true",
                        help="keep finished runs, continue interrupted ones")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or table echo")
    add_cluster_arguments(parser, "the combinations")
    parser.set_defaults(func=run)


def parse_param(text: str) -> tuple[str, list[tuple[str, object]]]:
    """``"key=v1,v2"`` → ``(key, [(text, value), ...])``; values parsed as TOML, else text.

    Commas inside brackets, braces or quotes do not split values.
    """
    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or not key or not values.strip():
        raise ValueError(f"--param {text!r}: expected KEY=V1,V2,... (e.g. "
                         "regularizer.lambda=1e-4,1e-3)")
    items = [v.strip() for v in _split_values(values)]
    if any(not v for v in items):
        raise ValueError(f"--param {text!r}: empty value")
    return key, [(v, _toml_value(v)) for v in items]


def _split_values(text: str) -> list[str]:
    parts, depth, quote, current = [], 0, None, ""
    for c in text:
        if quote:
            quote = None if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(current)
            current = ""
            continue
        current += c
    return [*parts, current]


def _toml_value(text: str):
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        return text


def with_value(cfg: dict, key: str, value) -> dict:
    """A copy of ``cfg`` with the dotted ``key`` set to ``value`` (validated later)."""
    out = copy.deepcopy(cfg)
    *sections, leaf = key.split(".")
    node = out
    for i, section in enumerate(sections):
        node = node.setdefault(section, {})
        if not isinstance(node, dict):
            raise ValueError(f"--param {key}: {'.'.join(sections[:i + 1])!r} is a value, not "
                             "a section")
    node[leaf] = value
    return out


def combinations(cfg: dict, params: list[tuple[str, list[tuple[str, object]]]]) -> list[dict]:
    """Every combination of the values: its folder name, its values, its validated config.

    Raises
    ------
    invflame.experiments.config.ConfigError
        For a combination that is not a valid configuration (names the values).
    """
    from invflame.experiments import config as configuration

    keys = [key for key, _ in params]
    if len(set(keys)) != len(keys):
        raise ValueError(f"each key may be swept by one --param only, got {keys}")
    out = []
    for i, choice in enumerate(itertools.product(*(values for _, values in params))):
        combined = cfg
        for key, (_, value) in zip(keys, choice, strict=True):
            combined = with_value(combined, key, value)
        label = "_".join(f"{key}={text}" for key, (text, _) in zip(keys, choice, strict=True))
        try:
            combined = configuration.validate(combined)
        except configuration.ConfigError as err:
            raise configuration.ConfigError(f"combination {label}: {err}") from err
        out.append({"name": f"{i:03d}_" + _safe(label), "label": label, "config": combined,
                    "values": {key: value for key, (_, value) in zip(keys, choice,
                                                                     strict=True)}})
    return out


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in ".=+-_" else "_" for c in name)[:150]


def summary_rows(combos: list[dict], outcomes) -> list[dict]:
    """One row per combination: values, status, metrics (normalized MSE, PSNR), error."""
    rows = []
    for combo, outcome in zip(combos, outcomes, strict=True):
        summary = outcome.summary or {}
        mse, psnr = summary.get("mse", {}), summary.get("psnr_db", {})
        rows.append({
            "run": combo["name"],
            **{key: _cell(value) for key, value in combo["values"].items()},
            "status": "ok" if outcome.ok else "failed",
            "attempts": outcome.attempts,
            "iterations": summary.get("iterations"),
            "loss_final": summary.get("loss", {}).get("final"),
            "MSE_T": mse.get("T"), "MSE_CO2": mse.get("CO2"), "MSE_H2O": mse.get("H2O"),
            "PSNR_T_dB": psnr.get("T"),
            "s_per_iteration": summary.get("seconds_per_iteration"),
            "error": outcome.error or "",
        })
    return rows


def _cell(value):
    return value if isinstance(value, int | float | str | bool) else str(value)


def markdown(rows: list[dict]) -> str:
    """The rows as a Markdown table (numbers to 4 significant digits)."""
    header = list(rows[0])
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        lines.append("| " + " | ".join(_format(row[k]) for k in header) + " |")
    return "\n".join(lines) + "\n"


def _format(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float) and not isinstance(value, bool):
        return f"{value:.4g}" if math.isfinite(value) else str(value)
    return str(value).replace("|", "\\|").replace("\n", " ")


def run(args: argparse.Namespace) -> int:
    """Run the sweep; 0 if every run finished, 1 if some failed, 2 for bad input."""
    from invflame.atomic_files import write_csv, write_json, write_text
    from invflame.experiments import config as configuration
    from invflame.experiments.cluster import Job, dask_client, failure_report, run_jobs

    try:
        params = [parse_param(text) for text in args.param]
        combos = combinations(configuration.load(args.config), params)
    except (ValueError, FileNotFoundError) as err:
        print(f"invflame sweep: error: {err}", file=sys.stderr)
        return 2
    jobs = [Job(c["label"], c["config"], args.out / c["name"]) for c in combos]
    workers = 1 if args.workers is None and args.scheduler is None else args.workers
    # without --workers/--scheduler: one run at a time, in a worker thread of this process
    with dask_client(workers, args.scheduler, processes=args.workers is not None) as client:
        outcomes = run_jobs(client, jobs, resume=args.resume, retries=args.retries,
                            progress=not args.quiet)
    rows = summary_rows(combos, outcomes)
    table = markdown(rows)
    write_csv(args.out / "summary.csv", rows)
    write_text(args.out / "summary.md", table)
    write_json(args.out / "sweep.json", {
        "config": str(args.config), "params": {key: [t for t, _ in v] for key, v in params},
        "rows": rows})
    if not args.quiet:
        print(table)
    print(f"{sum(o.ok for o in outcomes)} of {len(outcomes)} runs finished; results in "
          f"{args.out}")
    report = failure_report(outcomes)
    if report:
        print(report, end="", file=sys.stderr)
        return 1
    return 0
