#!/usr/bin/env bash
# The benchmarks of docs/performance.md's GPU section, on a machine with a CUDA GPU, a jaxlib
# with its CUDA plugin and a CUDA build of torch:
#
#     bash benchmarks/gpu.sh [LOG_DIR]
#
# Runs, at the paper configuration (60³ voxels, four cameras of 32×32 pixels, one ray per
# pixel, 1876 wavenumbers): bench_rte.py (the kernel against exp-only, wall clock),
# bench_neural.py (the neural field's epoch against the voxel one, torch on the GPU),
# bench_objective.py (the voxel objective compiled against the operators' methods),
# bench_paper_epoch.py (the paper preset's VG/TV and NN/Tikh. through the runner) and
# bench_regularizer.py (the voxel regularizers on the host's CPU). Each one's
# output goes to the terminal and to LOG_DIR/NAME.log (default LOG_DIR: results/gpu); one that
# fails or runs past its limit (seconds, below) is reported and the next one runs. JAX does
# not reserve most of the GPU ahead (XLA_PYTHON_CLIENT_PREALLOCATE=false), so that torch has
# room and the peaks printed are what was in use. PYTHON names the interpreter (default
# python3).
set -u
here=$(cd "$(dirname "$0")" && pwd)
logs=${1:-results/gpu}
python=${PYTHON:-python3}
mkdir -p "$logs"
export XLA_PYTHON_CLIENT_PREALLOCATE=false PYTHONUNBUFFERED=1

run() {
    local name=$1 limit=$2
    shift 2
    echo "== $name: $*"
    timeout "$limit" "$python" "$here/$1" "${@:2}" 2>&1 | tee "$logs/$name.log"
    echo "== $name: exit status ${PIPESTATUS[0]} (124: past its ${limit} s)"
}

nvidia-smi --query-gpu=name,driver_version,memory.total,memory.used,clocks.sm --format=csv
"$python" -c "import jax, torch; print('jax', jax.__version__, jax.devices(), '| torch', \
torch.__version__, 'CUDA' if torch.cuda.is_available() else 'no CUDA')"
run rte 200 bench_rte.py --rays-per-pixel 1 --repeats 5 --clock wall
run neural 150 bench_neural.py --rays-per-pixel 1 --n-coarse 32 --n-fine 32 --repeats 3 \
    --centres --torch-device cuda
run objective 100 bench_objective.py --repeats 10
run paper_epoch 180 bench_paper_epoch.py --epochs 3 --torch-device cuda
run regularizer 60 bench_regularizer.py
