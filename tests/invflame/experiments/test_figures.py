"""The field figures of a comparison, from its run folders."""

import matplotlib.image
import numpy as np

from invflame.experiments.figures import field_figures, run_fields


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
