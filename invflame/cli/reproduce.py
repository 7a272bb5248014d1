"""``invflame reproduce`` and ``invflame study``: the six-way comparison with one command.

``reproduce`` follows the paper's protocol (noisy-truth start, noise-free data from the same
model); ``study`` the honest one (a start from the data, FTIR noise, data rendered on the
truth's own grid with more sub-rays and a finer line-by-line step, runs to convergence). See
:mod:`invflame.experiments.reproduce`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from invflame.cli import arguments


def add_parser(subparsers) -> None:
    """Register ``invflame reproduce`` and ``invflame study``."""
    reproduce = subparsers.add_parser(
        "reproduce", help="the paper's comparison under its protocol (starts from the truth)",
        description="Runs VG/NR, VG/Tikh., VG/TV, NN/NR, NN/Tikh. and NN/TV under the paper's "
        "protocol (start: ground truth + 20 % noise; noise-free data from the reconstruction's "
        "own model; lambda = 1e-3 per pixel; fixed epochs) and writes into --out: one folder "
        "per method, the table (table.md, .csv, .json) with no-data baselines and the paper's "
        "Table 1, figures and logs. For what a researcher without the truth can do, see "
        "'invflame study'.")
    _add_common(reproduce, "results/reproduce")
    reproduce.set_defaults(func=run, protocol="paper")
    study = subparsers.add_parser(
        "study", help="the comparison from the data alone: honest start, noise, no inverse crime",
        description="Runs the six methods of the paper from a start made of the data "
        "(band-integrated tomography + a methane state relation), on data rendered from the "
        "truth on its own grid with 25 sub-rays per pixel and half the line-by-line step, "
        "with FTIR noise (NESR), each until its objective stops falling or the preset's "
        "iteration limit; the voxel rows choose λ from the data (discrepancy principle with "
        "the model error of prior flames: a ladder of solves); writes the same table, "
        "baselines and figures as 'reproduce'.")
    _add_common(study, "results/study")
    study.set_defaults(func=run, protocol="honest")


def _preset_names() -> list[str]:
    """The presets of :mod:`invflame.experiments.reproduce`, sorted."""
    from invflame.experiments.reproduce import PRESETS

    return sorted(PRESETS)


def _method_names() -> list[str]:
    """The methods of :mod:`invflame.experiments.reproduce`, in the order of its table."""
    from invflame.experiments.reproduce import METHODS

    return list(METHODS)


def _add_common(parser: argparse.ArgumentParser, default_out: str) -> None:
    parser.add_argument("--preset", choices=arguments.Choices(_preset_names), default="quick",
                        metavar="PRESET", help="quick: 30^3 voxels, 16^2 px, 0.08 cm-1 "
                        "(default); paper: 60^3, 32^2 px, 0.04 cm-1, 2000 epochs")
    parser.add_argument("--truth", default="poolfire", metavar="SOURCE",
                        help="ground truth: 'poolfire' (the packaged OpenFOAM pool fire, "
                        "default), 'synthetic' (a McCaffrey plume) or a field .npz file (e.g. "
                        "from 'invflame phantom from-openfoam')")
    parser.add_argument("--out", type=arguments.folder, default=default_out,
                        help=f"output folder (default {default_out})")
    parser.add_argument("--resume", action="store_true",
                        help="keep finished methods, continue interrupted ones")
    parser.add_argument("--methods", nargs="+", choices=arguments.Choices(_method_names),
                        metavar="METHOD", help="subset of the methods: %(choices)s")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the noise, the start and stochastic solvers (default 0)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars or log echo")
    add_cluster_arguments(parser, "the methods")


def add_cluster_arguments(parser: argparse.ArgumentParser, what: str) -> None:
    """``--workers``, ``--scheduler`` and ``--retries``: run ``what`` on a Dask cluster."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive_int, metavar="N",
                       help=f"run {what} in parallel on a local Dask cluster of N worker "
                       "processes (default: one after the other in this process)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help=f"run {what} on an existing Dask cluster: its scheduler address "
                       "(tcp://host:8786) or scheduler file (JSON), e.g. one started by "
                       "dask-jobqueue on Slurm; the output folder must be on a file system "
                       "the workers share")
    parser.add_argument("--retries", type=int, default=1, metavar="R",
                        help="on a cluster, retry a failed run R times, resuming from its "
                        "checkpoint (default 1)")


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive number of workers, got {text}")
    return value


def run(args: argparse.Namespace) -> int:
    """Run the comparison (on a Dask cluster with ``--workers``/``--scheduler``)."""
    from invflame.experiments.reproduce import reproduce

    if args.workers is None and args.scheduler is None:
        reproduce(args.preset, args.out, resume=args.resume, progress=not args.quiet,
                  methods=args.methods, seed=args.seed, protocol=args.protocol,
                  truth=args.truth)
        print(f"results in {args.out}")
        return 0
    return run_on_cluster(args)


def run_on_cluster(args: argparse.Namespace) -> int:
    """The methods as parallel Dask tasks, then the table and figures of those that finished."""
    from invflame.experiments.cluster import Job, dask_client, failure_report, run_jobs
    from invflame.experiments.reproduce import METHODS, folder_name, method_config, reproduce

    methods = list(args.methods or METHODS)
    jobs = [Job(m, method_config(args.preset, m, args.seed, args.protocol, args.truth),
                args.out / folder_name(m)) for m in methods]
    with dask_client(args.workers, args.scheduler) as client:
        outcomes = run_jobs(client, jobs, resume=args.resume, retries=args.retries,
                            progress=not args.quiet)
    finished = {folder_name(o.job.name): o.summary for o in outcomes if o.ok}
    if finished:
        reproduce(args.preset, args.out, resume=args.resume, progress=not args.quiet,
                  methods=[o.job.name for o in outcomes if o.ok], seed=args.seed,
                  protocol=args.protocol, truth=args.truth,
                  run=lambda cfg, folder, resume, progress: finished[Path(folder).name])
        print(f"results in {args.out}")
    report = failure_report(outcomes)
    if report:
        print(report, end="", file=sys.stderr)
        return 1
    return 0
