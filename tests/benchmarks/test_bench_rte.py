"""The RTE benchmark's stage timings run on a scene whose bins hold several spectral points."""

import jax.numpy as jnp
import numpy as np
from bench_rte import stages

from invflame.phantoms import make_phantom
from invflame.scene import Scene


def test_every_stage_is_timed_on_the_default_scene():
    scene = Scene.paper(6, 2, rays_per_pixel=1)
    assert scene.tables.n_points > scene.tables.n_eta  # saturated bins split into points
    fields = jnp.asarray(make_phantom("synthetic", grid=scene.grid).values, jnp.float32)
    times = stages(scene, fields, repeats=1, clock="wall")
    assert set(times) == {"spline tau", "Planck B", "transmission", "reductions",
                          "forward sweep", "reverse sweep", "reverse sweep, Numba", "batching"}
    assert all(np.isfinite(t) and t > 0 for t in times.values()), times
