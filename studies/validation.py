"""The honest study on a family of flames: what each method gains over its own start.

Usage: python studies/validation.py [--half report|tuning|packaged|all] [--family DIR]
       [--flames NAME ...] [--methods VG/TV NN/TV ...] [--preset quick] [--collect]
       [--out results/validation]

The family (``scripts/make_validation_family.sh`` writes it into ``runs/validation``) is split
once, before any result was seen, into a **tuning** half, on which settings may be chosen, and
a **report** half, on which they are only reported; the packaged pool fire (t = 0.9 s) is
reported beside the report half. For every flame of the chosen half it runs ``invflame study``
(:func:`invflame.experiments.reproduce.reproduce`, honest protocol: data rendered on the
flame's own grid with 25 sub-rays per pixel and half the line-by-line step, NESR 1e-3
W/(m²·sr·cm⁻¹), the data-driven start) with ``--resume``, so a killed study continues, and
prints per flame and method: MSE_T, the gain over the method's own start (its start's MSE_T
over its final one) and over the band tomography before its calibration (both data-driven
starts), MSE_CO2 and MSE_H2O against their start's, χ²/M, the hot-volume ratio and
whether it converged, beside flat ambient air (the best baseline without data); then per
method the median and least gain over the flames, and statements checked on those numbers.
"""

import argparse
import statistics
from pathlib import Path

from invflame.atomic_files import read_json
from invflame.experiments.reproduce import METHODS, reproduce

TUNING = ("poolfire_u0.01_t1.2", "poolfire_u0.01_t2", "poolfire_u0.02_t1",
          "plume_sheet1950_seed1")
"""Flames on which settings may be chosen (file stems in the family folder)."""

REPORT = ("poolfire_u0.01_t1.6", "poolfire_u0.01_t2.4", "poolfire_u0.01_t2.8",
          "poolfire_u0.02_t2", "plume_sheet1950_seed2")
"""Flames on which results are reported only."""


def flames(half: str, family: Path, only=None) -> list[tuple[str, str]]:
    """``(name, truth source)`` of each flame of a half; the packaged pool fire is 'poolfire'.
    Those named in ``only`` (all when None) must exist."""
    chosen = {"tuning": TUNING, "report": REPORT, "packaged": (), "all": TUNING + REPORT}[half]
    found = [(stem, str(family / f"{stem}.npz")) for stem in chosen]
    missing = [source for stem, source in found if not Path(source).is_file()
               and (only is None or stem in only)]
    if missing:
        raise SystemExit(f"error: missing {', '.join(missing)}: run "
                         "scripts/make_validation_family.sh first")
    packaged = [("poolfire_t0.9", "poolfire")] if half in ("report", "packaged",
                                                                        "all") else []
    return found + packaged


def rows_of(table: dict) -> tuple[list[dict], dict, dict | None]:
    """The methods' rows of a study's ``table.json``, its flat-air baseline and its band
    tomography before calibration (None where the start was not calibrated)."""
    baselines = {b["method"]: b for b in table["baselines"]}
    return (table["rows"], baselines["ambient air (flat)"],
            baselines.get("band tomography before calibration"))


def flame_lines(name: str, rows: list[dict], air: dict, raw: dict | None) -> list[str]:
    """Markdown rows of one flame."""
    lines = []
    for r in rows:
        over_raw = "–" if raw is None else f"{raw['MSE_T'] / r['MSE_T']:.2f}"
        lines.append(
            f"| {name} | {r['method']} | {r['MSE_T']:.4f} | {r['MSE_T_initial']:.4f} | "
            f"{r['improvement_T']:.2f} | {over_raw} | "
            f"{r['MSE_CO2'] / r['MSE_CO2_initial']:.2f} | "
            f"{r['MSE_H2O'] / r['MSE_H2O_initial']:.2f} | {r['chi2_per_measurement']:.3g} | "
            f"{r['hot_volume_ratio']:.2f} | {'yes' if r['converged'] else 'NO'} | "
            f"{air['MSE_T'] / r['MSE_T']:.2f} |")
    return lines


