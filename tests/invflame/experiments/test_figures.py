"""The figures of a comparison, from its run folders."""

import json

import matplotlib.colors
import matplotlib.image
import numpy as np

from invflame.experiments import config, figures
from invflame.experiments.figures import (
    MISFIT_LABELS,
    field_figures,
    loss_curves,
    loss_series,
    run_fields,
)
from invflame.geometry import VoxelGrid, paper_rig


def test_field_figures_of_run_folders(tmp_path, plume_fields):
    truth, estimates = plume_fields
    for method in ("VG-TV", "NN-TV"):
        folder = tmp_path / method
        folder.mkdir()
        truth.save(folder / "truth.npz")
        estimates["start"].save(folder / "initial.npz")
        estimates["smoothed"].save(folder / "reconstruction.npz")
    loaded_truth, loaded = run_fields({m: tmp_path / m for m in ("VG-TV", "NN-TV")})
    assert list(loaded) == ["start", "VG-TV", "NN-TV"]
    np.testing.assert_array_equal(loaded_truth.values, truth.values)
    written = field_figures(tmp_path, loaded_truth, loaded)
    assert [p.name for p in written] == ["cutaways.png", "errors.png", "isotherms_3d.png"]
    rows = {p.name: matplotlib.image.imread(p).shape for p in written}
    assert all(shape[1] == 1600 for shape in rows.values())
    # four rows of cutaways (truth, start, two methods) against three rows of errors
    assert rows["cutaways.png"][0] > rows["errors.png"][0]


def test_a_sooting_truth_reconstructed_without_soot_is_drawn_as_gas(tmp_path, plume_fields):
    truth, estimates = plume_fields
    folder = tmp_path / "VG-TV"
    folder.mkdir()
    truth.with_soot(np.full(truth.grid.shape, 1e-6)).save(folder / "truth.npz")
    estimates["smoothed"].save(folder / "reconstruction.npz")
    loaded_truth, loaded = run_fields({"VG/TV": folder})
    assert loaded_truth.soot is None and loaded["VG/TV"].soot is None
    written = field_figures(tmp_path, loaded_truth, loaded)
    assert all(path.is_file() for path in written)


def _history(folder, iterations, misfit, epochs, summary=None):
    folder.mkdir()
    rows = ["iteration,loss,misfit,regularizer,grad_norm,time"]
    rows += [f"{i},{10.0 / (i + 1)},{misfit},nan,1.0,{0.5 * i}" for i in range(iterations + 1)]
    (folder / "history.csv").write_text("\n".join(rows) + "\n")
    (folder / "summary.json").write_text(json.dumps({"iterations": iterations,
                                                      "epochs": epochs, **(summary or {})}))


def test_loss_series_in_epochs_and_misfit_only_where_logged(tmp_path):
    _history(tmp_path / "VG-TV", 8, 0.5, 8.0)
    _history(tmp_path / "NN-TV", 8, "nan", 2.0)   # four batches of rays per epoch
    runs = {"VG/TV": tmp_path / "VG-TV", "NN/TV": tmp_path / "NN-TV"}
    series = loss_series(runs)
    np.testing.assert_allclose(series["VG/TV"]["epoch"], np.arange(9.0))
    np.testing.assert_allclose(series["NN/TV"]["epoch"], np.arange(9.0) / 4)
    np.testing.assert_allclose(series["VG/TV"]["misfit"], 0.5)
    assert series["NN/TV"]["misfit"] is None
    both = matplotlib.image.imread(loss_curves(runs, tmp_path / "both.png"))
    alone = matplotlib.image.imread(loss_curves({"NN/TV": runs["NN/TV"]}, tmp_path / "nn.png"))
    # the misfit panel is left out when no run logged a misfit
    assert alone.shape[1] < both.shape[1]


def _pixels_of(image, colour):
    """How many pixels of an RGBA image are within 0.05 of ``colour`` (a matplotlib colour)."""
    rgb = np.array(matplotlib.colors.to_rgb(colour))
    return int((np.abs(image[..., :3] - rgb).max(axis=-1) < 0.05).sum())


