"""Scaling of one epoch (forward + VJP): over devices, and with rays, segments and wavenumbers.

Run: ``python benchmarks/bench_scaling.py [--repeats 5] [--quick]`` (about 2–3 minutes on a
2-core CPU). Prints three tables, the inputs of the cost model in ``docs/scaling.md``:

1. **Strong scaling.** The voxel scene of a small configuration (24³ voxels, four cameras of
   16² pixels, 660–700 cm⁻¹ at 0.1 cm⁻¹), one epoch = value and gradient of
   ``0.5 ||H(f) - g||²`` through :meth:`invflame.scene.Scene.forward`, on 1 device and with
   its rays split over 2 devices (``Scene(devices=2)``). Each count runs in a fresh process
   with ``XLA_FLAGS=--xla_force_host_platform_device_count=N``: on a CPU these "devices"
   share the same cores, so this checks the overhead of sharding more than it shows a speedup.
2. **Growth.** The bare emission kernel (:func:`operators.rte.kernel.emission_radiance`,
   synthetic tables, two absorbing species, every segment real) for three sizes each of rays,
   segments per ray and spectral points, the others fixed: time, ns per element (segment ×
   wavenumber) and the fitted exponent of time versus size.
3. **Problem sizes.** Rays, segments (Amanatides–Woo, from the actual geometry) and
   elements of the study's setup (60³, 4 × 32², 650–725 cm⁻¹ at 0.04 cm⁻¹) and of a
   16-camera ring of 128² pixels around a 128³ grid.
4. **Cost model** (``docs/scaling.md``): its memory estimate checked against XLA's own
   figure for the scene of table 1, and its predictions (time and memory per epoch) for the
   setups of table 3 on one and on eight GPUs, from the stated assumptions in
   :data:`GPU`. These are predictions, not measurements.
"""

import argparse
import json
import os
import subprocess
import sys

import numpy as np
from timing import best_time

DEVICES_FLAG = "--xla_force_host_platform_device_count"
GPU = {
    # Assumed cost of one element (segment x wavenumber) of an epoch (forward + VJP) on one
    # NVIDIA H100 SXM: ~50 B of HBM traffic per element (state arrays of the sweeps) at
    # 3.35 TB/s (NVIDIA H100 datasheet) plus ~150 B of L2 reads of table rows, at ~40 % of
    # peak: 0.1 ns. An assumption for planning, not a measurement.
    "s_per_element": 0.1e-9,
    # The study's measured epoch (Table 1, VG: 430 ms for the 3.02e8 elements of its setup,
    # on its own GPU and code): a pessimistic alternative.
    "s_per_element_study": 0.430 / 3.02e8,
    "s_per_step": 10e-6,          # launch latency of one sequential segment step (fwd or bwd)
    "allreduce_bytes_per_s": 200e9,  # effective NCCL all-reduce bandwidth over NVLink
    "memory_budget": 2**30,       # bytes of one ray batch (DEFAULT_MEMORY_BUDGET["gpu"])
}
N_COEF = 12  # table rows per wavenumber: 4 per absorbing species (CO2, H2O) + 4 for Planck
N_FIELDS = 4
SCALING_CONFIG = {"truth": {"grid": 24, "source": "synthetic"}, "rig": {"pixels": 16},
                  "spectrum": {"min": 660.0, "max": 700.0, "step": 0.1}}


# -- 1. strong scaling (child processes) ---------------------------------------------------
def epoch_on_devices(n_devices: int, repeats: int) -> dict:
    """In a process with ``n_devices`` devices: one epoch of the scaling scene, timed."""
    import jax
    import jax.numpy as jnp

    from invflame.experiments import config
    from invflame.experiments.runner import build_scene, load_truth

    cfg = config.validate(SCALING_CONFIG)
    plain = build_scene(cfg)
    scene = plain if n_devices == 1 else build_scene_on(cfg, n_devices)
    fields = jnp.asarray(load_truth(cfg, scene.grid).values, jnp.float32)
    data = plain.forward(fields) * 1.01
    epoch = jax.jit(jax.value_and_grad(lambda f: 0.5 * jnp.sum((scene.forward(f) - data) ** 2)))
    temp = epoch.lower(fields).compile().memory_analysis().temp_size_in_bytes
    return {"devices": n_devices, "rays": scene.n_rays,
            "segments": int(scene.segments.n_segments), "n_eta": int(scene.wavenumber.size),
            "max_segments": int(scene.segments.max_segments), "batch_rays": scene.batch_rays,
            "n_coef": int(scene.tables.coef.shape[1]), "xla_temp_bytes": int(temp),
            "seconds": best_time(lambda: epoch(fields), repeats)}


