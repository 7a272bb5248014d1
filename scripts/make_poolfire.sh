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
# Usage: scripts/make_poolfire.sh [-t END_TIME] [-i INTERVAL] [-u VELOCITY] [-n NP] [-w WORKDIR]
#                                 [-o OUT] [-c]
#   -t END_TIME  simulated time in s to run to and convert (default 0.9)
#   -i INTERVAL  also write and convert every INTERVAL s up to END_TIME (default: END_TIME only);
#                OUT is then a folder receiving poolfire_u<VELOCITY>_t<TIME>.npz per time
#   -u VELOCITY  CH4 inlet velocity in m/s (default 0.01, the tutorial's: about 13 kW; the heat
#                release scales with it)
#   -n NP        MPI processes (default 2)
#   -w WORKDIR   where the case is run (default runs/poolfire_case; replaced unless -c)
#   -o OUT       output .npz (default invflame/data/poolfire_t<END_TIME>.npz)
#   -c           convert only: reuse the finished case in WORKDIR, skip the simulation
# Environment: PYTHON (default .venv/bin/python, else python3),
#              FOAM_TUTORIAL (the tutorial folder), WM_PROJECT_DIR (default /usr/share/openfoam).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
end_time=0.9
interval=""
velocity=0.01
nproc=2
workdir="$repo/runs/poolfire_case"
out=""
convert_only=0
while getopts "t:i:u:n:w:o:ch" opt; do
    case "$opt" in
        t) end_time="$OPTARG" ;;
        i) interval="$OPTARG" ;;
        u) velocity="$OPTARG" ;;
        n) nproc="$OPTARG" ;;
        w) workdir="$OPTARG" ;;
        o) out="$OPTARG" ;;
        c) convert_only=1 ;;
        h) sed -n '2,26p' "$0"; exit 0 ;;
        *) sed -n '2,26p' "$0" >&2; exit 2 ;;
    esac
done
if [ -n "$interval" ]; then
    out="${out:-$repo/runs/poolfire_u${velocity}}"
else
    out="${out:-$repo/invflame/data/poolfire_t${end_time}.npz}"
fi
workdir="$(realpath -m "$workdir")"  # the script changes into the case
out="$(realpath -m "$out")"
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

    # Written every INTERVAL (default: END_TIME alone), in ASCII; NP subdomains split along
    # the height; the inlet velocity of the fuel.
    foamDictionary -entry endTime -set "$end_time" system/controlDict > /dev/null
    foamDictionary -entry writeInterval -set "${interval:-$end_time}" system/controlDict > /dev/null
    foamDictionary -entry boundaryField.inlet.value -set "uniform (0 $velocity 0)" 0/U > /dev/null
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
    if [ -n "$interval" ]; then
        step reconstructPar reconstructPar
    else
        step reconstructPar reconstructPar -time "$end_time"
    fi
    echo "[$(date +%T)] simulation done in $((SECONDS - start)) s"
else
    cd "$workdir"
fi

echo "[$(date +%T)] converting to $out"
"$python" - "$workdir" "$end_time" "$out" "$tutorial" "$velocity" "$interval" <<'EOF'
import sys
from pathlib import Path

from invflame.openfoam import read_case

case, end_time, out, tutorial, velocity, interval = sys.argv[1:]
if interval:  # every written time but the initial one, into the folder OUT
    times = sorted((d.name for d in Path(case).iterdir()
                    if d.is_dir() and d.name.replace(".", "", 1).isdigit() and float(d.name) > 0),
                   key=float)
    Path(out).mkdir(parents=True, exist_ok=True)
    targets = [(t, Path(out) / f"poolfire_u{velocity}_t{t}.npz") for t in times]
else:
    targets = [(end_time, Path(out))]
for time, path in targets:
    field = read_case(case, time)
    field.metadata["case"] = "combustion/fireFoam/LES/smallPoolFire3D (OpenFOAM tutorial)"
    field.metadata["tutorial_path"] = tutorial
    field.metadata["inlet_velocity_m_s"] = float(velocity)
    field.save(path)
    print(f"{path}: {field.summary()}")
EOF
echo "[$(date +%T)] done in $((SECONDS - start)) s: $out"
