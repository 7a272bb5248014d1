"""Runs from a measurement file and a rig file: no truth needed, the same numbers as in memory."""

import json
from types import SimpleNamespace

import numpy as np
import pytest

from invflame.cli import main
from invflame.errors import ConfigError, InputDataError
from invflame.experiments import config, config_memory, runner
from invflame.geometry import VoxelGrid, paper_rig
from invflame.geometry.rig_file import rig_records, write_rig
from invflame.measurement import Measurement
from invflame.measurement_file import MeasurementFile, read_measurement, write_measurement

SPECTRUM = {"min": 660.0, "max": 690.0, "step": 0.1}
SOLVER = {"name": "adam", "iterations": 4, "options": {"lr": 0.01}}
MEASURED = f"""
[truth]
grid = 8
[data]
source = "m.nc"
[spectrum]
min = {SPECTRUM['min']}
max = {SPECTRUM['max']}
step = {SPECTRUM['step']}
"""
"""A run on the 8^3 grid from the measurement file m.nc over :data:`SPECTRUM`, as TOML."""


def toml(path, text):
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """``invflame simulate`` of the synthetic flame on 4 paper cameras of 4 x 4 pixels, and a
    rig file of the same cameras."""
    folder = tmp_path_factory.mktemp("measured")
    cfg = toml(folder / "simulate.toml", f"""
[truth]
source = "synthetic"
grid = 8
[rig]
pixels = 4
[spectrum]
min = {SPECTRUM['min']}
max = {SPECTRUM['max']}
step = {SPECTRUM['step']}
[solver]
name = "adam"
iterations = 4
options = {{ lr = 0.01 }}
""")
    assert main(["simulate", str(cfg), "--out", str(folder / "m.nc")]) == 0
    rig = write_rig(paper_rig(VoxelGrid.poolfire(8), n_pixels=4), folder / "rig.toml")
    return folder, cfg, rig


def test_simulate_writes_a_measurement_file_of_the_configured_rig(simulated):
    folder, _, _ = simulated
    measured = read_measurement(folder / "m.nc")
    assert measured.measurement.data.shape == (4 * 16, measured.wavenumber.size)
    assert measured.measurement.noisy and measured.resolution == 8.0
    assert rig_records(measured.rig) == rig_records(paper_rig(VoxelGrid.poolfire(8), n_pixels=4))
    assert (folder / "m.png").is_file()


def test_a_file_run_without_truth_and_with_it_matches_the_in_memory_run(simulated, tmp_path,
                                                                       monkeypatch):
    folder, simulate_cfg, rig = simulated
    monkeypatch.chdir(folder)
    measured_cfg = toml(folder / "run.toml", MEASURED + """
[rig]
file = "rig.toml"
[instrument]
margin = 0  # the file's data were simulated on this window: model it alike
""")
    blind = config.load(measured_cfg)
    assert blind["truth"]["source"] == "none"
    blind["solver"] = {**blind["solver"], **SOLVER}
    summary = runner.run_experiment(blind, tmp_path / "blind", progress=False)
    assert "mse" not in summary and summary["chi2_per_measurement"]["final"] > 0
    assert not (tmp_path / "blind" / "truth.npz").exists()
    assert summary["protocol"]["data"] == "measured, read from m.nc"

    scored = dict(blind, truth={"source": "synthetic", "grid": 8})
    from_file = runner.run_experiment(config.validate(scored), tmp_path / "file", progress=False)
    in_memory = runner.run_experiment(config.load(simulate_cfg), tmp_path / "memory",
                                      progress=False)
    assert from_file["mse"] == in_memory["mse"]
    assert from_file["chi2_per_measurement"] == in_memory["chi2_per_measurement"]
    assert from_file["chi2_per_measurement"] == summary["chi2_per_measurement"]
    saved = json.loads((tmp_path / "file" / "summary.json").read_text())
    assert saved["mse"] == in_memory["mse"]
    for name in ("reconstruction.npz", "data.npz"):
        a, b = (np.load(tmp_path / run / name) for run in ("file", "memory"))
        for key in a.files:
            if a[key].dtype.kind == "f":
                np.testing.assert_array_equal(a[key], b[key])