def build_scene_on(cfg: dict, n_devices: int):
    """The configuration's scene with :meth:`Scene.forward` split over ``n_devices``."""
    from invflame.experiments.runner import build_scene
    from invflame.scene import Scene

    s = build_scene(cfg)
    return Scene(s.grid, s.rig, s.table, resolution=s.resolution, out_wavenumber=s.out_wavenumber,
                 devices=n_devices)


def strong_scaling(repeats: int) -> list[dict]:
    results = []
    for n in (1, 2):
        env = dict(os.environ, XLA_FLAGS=f"{DEVICES_FLAG}={n}")
        done = subprocess.run([sys.executable, __file__, "--child-devices", str(n),
                               "--repeats", str(repeats)], env=env, capture_output=True,
                              text=True, check=False)
        if done.returncode != 0:
            raise RuntimeError(f"the {n}-device run failed:\n{done.stderr[-3000:]}")
        results.append(json.loads(done.stdout.strip().splitlines()[-1]))
    return results


# -- 2. growth of the kernel's cost ----------------------------------------------------------
def synthetic_tables(n_eta: int):
    """Kernel tables of two absorbing species with smooth random cross-sections (cm²)."""
    from operators.rte import RTETables
    from operators.tabulated import PiecewiseCubic

    rng = np.random.default_rng(0)
    wavenumber = np.linspace(650.0, 725.0, n_eta)
    temperatures = np.linspace(250.0, 2500.0, 10)
    sigma = 1e-20 * (1 + rng.random((temperatures.size, 2, n_eta)))
    coef = PiecewiseCubic(temperatures, sigma).coef
    return RTETables.from_spline(wavenumber, temperatures, coef)


def kernel_epoch(n_rays: int, n_seg: int, n_eta: int, repeats: int) -> float:
    """Seconds of value and gradient of the kernel on ``n_rays × n_seg`` real segments."""
    import jax
    import jax.numpy as jnp

    from operators.rte import emission_radiance

    tables = synthetic_tables(n_eta)
    rng = np.random.default_rng(1)
    fields = jnp.asarray(np.stack([rng.uniform(300.0, 2000.0, (n_rays, n_seg)),
                                   rng.uniform(0.0, 0.1, (n_rays, n_seg)),
                                   rng.uniform(0.0, 0.2, (n_rays, n_seg))]), jnp.float32)
    lengths = jnp.full((n_rays, n_seg), 1.0 / n_seg, jnp.float32)
    weights = jnp.asarray(rng.standard_normal((n_rays, n_eta)), jnp.float32)
    epoch = jax.jit(jax.value_and_grad(
        lambda f: jnp.sum(weights * emission_radiance(tables, f, lengths))))
    return best_time(lambda: epoch(fields), repeats)


def growth(repeats: int, base: tuple[int, int, int]) -> list[dict]:
    rows, measured = [], {}
    for axis, name in enumerate(("rays", "segments/ray", "wavenumbers")):
        sizes, times = [], []
        for factor in (1, 2, 4):
            shape = list(base)
            shape[axis] *= factor
            if tuple(shape) not in measured:
                measured[tuple(shape)] = kernel_epoch(*shape, repeats)
            seconds = measured[tuple(shape)]
            sizes.append(shape[axis])
            times.append(seconds)
            rows.append({"vary": name, "rays": shape[0], "segments": shape[1],
                         "n_eta": shape[2], "seconds": seconds,
                         "ns_per_element": 1e9 * seconds / np.prod(shape)})
        slope = np.polyfit(np.log(sizes), np.log(times), 1)[0]
        for row in rows[-3:]:
            row["exponent"] = slope
    return rows