def test_loss_curves_that_coincide_all_show(tmp_path):
    _history(tmp_path / "NN-NR", 8, "nan", 2.0)
    _history(tmp_path / "NN-Tikh", 8, "nan", 2.0)   # the same losses: the curves coincide
    runs = {"NN/NR": tmp_path / "NN-NR", "NN/Tikh.": tmp_path / "NN-Tikh"}
    both = matplotlib.image.imread(loss_curves(runs, tmp_path / "both.png"))
    alone = matplotlib.image.imread(loss_curves({"NN/NR": runs["NN/NR"]}, tmp_path / "nr.png"))
    # the first run's curve shows between the second's dashes: a good part of its pixels drawn
    # alone, where with both solid it showed in the legend only (2 % of them)
    assert _pixels_of(both, "C0") > 0.1 * _pixels_of(alone, "C0")
    assert _pixels_of(both, "C1") > 0


def test_the_spectrum_figure_names_the_run_it_shows(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    measured = rng.random((4 * 3 * 3, 5))   # four cameras of 3 x 3 pixels, five wavenumbers
    np.savez(tmp_path / "data.npz", measured=measured, simulated=0.9 * measured,
             out_wavenumber=np.linspace(660.0, 700.0, 5))
    shown = []
    monkeypatch.setattr(figures.plt, "close", shown.append)
    rig = paper_rig(VoxelGrid.poolfire(4), n_pixels=3)
    figures.spectrum_and_image(tmp_path, tmp_path / "spectrum.png", rig, label="VG/TV")
    (fig,) = shown
    spectrum, _, _, _, _, simulated = fig.axes[:6]
    assert [t.get_text() for t in spectrum.get_legend().get_texts()] == [
        "measured", "simulated from VG/TV"]
    assert simulated.get_title() == "camera 1 (3×3 px)\nsimulated from VG/TV"
    ray = int(np.argmax(measured.sum(1)))
    camera, pixel = divmod(ray, 9)
    assert spectrum.get_title() == (f"brightest pixel: camera {camera + 1}, row {pixel // 3 + 1}, "
                                    f"column {pixel % 3 + 1} (ray {ray})")


def test_loss_curves_name_the_misfit_of_each_weighting(tmp_path, monkeypatch):
    def run(name, scaling, noise="nesr"):
        cfg = config.validate({"regularizer": {"scaling": scaling}, "noise": {"kind": noise}})
        _history(tmp_path / name, 4, 0.5, 4.0, {"config": cfg})
        return tmp_path / name

    chi2, paper, clean = run("chi2", "chi2"), run("paper", "paper"), run("clean", "chi2", "none")
    _history(tmp_path / "unknown", 4, 0.5, 4.0)
    # a measurement file without noise: only the summary's record tells
    measured = config.validate({})
    measured["data"]["source"] = "data.nc"
    _history(tmp_path / "measured", 4, 0.5, 4.0, {"config": measured,
                                                  "noise_weighted_misfit": False})
    shown = []
    monkeypatch.setattr(figures.plt, "close", shown.append)
    for runs in ({"VG": chi2}, {"VG": paper}, {"VG": clean}, {"VG": tmp_path / "unknown"},
                 {"VG": tmp_path / "measured"}, {"VG": chi2, "NN": paper}):
        loss_curves(runs, tmp_path / "loss.png")
    labels = [fig.axes[1].get_ylabel() for fig in shown]
    assert labels == [MISFIT_LABELS[True], MISFIT_LABELS[False], MISFIT_LABELS[False],
                      MISFIT_LABELS[None], MISFIT_LABELS[False], "data misfit"]
    assert MISFIT_LABELS[True] == "noise-weighted χ² = ‖(F(θ) − d)/σ‖² [1]"
    assert "(W/(m²·sr·cm⁻¹))²" in MISFIT_LABELS[False]
    # runs of both kinds: each curve says its quantity
    assert [t.get_text() for t in shown[-1].axes[1].get_legend().get_texts()] == [
        f"VG: {MISFIT_LABELS[True]}", f"NN: {MISFIT_LABELS[False]}"]