def summary_lines(results: dict[str, list[dict]]) -> list[str]:
    """Per method over the flames: median and least gain, and the checks."""
    lines = ["", "| method | flames | median gain | least gain | median, least gain over the "
             "band tomography | worst CO2 ratio | worst H2O ratio | hot vol. range | converged | "
             "least ratio to flat air |",
             "|---|---:|---:|---:|---:|---:|---:|---|---:|---:|"]
    checks = []
    for method, rows in results.items():
        if not rows:
            continue
        gains = [r["improvement_T"] for r in rows]
        co2 = max(r["MSE_CO2"] / r["MSE_CO2_initial"] for r in rows)
        h2o = max(r["MSE_H2O"] / r["MSE_H2O_initial"] for r in rows)
        hot = [r["hot_volume_ratio"] for r in rows]
        converged = sum(r["converged"] for r in rows)
        air = min(r["air_ratio"] for r in rows)
        raw = [r["raw_gain"] for r in rows if r["raw_gain"] is not None]
        over_raw = f"{statistics.median(raw):.2f}, {min(raw):.2f}" if raw else "–"
        lines.append(f"| {method} | {len(rows)} | {statistics.median(gains):.2f} | "
                     f"{min(gains):.2f} | {over_raw} | {co2:.2f} | {h2o:.2f} | "
                     f"{min(hot):.2f}-{max(hot):.2f} | {converged}/{len(rows)} | {air:.2f} |")
        checks.append(f"- {method}: improves on its start on every flame: "
                      f"{'yes' if min(gains) > 1 else 'NO'}; CO2 and H2O within 10 % of the "
                      f"start's: {'yes' if max(co2, h2o) <= 1.1 else 'NO'}; hot volume within "
                      f"0.7-1.4: {'yes' if 0.7 <= min(hot) and max(hot) <= 1.4 else 'NO'}; "
                      f"converged everywhere: {'yes' if converged == len(rows) else 'NO'}")
    return lines + ["", "Checked on these numbers:", *checks]


def main() -> None:
    parser = argparse.ArgumentParser(prog="validation", description=__doc__.split("\n")[0])
    parser.add_argument("--half", choices=("report", "tuning", "packaged", "all"),
                        default="report")
    parser.add_argument("--family", type=Path, default=Path("runs/validation"))
    parser.add_argument("--flames", nargs="+", metavar="NAME",
                        help="only these flames of the half (e.g. to share them between "
                             "processes; a later call without it reads their finished runs)")
    parser.add_argument("--methods", nargs="+", choices=list(METHODS), default=list(METHODS))
    parser.add_argument("--preset", choices=("quick", "paper"), default="quick")
    parser.add_argument("--out", type=Path, default=Path("results/validation"))
    parser.add_argument("--collect", action="store_true",
                        help="run nothing: print the flames whose studies have finished")
    args = parser.parse_args()
    results: dict[str, list[dict]] = {m: [] for m in args.methods}
    lines = [f"Preset {args.preset}, half {args.half}; honest protocol, data-driven start.", "",
             "| flame | method | MSE_T | start MSE_T | gain | gain over the band tomography "
             "before calibration | CO2 / start | H2O / start | χ²/M | hot vol. | converged | "
             "flat air / MSE_T |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|:-:|---:|"]
    chosen = flames(args.half, args.family, args.flames)
    unknown = set(args.flames or ()) - {name for name, _ in chosen}
    if unknown:
        parser.error(f"--flames {sorted(unknown)} not in the {args.half} half: "
                     f"{[name for name, _ in chosen]}")
    for name, source in chosen:
        folder = args.out / args.preset / name
        if args.flames and name not in args.flames or args.collect and not (
                folder / "table.json").is_file():
            continue
        if not args.collect:
            reproduce(args.preset, folder, resume=True, progress=False, methods=args.methods,
                      protocol="honest", truth=source)
        rows, air, raw = rows_of(read_json(folder / "table.json"))
        rows = [r for r in rows if r["method"] in results]
        for r in rows:
            results[r["method"]].append({**r, "air_ratio": air["MSE_T"] / r["MSE_T"],
                                         "raw_gain": None if raw is None
                                         else raw["MSE_T"] / r["MSE_T"]})
        lines += flame_lines(name, rows, air, raw)
        print("\n".join(lines[-len(rows):]), flush=True)
    print("\n".join(lines + summary_lines(results)))


if __name__ == "__main__":
    main()
