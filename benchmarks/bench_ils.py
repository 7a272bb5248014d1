"""ILSConvolution speed at the paper's size: 4096 rays, 650-725 cm-1 at 0.04 cm-1, 8 cm-1.

Prints the time of the forward and adjoint (one dense matrix product each) next to an
FFT-based circular convolution of the same spectra, as a yardstick for the alternative.

    python benchmarks/bench_ils.py
"""

import time

import numpy as np

import operators as op


def best_of(fun, repeats=7):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fun()
        times.append(time.perf_counter() - start)
    return min(times)


def measure(dtype, n_rays=4096):
    eta = np.arange(650.0, 725.0 + 1e-9, 0.04)
    ils = op.ILSConvolution(eta, n_rays=n_rays, resolution=8.0, dtype=dtype)
    x = np.random.default_rng(0).random(ils.dims).astype(dtype)
    y = ils(x)
    kernel = np.fft.rfft(np.fft.ifftshift(op.ils.triangular_ils(eta - eta.mean(), 8.0)))
    t_fwd = best_of(lambda: ils(x))
    t_adj = best_of(lambda: ils.adjoint(y))
    t_fft = best_of(lambda: np.fft.irfft(np.fft.rfft(x, axis=1) * kernel, eta.size, axis=1))
    print(f"{np.dtype(dtype).name}: {n_rays} rays x {eta.size} -> {ils.dimsd[1]} points: "
          f"forward {1e3 * t_fwd:.2f} ms, adjoint {1e3 * t_adj:.2f} ms, "
          f"FFT convolution alone {1e3 * t_fft:.2f} ms")


def main():
    for dtype in (np.float32, np.float64):
        measure(dtype)


if __name__ == "__main__":
    main()
