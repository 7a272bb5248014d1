"""Run by ``test_rte_sweep_cpu.py`` in a process of its own, with an empty cache folder (Numba
shows the code of what it compiled itself, not of what it loaded from its cache): compiles the
sweeps of one gas in float32 and prints, as JSON, per sweep whether its LLVM IR asks for
512-bit vectors and how many of its instructions name a 512-bit register, and whether the
processor has AVX-512."""

import json
import re

import llvmlite.binding as llvm
import numba
import numpy as np

from operators.rte.numba_targets import compiled_sweeps

sweeps = compiled_sweeps(1, 1, "float32")
n_rays, n_eta = 2, 32
coef, background = np.zeros((1, 8, n_eta), np.float32), np.zeros((1, n_eta), np.float32)
index, offset = np.zeros((n_rays, 1), np.int32), np.zeros((n_rays, 1), np.float32)
amount, spectrum = np.zeros((n_rays, 1, 1), np.float32), np.zeros((n_rays, n_eta), np.float32)
rays = np.zeros(n_rays, np.int32)
common = (coef, index, amount, offset, rays, rays)
arguments = {
    "forward": (*common, background, spectrum),
    "forward_mode": (*common, background, amount, offset, background, spectrum, spectrum),
    "reverse": (*common, spectrum, spectrum, np.zeros((n_rays, 1, 2), np.float32),
                np.zeros((0, n_eta), np.float32)),
}
report = {"avx512f": "+avx512f" in llvm.get_host_cpu_features().flatten().split(",")}
for name, args in arguments.items():
    sweep = getattr(sweeps, name)
    sweep.compile(tuple(numba.typeof(a) for a in args))
    signature = sweep.signatures[0]
    report[name] = {"attribute": '"prefer-vector-width"="512"' in sweep.inspect_llvm(signature),
                    "zmm": len(re.findall(r"%zmm", sweep.inspect_asm(signature)))}
print(json.dumps(report))