# -- 3. problem sizes -------------------------------------------------------------------------
def ring_rig(grid, n_cameras: int, n_pixels: int, distance: float = 1.5,
             focal_length: float = 0.59):
    """``n_cameras`` pinhole cameras equally spaced on a horizontal circle, framing the box."""
    from invflame.geometry.camera import PinholeCamera, framing_sensor_size
    from invflame.geometry.rig import CameraRig

    up = np.eye(3)[grid.up_axis]
    a, b = (axis for axis in range(3) if axis != grid.up_axis)
    angles = 2 * np.pi * np.arange(n_cameras) / n_cameras
    positions = [grid.centre + distance * (np.cos(t) * np.eye(3)[a] + np.sin(t) * np.eye(3)[b])
                 for t in angles]
    sensor = max(max(framing_sensor_size(p, grid.centre, up, focal_length, grid.corners()))
                 for p in positions)
    return CameraRig(tuple(PinholeCamera(p, grid.centre, up, focal_length, (sensor, sensor),
                                         (n_pixels, n_pixels)) for p in positions))


def problem_sizes() -> list[dict]:
    """Rays, segments and elements of the study's setup and of a 16-camera 128² / 128³ rig.

    For the ring, cameras at 0°, 22.5° and 45° are traversed and weighted 4, 8 and 4 (the
    ring's symmetry classes), rather than all sixteen.
    """
    from invflame.geometry import VoxelGrid, paper_rig, traverse
    from invflame.geometry.rig import CameraRig

    rows = []
    grid = VoxelGrid.poolfire(60)
    seg = traverse(grid, *paper_rig(grid, n_pixels=32).rays())
    rows.append({"setup": "study: 60^3, 4 x 32^2 px", "rays": seg.n_rays,
                 "segments": int(seg.n_segments), "max_segments": int(seg.max_segments)})
    grid = VoxelGrid.poolfire(128)
    ring = ring_rig(grid, 16, 128)
    segments, longest = 0, 0
    for camera, weight in zip(ring.cameras[:3], (4, 8, 4), strict=True):
        seg = traverse(grid, *CameraRig((camera,)).rays())
        segments += weight * int(seg.n_segments)
        longest = max(longest, int(seg.max_segments))
    rows.append({"setup": "ring: 128^3, 16 x 128^2 px", "rays": ring.n_rays,
                 "segments": segments, "max_segments": longest})
    return rows


# -- 4. the cost model ------------------------------------------------------------------------
def working_memory(rays: int, max_segments: int, n_eta: int, batch_rays: int,
                   n_devices: int = 1, n_coef: int = N_COEF) -> float:
    """Bytes of one device's working arrays in an epoch (float32), see ``docs/scaling.md``.

    Per device, ``r = rays / n_devices``: segment fields gathered, batched, and their
    cotangents (48 r S), spectra kept for the VJP (radiance, cotangent and their batched
    copies: 16 r N) and one batch's working set ``b N 4 (16 + n_coef)``.
    """
    r = rays / n_devices
    return 48 * r * max_segments + 16 * r * n_eta + batch_rays * n_eta * 4 * (16 + n_coef)


def resident_memory(rays: int, max_segments: int, n_eta: int, n_voxels: int,
                    n_devices: int = 1) -> float:
    """Bytes kept between epochs on one device: ray geometry (int64 voxel + float32 length
    per segment slot), tables (~60 intervals), parameters with gradient and Adam moments."""
    return (12 * rays / n_devices * max_segments + 60 * N_COEF * n_eta * 4
            + 4 * N_FIELDS * n_voxels * 4)


