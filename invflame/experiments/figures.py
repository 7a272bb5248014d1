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
from invflame.experiments.metrics import normalized_mse  # noqa: E402
from invflame.field import Field  # noqa: E402
from invflame.plotting.comparison import plot_comparison, plot_errors  # noqa: E402
from invflame.plotting.isosurfaces import plot_isotherms_3d  # noqa: E402


def read_history(path) -> dict[str, np.ndarray]:
    """Columns of a run's ``history.csv`` as float arrays."""
    with open(path) as handle:
        rows = list(csv.DictReader(handle))
    return {key: np.array([float(r[key]) for r in rows]) for key in rows[0]} if rows else {}


def loss_series(runs: dict[str, Path]) -> dict[str, dict[str, np.ndarray | None]]:
    """Each run's objective and data misfit against epochs, from its ``history.csv``.

    An iteration is an epoch for the voxel solvers and one batch of rays for the neural field;
    the run's ``summary.json`` (iterations and epochs) sets the scale, one iteration per epoch
    without it. ``misfit`` is None for a run that logged none (a stochastic neural-field run
    logs its loss only).
    """
    series = {}
    for label, folder in runs.items():
        history = read_history(Path(folder) / "history.csv")
        summary = Path(folder) / "summary.json"
        per_iteration = 1.0
        if summary.exists():
            done = read_json(summary)
            per_iteration = done["epochs"] / done["iterations"] if done["iterations"] else 1.0
        misfit = history["misfit"]
        series[label] = {"epoch": history["iteration"] * per_iteration, "loss": history["loss"],
                         "misfit": misfit if np.isfinite(misfit).any() else None}
    return series


#: Line styles of the runs' curves, in turn: a later run's curve lies over an earlier one's
#: that it follows closely (the three neural-field rows of a study, a few per cent apart) and
#: leaves it visible between its dashes or dots.
_LINES = ({"linestyle": "-", "linewidth": 2.2}, {"linestyle": "--", "linewidth": 1.6},
          {"linestyle": ":", "linewidth": 1.6})


def loss_curves(runs: dict[str, Path], path) -> Path:
    """Objective (and data misfit, where logged) against epoch for each run, log scale; the
    runs' curves are drawn solid, dashed and dotted in turn, so that curves that coincide all
    show."""
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
        for label, s in with_misfit.items():
            axes[1].semilogy(s["epoch"], s["misfit"], label=label, **line[label])
        unlogged = sorted(set(series) - set(with_misfit))
        axes[1].set(ylabel="‖F(θ) − d‖² [(W/(m²·sr·cm⁻¹))²]",
                    title="data misfit" + (f" (not logged by {', '.join(unlogged)})"
                                           if unlogged else ""))
    for ax in axes:
        ax.set_xlabel("epoch (one pass over all rays)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return Path(path)


def spectrum_and_image(folder, path, n_cameras: int = 4, label: str = "reconstruction") -> Path:
    """Measured vs simulated spectrum of the brightest pixel, and camera 1's band image, of the
    run in ``folder``, whose reconstruction the figure names ``label``."""
    data = np.load(Path(folder) / "data.npz")
    measured, simulated, eta = data["measured"], data["simulated"], data["out_wavenumber"]
    n_pixels = int(round(np.sqrt(measured.shape[0] / n_cameras)))
    pixel = int(np.argmax(measured.sum(axis=1)))
    band = measured.sum(axis=1) * (eta[1] - eta[0])
    band_sim = simulated.sum(axis=1) * (eta[1] - eta[0])
    image = band.reshape(n_cameras, n_pixels, n_pixels)[0]
    image_sim = band_sim.reshape(n_cameras, n_pixels, n_pixels)[0]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    axes[0].plot(eta, measured[pixel], "k.-", label="measured")
    axes[0].plot(eta, simulated[pixel], "r-", label=f"simulated from {label}")
    axes[0].set(xlabel="wavenumber [cm⁻¹]", ylabel="radiance [W/(m²·sr·cm⁻¹)]",
                title=f"brightest pixel (ray {pixel})")
    axes[0].legend(fontsize=8)
    vmax = max(image.max(), image_sim.max())
    for ax, img, title in ((axes[1], image, "measured"),
                           (axes[2], image_sim, f"simulated from {label}")):
        shown = ax.imshow(img, cmap="inferno", vmin=0, vmax=vmax)
        ax.set(title=f"camera 1, {title}", xticks=[], yticks=[])
    fig.colorbar(shown, ax=axes[1:], label="band radiance [W/(m²·sr)]")
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return Path(path)


def run_fields(runs: dict[str, Path]) -> tuple[Field, dict[str, Field]]:
    """The ground truth and the estimates to show for runs: the start (of the first run), then
    each run's reconstruction, by label.

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
    return Field.load(first / "truth.npz"), estimates


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
    reconstruction, against the ground truth), ``loss_curves.png``, and ``spectrum_image.png``
    (of the first run, named in it).
    """
    out = Path(out)
    truth, estimates = run_fields(runs)
    written = field_figures(out, truth, estimates)
    first, first_folder = next(iter(runs.items()))
    written += [loss_curves(runs, out / "loss_curves.png"),
                spectrum_and_image(first_folder, out / "spectrum_image.png", label=first)]
    return written
