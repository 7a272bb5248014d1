"""Figures of a run or a comparison: cutaways, loss curves, spectra and camera images."""

from __future__ import annotations

import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from invflame.field import Field  # noqa: E402
from invflame.plotting.fields import plot_fields  # noqa: E402


def read_history(path) -> dict[str, np.ndarray]:
    """Columns of a run's ``history.csv`` as float arrays."""
    with open(path) as handle:
        rows = list(csv.DictReader(handle))
    return {key: np.array([float(r[key]) for r in rows]) for key in rows[0]} if rows else {}


def loss_curves(runs: dict[str, Path], path) -> Path:
    """Loss against iteration for each run (log scale), one line per run."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for label, folder in runs.items():
        history = read_history(Path(folder) / "history.csv")
        axes[0].semilogy(history["iteration"], history["loss"], label=label)
        axes[1].semilogy(history["iteration"], history["misfit"], label=label)
    axes[0].set(xlabel="iteration (epoch)", ylabel="loss", title="objective")
    axes[1].set(xlabel="iteration (epoch)", ylabel="‖F(θ) − d‖² [(W/(m²·sr·cm⁻¹))²]",
                title="data misfit (stochastic neural-field runs log their loss only)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return Path(path)


def spectrum_and_image(folder, path, n_cameras: int = 4) -> Path:
    """Measured vs simulated spectrum of the brightest pixel, and camera 1's band image."""
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
    axes[0].plot(eta, simulated[pixel], "r-", label="simulated from reconstruction")
    axes[0].set(xlabel="wavenumber [cm⁻¹]", ylabel="radiance [W/(m²·sr·cm⁻¹)]",
                title=f"brightest pixel (ray {pixel})")
    axes[0].legend(fontsize=8)
    vmax = max(image.max(), image_sim.max())
    for ax, img, title in ((axes[1], image, "measured"), (axes[2], image_sim, "simulated")):
        shown = ax.imshow(img, cmap="inferno", vmin=0, vmax=vmax)
        ax.set(title=f"camera 1, {title}", xticks=[], yticks=[])
    fig.colorbar(shown, ax=axes[1:], label="band radiance [W/(m²·sr)]")
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return Path(path)


def comparison_figures(out, runs: dict[str, Path]) -> list[Path]:
    """The figures of a comparison, written into ``out``.

    ``cutaways.png`` (ground truth and every reconstruction, isotherms every 100 K from 500 to
    1500 K), ``loss_curves.png``, and ``spectrum_image.png`` (of the first run).
    """
    out = Path(out)
    first = next(iter(runs.values()))
    fields = [Field.load(Path(first) / "truth.npz")]
    fields += [Field.load(Path(f) / "reconstruction.npz") for f in runs.values()]
    labels = ["ground truth", *runs]
    written = [out / "cutaways.png", out / "loss_curves.png", out / "spectrum_image.png"]
    plot_fields(fields, labels=labels, path=written[0])
    plt.close("all")
    loss_curves(runs, written[1])
    spectrum_and_image(first, written[2])
    return written