def test_the_command_line_runs_from_the_file_alone(simulated, tmp_path, monkeypatch, capsys):
    folder, _, _ = simulated
    monkeypatch.chdir(folder)
    cfg = toml(tmp_path / "run.toml", MEASURED + """
[solver]
name = "adam"
iterations = 2
""")
    assert main(["run", str(cfg), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    assert "(no ground truth)" in capsys.readouterr().out
    # the channels 668-682 cm-1 at 8 cm-1 need 4 resolutions of lineshape beyond them
    assert ("the line-by-line window 660-690 cm-1 widened to 636-714 cm-1"
            in (tmp_path / "out" / "log.txt").read_text())
    used = config.load(tmp_path / "out" / "config.toml")["spectrum"]
    assert (used["min"], used["max"]) == pytest.approx((636.0, 714.0))


@pytest.mark.parametrize(("margin", "window"), [(0.0, (660.0, 690.0)), (1.0, (660.0, 690.0)),
                                                (1.5, (656.0, 694.0)), (2.04, (651.6, 698.4))])
def test_the_window_widens_on_its_step_to_the_margin_the_channels_need(simulated, monkeypatch,
                                                                       margin, window):
    monkeypatch.chdir(simulated[0])
    cfg = config.validate({"truth": {"grid": 8}, "data": {"source": "m.nc"},
                           "spectrum": SPECTRUM, "instrument": {"margin": margin}})
    widened, note = runner.widened_window(cfg, runner.read_data(cfg))
    assert (widened["spectrum"]["min"], widened["spectrum"]["max"]) == pytest.approx(window)
    assert (widened is cfg) == (note == "") == (window == (660.0, 690.0))
    assert cfg["spectrum"]["min"] == SPECTRUM["min"]  # the caller's configuration unchanged


def test_the_memory_check_counts_the_window_widened_for_the_channels(simulated, monkeypatch):
    monkeypatch.chdir(simulated[0])
    tables = {}
    for margin in (0.0, 2.04):
        cfg = config.validate({"truth": {"grid": 8}, "data": {"source": "m.nc"},
                               "spectrum": SPECTRUM, "instrument": {"margin": margin}})
        found = config_memory.estimates(cfg, {"measured": runner.read_data(cfg), "rig": None})
        [tables[margin]] = [e for e in found
                            if e.what == "the absorption table of the reconstruction"]
    assert "x 301 points x" in tables[0.0].shape and "x 469 points x" in tables[2.04].shape
    assert tables[2.04].nbytes == pytest.approx(tables[0.0].nbytes * 469 / 301)


def test_a_window_widened_below_zero_wavenumber_is_refused():
    cfg = config.validate({"truth": {"grid": 8}, "spectrum": SPECTRUM})
    channels = SimpleNamespace(wavenumber=np.array([20.0, 680.0]), resolution=8.0)
    with pytest.raises(ConfigError, match="from 20 cm-1 would need the window to reach -12 "
                                          "cm-1: lower 'instrument.margin'"):
        runner.widened_window(cfg, channels)


@pytest.mark.parametrize(("settings", "message"), [
    ({"truth": {"source": "none"}}, "'truth.source' = 'none' needs measured data"),
    ({"data": {"source": "missing.nc"}}, "'data.source' = 'missing.nc' is not an existing"),
    ({"data": {"source": "m.nc"}, "init": {"kind": "noisy-truth"}}, "needs a ground truth"),
    ({"rig": {"file": "paper", "cameras": [{}]}}, "\\[rig\\] gives both 'file' and"),
    ({"rig": {"cameras": [{"position": [0.0, 0.5, 0.0], "look_at": [1.0, 0.5, 0.0],
                           "up": [0.0, 1.0, 0.0], "focal_length": 0.5,
                           "sensor_size": [0.4, 0.4], "pixels": [4, 4]}]}},
     "'rig.cameras': camera 0 at \\[0.0, 0.5, 0.0\\] m is inside the grid"),
    ({"rig": {"cameras": [{"position": [2.0, 0.5, 0.0], "focal_length": 0.5,
                           "sensor_size": [0.4, 0.4], "pixels": [4, 4]}]}},
     "'rig.cameras': rig.cameras: camera 0: give exactly one of 'look_at'"),
    ({"rig": {"cameras": {"position": 1}}}, "'rig.cameras' must be \\[\\[rig.cameras\\]\\] "
                                           "tables"),
    ({"rig": {"file": "nowhere.toml"}}, "'rig.file' = 'nowhere.toml': rig file not found"),
])
def test_bad_data_and_rig_settings_name_the_key(simulated, monkeypatch, settings, message):
    monkeypatch.chdir(simulated[0])
    with pytest.raises(ConfigError, match=message):
        config.validate({"truth": {"grid": 8}, **settings})


def test_inline_cameras_make_the_same_scene_as_the_rig_file(simulated, monkeypatch):
    folder, _, rig = simulated
    monkeypatch.chdir(folder)
    cameras = rig_records(paper_rig(VoxelGrid.poolfire(8), n_pixels=4))
    base = {"truth": {"grid": 8}, "spectrum": SPECTRUM}
    inline = config.validate({**base, "rig": {"cameras": cameras}})
    from_file = config.validate({**base, "rig": {"file": "rig.toml"}})
    assert config.load(toml(folder / "inline.toml", config.dumps(inline))) == inline
    a, b = (runner.build_scene(c) for c in (inline, from_file))
    np.testing.assert_array_equal(a.segments.length, b.segments.length)
    np.testing.assert_array_equal(a.segments.voxel, b.segments.voxel)


def test_a_window_that_misses_the_measured_wavenumbers_is_named(simulated, monkeypatch):
    monkeypatch.chdir(simulated[0])
    cfg = config.validate({"truth": {"grid": 8}, "data": {"source": "m.nc"},
                           "spectrum": {"min": 670.0, "max": 690.0, "step": 0.1}})
    with pytest.raises(ConfigError, match="'data.source' = 'm.nc' measures 668-682 cm-1, "
                                          "outside the window"):
        runner.build_scene(cfg, measured=runner.read_data(cfg))


def test_bad_pixels_leave_the_data_term_of_a_run(simulated, tmp_path, monkeypatch):
    folder, _, _ = simulated
    monkeypatch.chdir(folder)
    measured = read_measurement("m.nc")
    sigma = np.broadcast_to(measured.measurement.sigma, measured.measurement.data.shape).copy()
    sigma[[5, 40]] = np.inf  # two bad pixels
    data = np.where(np.isinf(sigma), 0.0, measured.measurement.data).astype(np.float32)
    write_measurement(MeasurementFile(Measurement(data, sigma, True, {}), measured.rig,
                                      measured.wavenumber, measured.resolution),
                      tmp_path / "masked.nc")
    base = {"truth": {"grid": 8}, "spectrum": SPECTRUM, "solver": SOLVER,
            "data": {"source": str(tmp_path / "masked.nc")}}
    from_data = runner.run_experiment(config.validate(base), tmp_path / "from-data",
                                      progress=False)  # the band tomography drops the pixels
    summary = runner.run_experiment(config.validate({**base, "init": {"kind": "ambient"}}),
                                    tmp_path / "run", progress=False)
    assert summary["loss"]["final"] < summary["loss"]["initial"]
    assert from_data["chi2_per_measurement"]["initial"] < summary["chi2_per_measurement"][
        "initial"]
    saved = np.load(tmp_path / "run" / "data.npz")
    keep = np.isfinite(saved["sigma"])
    chi2 = np.sum(((saved["simulated"] - saved["measured"]) / saved["sigma"])[keep] ** 2)
    assert summary["chi2_per_measurement"]["final"] == pytest.approx(chi2 / keep.sum(),
                                                                     rel=1e-6)
    assert keep.sum() == (64 - 2) * measured.wavenumber.size


def test_a_rig_stating_another_resolution_is_refused(simulated, monkeypatch):
    folder, _, _ = simulated
    monkeypatch.chdir(folder)
    write_rig(paper_rig(VoxelGrid.poolfire(8), n_pixels=4), folder / "rig4.toml",
              {"resolution": 4.0})
    cfg = config.validate({"truth": {"grid": 8}, "spectrum": SPECTRUM,
                           "rig": {"file": "rig4.toml"}})
    with pytest.raises(InputDataError, match="resolution 4 cm-1 but \\[instrument\\] and "
                                             "\\[spectrum\\] models 8 cm-1"):
        runner.build_scene(cfg)


def test_a_rig_window_lies_inside_the_simulated_one_and_narrows_the_measured_channels(
        simulated, monkeypatch):
    folder, _, _ = simulated
    monkeypatch.chdir(folder)
    rig = paper_rig(VoxelGrid.poolfire(8), n_pixels=4)
    write_rig(rig, folder / "rig_window.toml", {"window": [650.0, 700.0]})
    base = {"truth": {"grid": 8}, "spectrum": SPECTRUM, "rig": {"file": "rig_window.toml"}}
    with pytest.raises(InputDataError, match="rig_window.toml: camera 0: 'window' = 650-700 "
                                             "cm-1 reaches outside the window 660-690 cm-1 "
                                             "that \\[instrument\\] and \\[spectrum\\] models"):
        runner.build_scene(config.validate(base))
    cfg = config.validate({**base, "data": {"source": "m.nc"}})  # the channels set the window
    scene = runner.build_scene(cfg, measured=runner.read_data(cfg))
    assert (scene.out_wavenumber.min(), scene.out_wavenumber.max()) == (668.0, 682.0)
    write_rig(rig, folder / "rig_narrow.toml", [{"window": [672.0, 676.0]}, {}, {}, {}])
    cfg = config.validate({**cfg, "rig": {"file": "rig_narrow.toml"}})
    measured = runner.read_data(cfg)
    assert measured.windows == ((672.0, 676.0), None, None, None)
    per_pixel = measured.measurement.measured.sum(axis=1)  # channels every 2 cm-1
    assert set(per_pixel[:16]) == {3} and set(per_pixel[16:]) == {8}
    assert runner.build_scene(cfg, measured=measured).camera_windows == measured.windows


def test_a_file_without_noise_is_reported_as_an_unweighted_misfit(simulated, tmp_path,
                                                                  monkeypatch):
    folder, _, _ = simulated
    measured = read_measurement(folder / "m.nc")
    clean = Measurement(measured.measurement.data, np.ones_like(measured.measurement.data),
                        noisy=False, provenance={})
    write_measurement(MeasurementFile(clean, measured.rig, measured.wavenumber,
                                      measured.resolution), tmp_path / "clean.nc")
    monkeypatch.chdir(tmp_path)
    cfg = config.validate({"truth": {"grid": 8}, "data": {"source": "clean.nc"},
                           "spectrum": dict(SPECTRUM), "solver": dict(SOLVER)})
    summary = runner.run_experiment(cfg, tmp_path / "run", progress=False)
    assert summary["noisy_data"] is False and summary["noise_weighted_misfit"] is False
    assert summary["protocol"]["noise"].startswith("unknown (the file holds no noise)")
    log = (tmp_path / "run" / "log.txt").read_text()
    assert "mean square misfit [(W/(m2 sr cm-1))^2]" in log and "chi2/M" not in log
    chosen = config.validate(dict(cfg, regularizer={"kind": "tikhonov", "lambda": "discrepancy"}))
    with pytest.raises(ConfigError, match="'discrepancy' needs data with a noise σ"):
        runner.run_experiment(chosen, tmp_path / "chosen", progress=False)
