"""A run from a measurement file records the file's instrument, which it uses in place of
``[instrument]``, in its ``config.toml`` and ``summary.json``."""

import json

import numpy as np

from invflame.experiments import config, runner
from invflame.geometry import VoxelGrid, paper_rig
from invflame.measurement import Measurement
from invflame.measurement_file import MeasurementFile, write_measurement

RIG = paper_rig(VoxelGrid.poolfire(8), n_pixels=3)
WAVENUMBER = np.arange(666.0, 684.5, 1.0)  # cm-1, sampled for a 4 cm-1 resolution


def test_the_run_records_the_resolution_and_wavenumbers_of_the_file(tmp_path):
    data = np.random.default_rng(0).uniform(0.0, 1.0, (RIG.n_rays, WAVENUMBER.size))
    source = write_measurement(MeasurementFile(Measurement(data, np.full(WAVENUMBER.size, 1e-2),
                                                           True, {}), RIG, WAVENUMBER, 4.0),
                               tmp_path / "m.nc")
    cfg = config.validate({"truth": {"grid": 8}, "data": {"source": str(source)},
                           "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
                           "init": {"kind": "ambient"},
                           "solver": {"name": "adam", "iterations": 2, "options": {"lr": 0.01}}})
    assert cfg["instrument"]["resolution"] == 8.0
    summary = runner.run_experiment(cfg, tmp_path / "run", progress=False)

    used = {"from": f"the measurement file data.source = {str(source)!r}, in place of "
                    "[instrument]",
            "resolution": 4.0, "apodization": "triangular", "wavenumber_min": 666.0,
            "wavenumber_max": 684.0, "n_wavenumbers": 19, "windows": None}
    assert summary["measured_instrument"] == used
    saved = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert saved["measured_instrument"] == used
    text = (tmp_path / "run" / "config.toml").read_text()
    assert text.startswith(f"# [instrument] is not used: the measurement file data.source = "
                           f"{str(source)!r} sets the instrument:\n# resolution = 4 cm-1, "
                           "apodization = 'triangular', 19 wavenumbers 666-684 cm-1\n")
    # the comment changes no value; the window is widened 4 resolutions beyond 666-684 cm-1
    widened = {**cfg, "spectrum": {**cfg["spectrum"], "min": 650.0, "max": 700.0}}
    assert config.load(tmp_path / "run" / "config.toml") == widened
    again = runner.run_experiment(cfg, tmp_path / "run", resume=True, progress=False)
    assert again["measured_instrument"] == used

