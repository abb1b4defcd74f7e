#!/usr/bin/env bash
# The asynchronous integrator over MPI (docs/petsc-backend.md, "The asynchronous integrator
# over MPI"): a box cantilever 4 x 1 x 1 (CELLS cubes across, 4 CELLS along; 6 tets each),
# corotational with the exact tangent, sagging under gravity and pulled sideways, its last
# FRACTION (default 0.05) of its length a fast region at ratio 8 (REGIONS=2: also as much
# at its fixed end, from x = 0.05); offlineSimulator locally (CHOLMOD) and with --backend
# petsc on RANKS (default 1 and 2) ranks (CG + GAMG, MUMPS), the regions owned by one rank
# each and the element loops distributed and, beyond one rank, each replicated on every rank. One Markdown row per run on stdout:
# set-up and wall time per frame from the simulator's summary, and the largest difference
# from the local run's frames relative to the largest displacement (on every vertex up to
# 3,000 vertices, on an evenly spaced sample of about 3,000 beyond).
#   CELLS="12 18" bash scripts/petsc-async.sh [build/bin] > async-mpi.md
set -euo pipefail
bin=$(cd "${1:-build/bin}" && pwd)
cells_list=${CELLS:-"12 18"}
ranks=${RANKS:-"1 2"}
# Each rank count with the regions owned by one rank each and the element loops
# distributed; beyond one rank also with the element loops replicated, and with both
# replicated (only L's solve distributed).
runs=""
for n in $ranks; do
  runs="$runs $n:owned:distributed"
  [ "$n" -gt 1 ] && runs="$runs $n:owned:replicated $n:replicated:replicated"
done
frames=${FRAMES:-3}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMP_NUM_THREADS=1 OMPI_MCA_mpi_yield_when_idle=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
echo "| tets | vertices | run | set-up (s) | per frame (ms) | frame ratio to local | L solves / iterations | difference from local |"
echo "|---|---|---|---|---|---|---|---|"
fraction=${FRACTION:-0.05}
tip_start=$(python3 -c "print(4 - 4 * $fraction)")
second=""
if [ "${REGIONS:-1}" = 2 ]; then
  root_end=$(python3 -c "print(0.05 + 4 * $fraction)")
  second=', {"name": "root", "ratio": 8, "boxes": [{"min": [0.05, -1, -1], "max": ['$root_end', 2, 2]}]}'
fi
for cells in $cells_list; do
  cat > scene.json <<JSON
{
  "mesh": {"generator": "box", "size": [4, 1, 1], "cells": [$((4 * cells)), $cells, $cells],
           "material": {"density": 1000, "youngsModulus": 1e6, "poissonRatio": 0.45}},
  "fixed": {"sets": ["xmin"]},
  "gravity": [0, -9.81, 0],
  "forces": [{"type": "pull", "set": "xmax", "force": [0, 0, 20], "window": [0, 0.1]}],
  "forceModel": {"type": "corotational", "tangent": "exact"},
  "integrator": {"name": "async", "timestep": 0.01,
                 "options": {"regions": [{"name": "tip", "ratio": 8, "boxes": [{"min": [$tip_start, -1, -1], "max": [5, 2, 2]}]}$second]}},
  "frames": {"rate": 25, "count": $frames}
}
JSON
  "$bin/offlineSimulator" scene.json -o local.afsim > local.txt 2> /dev/null
  tets=$((24 * cells * cells * cells))
  vertices=$(((4 * cells + 1) * (cells + 1) * (cells + 1)))
  local_frame=$(grep -m1 "^  per frame" local.txt | awk '{print $3}')
  local_setup=$(grep -m1 "^  setup" local.txt | awk '{print $2}')
  echo "| $tets | $vertices | local (CHOLMOD) | $local_setup | $local_frame | 1.00 | | |"
  for solver in cg-gamg mumps; do
    for run in $runs; do
      IFS=: read -r n regions elements <<< "$run"
      mpiexec -n "$n" "$bin/offlineSimulator" scene.json --backend petsc --petsc-solver "$solver" \
        --petsc-regions "$regions" --petsc-elements "$elements" -o petsc.afsim > petsc.txt 2> /dev/null
      frame=$(grep -m1 "^  per frame" petsc.txt | awk '{print $3}')
      setup=$(grep -m1 "^  setup" petsc.txt | awk '{print $2}')
      solves=$(grep -m1 "PETSc  " petsc.txt | sed 's/.*: \([0-9]*\) solves, \([0-9]*\) iterations.*/\1 \/ \2/')
      difference=$(python3 - "$bin" "$vertices" <<'PY'
import csv, subprocess, sys
n = int(sys.argv[2])
ids = ",".join(str(v) for v in range(0, n, max(1, n // 3000)))  # a sample: the command line stays short
for name in ("local", "petsc"):
    subprocess.run([sys.argv[1] + "/afsimTool", "csv", name + ".afsim", "--vertices", ids, "-o", name + ".csv"], check=True)
rows = lambda f: [[float(x) for x in r[2:]] for r in list(csv.reader(open(f)))[1:]]
a, b = rows("local.csv"), rows("petsc.csv")
scale = max(abs(x) for r in a for x in r)
print(f"{max(abs(x - y) for r, s in zip(a, b) for x, y in zip(r, s)) / scale:.1e}")
PY
)
      ratio=$(python3 -c "print(f'{$frame / $local_frame:.2f}')")
      echo "| $tets | $vertices | PETSc $solver, $n rank(s), regions $regions, elements $elements | $setup | $frame | $ratio | $solves | $difference |"
    done
  done
done
