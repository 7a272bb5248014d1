"""A scene with a background and soot on two forced CPU devices against one device.

``XLA_FLAGS=--xla_force_host_platform_device_count=2`` must be set before JAX starts, so
``test_scene_background.py`` runs this file as a script with that environment. It prints one
JSON object: the devices seen and the relative differences of the forward map and its VJP.
"""

import json
import sys
from pathlib import Path

import numpy as np

from invflame.background import BlackbodyWall
from invflame.geometry import VoxelGrid, paper_rig
from invflame.scene import Scene

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_scene import small_table, smooth_field  # noqa: E402

grid = VoxelGrid.cube(5, size=1.0, centre=(0.0, 0.5, 0.0))
settings = dict(resolution=4.0, dtype=np.float64, planck="exact",
                background=BlackbodyWall(600.0, 0.7), soot=np.full(grid.shape, 1e-6))
one = Scene(grid, paper_rig(grid, n_pixels=3), small_table(), **settings)
two = Scene(grid, paper_rig(grid, n_pixels=3), small_table(), devices=2, **settings)
fields = smooth_field(grid)
w = np.random.default_rng(0).standard_normal(one.data_shape)
pairs = {"forward": (one.operator(fields), two.operator(fields)),
         "vjp": (one.operator.vjp(fields, w), two.operator.vjp(fields, w))}
print(json.dumps({"devices": int(two.mesh.devices.size)}
                 | {key: float(np.abs(a - b).max() / np.abs(a).max())
                    for key, (a, b) in pairs.items()}))
