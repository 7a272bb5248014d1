"""Figures of a run or a comparison: cutaways, error maps, 3-D isotherms, loss curves, spectra
and camera images."""

from __future__ import annotations

import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from invflame.atomic_files import read_json  # noqa: E402
from invflame.experiments import config as configuration  # noqa: E402
from invflame.experiments.inputs import read_data, scene_rig  # noqa: E402
from invflame.experiments.metrics import normalized_mse  # noqa: E402
from invflame.field import Field  # noqa: E402
from invflame.geometry import CameraRig  # noqa: E402
from invflame.plotting.comparison import plot_comparison, plot_errors  # noqa: E402
from invflame.plotting.isosurfaces import plot_isotherms_3d  # noqa: E402
from invflame.plotting.spectra import plot_spectrum_and_images  # noqa: E402


def read_history(path) -> dict[str, np.ndarray]:
    """Columns of a run's ``history.csv`` as float arrays."""
    with open(path) as handle:
        rows = list(csv.DictReader(handle))
    return {key: np.array([float(r[key]) for r in rows]) for key in rows[0]} if rows else {}


def noise_weighted(summary: dict) -> bool | None:
    """Whether a run's data misfit is the noise-weighted χ² = ‖(F(θ) − d)/σ‖² (dimensionless)
    rather than ‖F(θ) − d‖² in (W/(m²·sr·cm⁻¹))²: as its summary records it
    (``noise_weighted_misfit``), else as its configuration says (``regularizer.scaling =
    "chi2"`` with measured data or synthetic data with noise; a measurement file may hold no
    noise, which only the record tells). None for a summary with neither.

    Parameters
    ----------
    summary : dict
        A run's ``summary.json``.
    """
    if summary.get("noise_weighted_misfit") is not None:
        return summary["noise_weighted_misfit"]
    cfg = summary.get("config")  # a run from before the summary recorded it
    if cfg is None:
        return None
    return (cfg["regularizer"]["scaling"] == "chi2"
            and bool(cfg["data"]["source"] or cfg["noise"]["kind"] != "none"))


def loss_series(runs: dict[str, Path]) -> dict[str, dict]:
    """Each run's objective and data misfit against epochs, from its ``history.csv``.

    An iteration is an epoch for the voxel solvers and one batch of rays for the neural field;
    the run's ``summary.json`` (iterations and epochs) sets the scale, one iteration per epoch
    without it. ``misfit`` is None for a run that logged none (a stochastic neural-field run
    logs its loss only); ``noise_weighted`` says which misfit it is (:func:`noise_weighted`;
    None without a summary).
    """
    series = {}
    for label, folder in runs.items():
        history = read_history(Path(folder) / "history.csv")
        summary = Path(folder) / "summary.json"
        done = read_json(summary) if summary.exists() else {}
        per_iteration = done["epochs"] / done["iterations"] if done.get("iterations") else 1.0
        misfit = history["misfit"]
        series[label] = {"epoch": history["iteration"] * per_iteration, "loss": history["loss"],
                         "misfit": misfit if np.isfinite(misfit).any() else None,
                         "noise_weighted": noise_weighted(done)}
    return series


MISFIT_LABELS = {True: "noise-weighted χ² = ‖(F(θ) − d)/σ‖² [1]",
                 False: "‖F(θ) − d‖² [(W/(m²·sr·cm⁻¹))²]",
                 None: "data misfit (weighting not recorded)"}
"""The misfit axis's label for a noise-weighted run, an unweighted one, and one whose summary
does not say (:func:`noise_weighted`)."""

#: Line styles of the runs' curves, in turn: a later run's curve lies over an earlier one's
#: that it follows closely (the three neural-field rows of a study, a few per cent apart) and
#: leaves it visible between its dashes or dots.
_LINES = ({"linestyle": "-", "linewidth": 2.2}, {"linestyle": "--", "linewidth": 1.6},
          {"linestyle": ":", "linewidth": 1.6})


