"""The solver race's reference: the levels the other variants race to, and a reference taken
from a finished ``invflame reproduce`` run instead of run by the race
(:func:`recorded_reference`)."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np

import solvers
from invflame.experiments.figures import read_history
from invflame.field import Field

FRACTIONS = (0.25, 0.5, 1.0)
"""Fractions of the reference's iterations after which its objective and MSE_T are levels."""


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