def predict(rays: int, segments: int, max_segments: int, n_eta: int, n_voxels: int,
            n_devices: int, s_per_element: float) -> dict:
    """Predicted seconds and bytes per device of one epoch on ``n_devices`` GPUs."""
    r = -(-rays // n_devices)
    batch = max(1, min(r, GPU["memory_budget"] // (n_eta * 4 * (16 + N_COEF))))
    steps = 2 * -(-r // batch) * max_segments                # forward and reverse sweeps
    parameters = N_FIELDS * n_voxels * 4
    allreduce = 0.0 if n_devices == 1 else (2 * (n_devices - 1) / n_devices * parameters
                                            / GPU["allreduce_bytes_per_s"] + 50e-6)
    seconds = (segments * n_eta * s_per_element / n_devices + steps * GPU["s_per_step"]
               + allreduce)
    memory = (working_memory(rays, max_segments, n_eta, batch, n_devices)
              + resident_memory(rays, max_segments, n_eta, n_voxels, n_devices))
    return {"seconds": seconds, "bytes": memory, "batch": batch, "steps": steps,
            "allreduce": allreduce}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed repetitions (best kept)")
    parser.add_argument("--quick", action="store_true",
                        help="smaller growth sizes (a few seconds less)")
    parser.add_argument("--child-devices", type=int, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child_devices is not None:
        print(json.dumps(epoch_on_devices(args.child_devices, args.repeats)))
        return

    import jax

    print(f"backend {jax.default_backend()}, {os.cpu_count()} CPU cores\n")
    print("1. strong scaling, one epoch (forward + VJP) of the voxel scene")
    scaling = strong_scaling(args.repeats)
    for r in scaling:
        print(f"   {r['devices']} device(s): {1e3 * r['seconds']:8.1f} ms  "
              f"({r['rays']} rays, {r['segments']} segments, {r['n_eta']} wavenumbers; "
              f"speedup {scaling[0]['seconds'] / r['seconds']:.2f})")

    base = (128, 16, 128) if args.quick else (256, 32, 256)
    print(f"\n2. growth of the kernel epoch around (rays, segments/ray, n_eta) = {base}")
    print(f"   {'vary':>13} {'rays':>6} {'seg':>5} {'n_eta':>6} {'ms':>9} {'ns/elem':>8} "
          f"{'exponent':>8}")
    for r in growth(args.repeats, base):
        print(f"   {r['vary']:>13} {r['rays']:6d} {r['segments']:5d} {r['n_eta']:6d} "
              f"{1e3 * r['seconds']:9.1f} {r['ns_per_element']:8.2f} {r['exponent']:8.2f}")

    print("\n3. problem sizes (elements = segments x wavenumbers)")
    sizes = problem_sizes()
    windows = (("650-725 cm-1 at 0.04", 1876), ("600-800 cm-1 at 0.04", 5001))
    for r in sizes:
        for label, n_eta in windows:
            print(f"   {r['setup']:>28}, {label}: {r['rays']} rays, {r['segments']:.4g} "
                  f"segments (max {r['max_segments']}/ray), {r['segments'] * n_eta:.3g} "
                  "elements")

    print("\n4. cost model")
    one = scaling[0]
    model = working_memory(one["rays"], one["max_segments"], one["n_eta"], one["batch_rays"],
                           n_coef=one["n_coef"])
    print(f"   check, scene of table 1 on 1 device: working memory model {model / 2**20:.1f} "
          f"MiB, XLA temporaries {one['xla_temp_bytes'] / 2**20:.1f} MiB")
    print("   PREDICTIONS for H100-class GPUs (assumptions in GPU, docs/scaling.md); time per "
          "epoch at 0.1 ns/element [at the study's 1.42 ns/element], memory per GPU")
    for r, n_voxels in zip(sizes, (60**3, 128**3), strict=True):
        for label, n_eta in windows:
            for n_devices in (1, 8):
                fast = predict(r["rays"], r["segments"], r["max_segments"], n_eta, n_voxels,
                               n_devices, GPU["s_per_element"])
                slow = predict(r["rays"], r["segments"], r["max_segments"], n_eta, n_voxels,
                               n_devices, GPU["s_per_element_study"])
                print(f"   {r['setup']:>28}, {label}, {n_devices} GPU(s): "
                      f"{1e3 * fast['seconds']:8.1f} ms [{1e3 * slow['seconds']:8.1f} ms], "
                      f"{fast['bytes'] / 2**30:6.2f} GiB (batch {fast['batch']} rays, "
                      f"{fast['steps']} steps, all-reduce {1e3 * fast['allreduce']:.2f} ms)")


if __name__ == "__main__":
    main()