def loss_curves(runs: dict[str, Path], path) -> Path:
    """Objective (and data misfit, where logged) against epoch for each run, log scale; the
    runs' curves are drawn solid, dashed and dotted in turn, so that curves that coincide all
    show.

    The misfit axis names the quantity logged (:data:`MISFIT_LABELS`): the dimensionless
    noise-weighted χ² for noise-weighted runs, ‖F(θ) − d‖² in (W/(m²·sr·cm⁻¹))² otherwise;
    runs of both kinds each say theirs in the misfit panel's legend.

    Parameters
    ----------
    runs : dict of str to Path
        Label → run folder (``history.csv``, ``summary.json``).
    path : str or os.PathLike
        The PNG to write.
    """
    series = loss_series(runs)
    line = {label: _LINES[i % len(_LINES)] for i, label in enumerate(series)}
    with_misfit = {label: s for label, s in series.items() if s["misfit"] is not None}
    fig, axes = plt.subplots(1, 2 if with_misfit else 1, figsize=(11 if with_misfit else 6, 4),
                             squeeze=False)
    axes = axes[0]
    for label, s in series.items():
        axes[0].semilogy(s["epoch"], s["loss"], label=label, **line[label])
    axes[0].set(ylabel="loss", title="objective")
    if with_misfit:
        kinds = list(dict.fromkeys(s["noise_weighted"] for s in with_misfit.values()))
        for label, s in with_misfit.items():
            named = label if len(kinds) == 1 else f"{label}: {MISFIT_LABELS[s['noise_weighted']]}"
            axes[1].semilogy(s["epoch"], s["misfit"], label=named, **line[label])
        unlogged = sorted(set(series) - set(with_misfit))
        axes[1].set(ylabel=MISFIT_LABELS[kinds[0]] if len(kinds) == 1 else "data misfit",
                    title="data misfit" + (f" (not logged by {', '.join(unlogged)})"
                                           if unlogged else ""))
        if len(kinds) > 1:
            axes[1].legend(fontsize=7)
    for ax in axes:
        ax.set_xlabel("epoch (one pass over all rays)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return Path(path)


def run_rig(folder) -> CameraRig:
    """The cameras of the run in ``folder``, chosen from its ``config.toml`` as the run chose
    them (:func:`invflame.experiments.inputs.scene_rig`).

    Parameters
    ----------
    folder : str or os.PathLike
        A run folder (:func:`invflame.experiments.runner.run_experiment`).

    Raises
    ------
    FileNotFoundError
        If the folder holds no ``config.toml``.
    """
    cfg = configuration.load(Path(folder) / "config.toml")
    return scene_rig(cfg, read_data(cfg))


def spectrum_and_image(folder, path, rig: CameraRig | None = None,
                       label: str = "reconstruction") -> Path:
    """Measured against simulated spectrum of the brightest pixel, and every camera's band
    image, of the run in ``folder`` (its ``data.npz``), whose reconstruction the figure names
    ``label`` (:func:`invflame.plotting.spectra.plot_spectrum_and_images`); values masked in
    the data (σ = inf: bad pixels and wavenumbers, channels outside a camera's window) are
    not drawn.

    Parameters
    ----------
    folder : str or os.PathLike
        A run folder.
    path : str or os.PathLike
        The PNG to write.
    rig : CameraRig, optional
        The run's cameras, each with its own pixel counts; default: :func:`run_rig`.
    label : str, optional
        Name of the run's reconstruction.
    """
    data = np.load(Path(folder) / "data.npz")
    rig = run_rig(folder) if rig is None else rig
    channels = (np.isfinite(np.broadcast_to(data["sigma"], data["measured"].shape))
                if "sigma" in data.files else None)
    plt.close(plot_spectrum_and_images(data["out_wavenumber"], data["measured"],
                                       data["simulated"], rig, label, path, channels=channels))
    return Path(path)


def run_fields(runs: dict[str, Path]) -> tuple[Field, dict[str, Field]]:
    """The ground truth and the estimates to show for runs: the start (of the first run), then
    each run's reconstruction, by label; their gas alone (:attr:`~invflame.field.Field.gas`)
    unless all hold a soot volume fraction (a sooting truth reconstructed without soot).

    Parameters
    ----------
    runs : dict of str to Path
        Method label → run folder (each holding ``truth.npz`` and ``reconstruction.npz``).
    """
    first = Path(next(iter(runs.values())))
    estimates = {}
    if (first / "initial.npz").is_file():
        estimates["start"] = Field.load(first / "initial.npz")
    estimates.update({label: Field.load(Path(folder) / "reconstruction.npz")
                      for label, folder in runs.items()})
    truth = Field.load(first / "truth.npz")
    if any(field.soot is None for field in [truth, *estimates.values()]):
        truth, estimates = truth.gas, {k: field.gas for k, field in estimates.items()}
    return truth, estimates


def field_figures(out, truth: Field, estimates: dict[str, Field]) -> list[Path]:
    """The figures of fields against the truth, written into ``out``, with the normalized MSE
    of each estimate (:func:`invflame.experiments.metrics.normalized_mse`) in their titles.

    ``cutaways.png`` (:func:`invflame.plotting.comparison.plot_comparison`: rows truth and
    estimates, columns T, X_CO2, X_H2O on two mid-planes), ``errors.png``
    (:func:`~invflame.plotting.comparison.plot_errors`: estimate − truth) and
    ``isotherms_3d.png`` (:func:`invflame.plotting.isosurfaces.plot_isotherms_3d`: cutaway
    isotherm surfaces every 100 K from 500 to 1500 K).

    Parameters
    ----------
    out : str or Path
        Output folder.
    truth : Field
        Ground truth (T [K], mole fractions [1]).
    estimates : dict of str to Field
        Label → fields on the truth's grid, in display order.
    """
    out = Path(out)
    scores = {label: normalized_mse(truth.values, f.values) for label, f in estimates.items()}
    written = [out / "cutaways.png", out / "errors.png", out / "isotherms_3d.png"]
    plt.close(plot_comparison(truth, estimates, scores, path=written[0]))
    plt.close(plot_errors(truth, estimates, scores, path=written[1]))
    plt.close(plot_isotherms_3d({"ground truth": truth, **estimates}, path=written[2],
                                scores={k: v.get("T") for k, v in scores.items()}))
    return written


def comparison_figures(out, runs: dict[str, Path]) -> list[Path]:
    """The figures of a comparison, written into ``out``.

    The field figures of :func:`field_figures` (the start of the first run, then every
    reconstruction, against the ground truth; none for runs without a ground truth, whose
    folders hold no ``truth.npz``), ``loss_curves.png``, and ``spectrum_image.png`` (of the
    first run, named in it).
    """
    out = Path(out)
    first, first_folder = next(iter(runs.items()))
    written = []
    if (Path(first_folder) / "truth.npz").is_file():
        written += field_figures(out, *run_fields(runs))
    written += [loss_curves(runs, out / "loss_curves.png"),
                spectrum_and_image(first_folder, out / "spectrum_image.png", label=first)]
    return written
