#!/usr/bin/env bash
# Make the validation family: flames no reconstruction setting was developed on, into OUT
# (default runs/validation, outside git: about 2.5 MB a flame).
#
#   poolfire_u0.01_t{0.4,0.8,1.2,1.6,2,2.4,2.8}.npz  the packaged fire's LES (13 kW), other times
#   poolfire_u0.02_t{1,2}.npz          the same case with twice the fuel flow (about 26 kW)
#   plume_sheet1950_seed{1,2}.npz      McCaffrey plumes with an adiabatic flame sheet, puffing
#                                       and turbulence of relative amplitude 0.3
#
# studies/validation.py splits them into a tuning half and a report half. Needs OpenFOAM
# (apt-get install -y openfoam openfoam-examples); about 25 min on 2 cores.
# Usage: scripts/make_validation_family.sh [OUT]
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$repo/runs/validation}"
invflame="${INVFLAME:-$repo/.venv/bin/invflame}"
bash "$repo/scripts/make_poolfire.sh" -t 2.8 -i 0.4 -u 0.01 -w "$repo/runs/case_u0.01" -o "$out"
bash "$repo/scripts/make_poolfire.sh" -t 2.0 -i 1.0 -u 0.02 -w "$repo/runs/case_u0.02" -o "$out"
for seed in 1 2; do
    "$invflame" phantom write synthetic --sheet-rise 1950 --perturbation 0.3 --seed "$seed" \
        --out "$out/plume_sheet1950_seed$seed.npz"
done
ls -l "$out"
