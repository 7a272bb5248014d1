#!/usr/bin/env bash
# Reproduce the packaged ground truth invflame/data/poolfire_t0.9.npz.
#
# Runs the OpenFOAM v1912 fireFoam tutorial combustion/fireFoam/LES/smallPoolFire3D
# (1 m cube, 60^3 cells, 0.2 m square CH4 inlet at 0.01 m/s, one-step infinitely fast
# chemistry, fvDOM radiation) to t = END_TIME on NP cores with ASCII output, reconstructs the
# decomposed case and converts that time to the invflame field format (T in K, mole
# fractions of CO2, H2O, CH4) on the regular 60^3 grid of the mesh's cells.
#
# Needs Debian's openfoam and openfoam-examples packages:
#     apt-get install -y openfoam openfoam-examples
#
# Usage: scripts/make_poolfire.sh [-t END_TIME] [-n NP] [-w WORKDIR] [-o OUT.npz] [-c]
#   -t END_TIME  simulated time in s to run to and convert (default 0.9)
#   -n NP        MPI processes (default 2)
#   -w WORKDIR   where the case is run (default runs/poolfire_case; replaced unless -c)
#   -o OUT       output .npz (default invflame/data/poolfire_t<END_TIME>.npz)
#   -c           convert only: reuse the finished case in WORKDIR, skip the simulation
# Environment: PYTHON (default .venv/bin/python, else python3),
#              FOAM_TUTORIAL (the tutorial folder), WM_PROJECT_DIR (default /usr/share/openfoam).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
end_time=0.9
nproc=2
workdir="$repo/runs/poolfire_case"
out=""
convert_only=0
while getopts "t:n:w:o:ch" opt; do
    case "$opt" in
        t) end_time="$OPTARG" ;;
        n) nproc="$OPTARG" ;;
        w) workdir="$OPTARG" ;;
        o) out="$OPTARG" ;;
        c) convert_only=1 ;;
        h) sed -n '2,21p' "$0"; exit 0 ;;
        *) sed -n '2,21p' "$0" >&2; exit 2 ;;
    esac
done
out="${out:-$repo/invflame/data/poolfire_t${end_time}.npz}"
python="${PYTHON:-}"
if [ -z "$python" ]; then
    if [ -x "$repo/.venv/bin/python" ]; then python="$repo/.venv/bin/python"; else python=python3; fi
fi
tutorial="${FOAM_TUTORIAL:-/usr/share/doc/openfoam-examples/examples/combustion/fireFoam/LES/smallPoolFire3D}"
export WM_PROJECT_DIR="${WM_PROJECT_DIR:-/usr/share/openfoam}"

for tool in blockMesh topoSet createPatch decomposePar fireFoam reconstructPar foamDictionary \
            mpirun; do
    command -v "$tool" > /dev/null || {
        echo "error: $tool not found; install OpenFOAM: apt-get install -y openfoam openfoam-examples" >&2
        exit 1
    }
done

step() {  # step NAME CMD...: run CMD in the case, log to log.NAME, stop with the log tail on failure
    local name="$1"; shift
    echo "[$(date +%T)] $name"
    if ! "$@" > "log.$name" 2>&1; then
        tail -n 30 "log.$name" >&2
        echo "error: $name failed; full log in $workdir/log.$name" >&2
        exit 1
    fi
}

start=$SECONDS
if [ "$convert_only" -eq 0 ]; then
    [ -d "$tutorial" ] || {
        echo "error: tutorial not found at $tutorial (apt-get install -y openfoam-examples)" >&2
        exit 1
    }
    rm -rf "$workdir"
    mkdir -p "$(dirname "$workdir")"
    cp -r "$tutorial" "$workdir"
    chmod -R u+w "$workdir"
    cd "$workdir"

    # One written time, END_TIME, in ASCII; NP subdomains split along the height.
    foamDictionary -entry endTime -set "$end_time" system/controlDict > /dev/null
    foamDictionary -entry writeInterval -set "$end_time" system/controlDict > /dev/null
    foamDictionary -entry writeFormat -set ascii system/controlDict > /dev/null
    foamDictionary -entry writeCompression -set off system/controlDict > /dev/null
    foamDictionary -entry numberOfSubdomains -set "$nproc" system/decomposeParDict > /dev/null
    foamDictionary -entry coeffs.n -set "(1 $nproc 1)" system/decomposeParDict > /dev/null

    # The tutorial's Allrun, then reconstruction.
    step blockMesh blockMesh
    step topoSet topoSet
    step createPatch createPatch -overwrite
    cp 0/ph_rgh.orig 0/ph_rgh
    step decomposePar decomposePar -force
    mpi_flags=()
    if [ "$(id -u)" -eq 0 ]; then mpi_flags=(--allow-run-as-root --oversubscribe); fi
    step fireFoam mpirun "${mpi_flags[@]}" -np "$nproc" fireFoam -parallel
    step reconstructPar reconstructPar -time "$end_time"
    echo "[$(date +%T)] simulation done in $((SECONDS - start)) s"
else
    cd "$workdir"
fi

echo "[$(date +%T)] converting t = $end_time s to $out"
"$python" - "$workdir" "$end_time" "$out" "$tutorial" <<'EOF'
import sys

from invflame.openfoam import read_case

case, time, out, tutorial = sys.argv[1:]
field = read_case(case, time)
field.metadata["case"] = "combustion/fireFoam/LES/smallPoolFire3D (OpenFOAM tutorial)"
field.metadata["tutorial_path"] = tutorial
field.save(out)
print(field.summary())
EOF
echo "[$(date +%T)] done in $((SECONDS - start)) s: $out"
