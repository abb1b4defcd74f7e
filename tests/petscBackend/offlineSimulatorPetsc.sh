#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# offlineSimulator --backend petsc under mpiexec -n 2 writes the frames the local run writes
# (and continues them from its checkpoint; stops every rank on SIGINT to one):
# a small pulled box (linear, corotational, and neo-Hookean with inversion handling under
# Newton iterations, backward Euler), compared frame by frame with afsimTool csv.
# Tolerance: MUMPS solves directly, so the linearized runs differ by round-off of two
# factorizations (relative 1e-9 of the largest displacement is far above it and far below
# any modelling difference, e.g. one step of the pull window). Newton stops each step at a
# relative residual of 1e-10 on either side, possibly at a different iterate: an error of
# at most kappa 1e-10 per step (kappa ~ 1e3 for this box's M + h^2 K), so 1e-6.
set -euo pipefail
bin="$1" mpiexec="$2" work="$3"
rm -rf "$work" && mkdir -p "$work" && cd "$work"
compare() {  # label forceModel integratorOptions tolerance
  cat > scene.json <<JSON
{
  "mesh": {"generator": "box", "size": [2, 0.5, 0.5], "cells": [8, 2, 2]},
  "fixed": {"sets": ["xmin"]},
  "forces": [{"type": "pull", "set": "xmax", "force": [0, -50, 0], "window": [0, 0.2]}],
  "gravity": [0, -9.81, 0],
  "forceModel": $2,
  "integrator": {"name": "backward-euler", "timestep": 0.01, "options": $3},
  "frames": {"rate": 20, "count": 8}
}
JSON
  "$bin/offlineSimulator" scene.json -q -o local.afsim
  "$mpiexec" -n 2 "$bin/offlineSimulator" scene.json --backend petsc --petsc-solver mumps -o petsc.afsim \
    > petsc.txt 2> progress.txt
  grep -q "ranks       2" petsc.txt || { echo "no 2-rank summary:"; cat petsc.txt; exit 1; }
  agree local.afsim petsc.afsim "$1" "$4"
}
agree() {  # fileA fileB label tolerance [vertices frames]: every vertex of every frame, relative to max |u|
  vertices=$(seq -s, 0 $((${5:-81} - 1)))  # default: every vertex of the 9 x 3 x 3 lattice
  frames=${6:-8}
  "$bin/afsimTool" csv "$1" --vertices "$vertices" -o a.csv
  "$bin/afsimTool" csv "$2" --vertices "$vertices" -o b.csv
  python3 - "$3" "$4" "$frames" <<'PY'
import csv, sys
rows = lambda f: [[float(x) for x in r] for r in list(csv.reader(open(f)))[1:]]
a, b = rows("a.csv"), rows("b.csv")
assert len(a) == len(b) == int(sys.argv[3]), (len(a), len(b))
scale = max(abs(x) for r in a for x in r[2:])
diff = max(abs(x - y) for r, s in zip(a, b) for x, y in zip(r[2:], s[2:]))
print(f"{sys.argv[1]}: max |u| {scale:.3e}, largest difference {diff:.3e}")
assert scale > 0 and diff <= float(sys.argv[2]) * scale, "the runs differ"
PY
}
compare linear '{"type": "linear"}' '{}' 1e-9
compare corotational '{"type": "corotational"}' '{}' 1e-9
compare neo-hookean-newton '{"type": "neo-hookean", "inversionThreshold": 0.2}' \
  '{"maxIterations": 5, "tolerance": 1e-10, "reuseFactor": false}' 1e-6
grep -q "newton      " petsc.txt || { echo "no Newton line in the summary:"; cat petsc.txt; exit 1; }
# Checkpoints: rank 0 writes them, every rank restores. 4 frames on 2 ranks, resumed to 8 on
# 3 ranks, equal the uninterrupted 2-rank run but for rounding (other factorizations; the step
# times t_0 + k h counted from the checkpoint's t_0), which may let Newton stop at another
# iterate: the Newton bound above, 1e-6 (observed 4e-16; a state restored wrongly, e.g. v,
# changes the motion by far more).
"$mpiexec" -n 2 "$bin/offlineSimulator" scene.json --backend petsc --petsc-solver mumps -q --frames 4 -o resumed.afsim
"$mpiexec" -n 3 "$bin/offlineSimulator" scene.json --backend petsc --petsc-solver mumps -q --resume -o resumed.afsim
agree petsc.afsim resumed.afsim resumed-on-3-ranks 1e-6
# .vtu series and velocities on PETSc: rank 0 writes them; 8 .vtu files listed in frames.pvd,
# velocities in the records, and the frames equal the local run's (the linearized bound).
python3 - <<'PY'
import json
scene = json.load(open("scene.json"))
scene["forceModel"], scene["integrator"]["options"] = {"type": "linear"}, {}
scene["output"] = {"velocities": True}
json.dump(scene, open("outputs.json", "w"))
PY
"$bin/offlineSimulator" outputs.json -q -o local-outputs.afsim --vtu local-vtu
"$mpiexec" -n 2 "$bin/offlineSimulator" outputs.json --backend petsc --petsc-solver mumps -q -o petsc-outputs.afsim \
  --vtu petsc-vtu
[ "$(ls petsc-vtu/frame_*.vtu | wc -l)" = 8 ] || { ls petsc-vtu; exit 1; }
[ "$(grep -c '<DataSet' petsc-vtu/frames.pvd)" = 8 ] || { cat petsc-vtu/frames.pvd; exit 1; }
"$bin/afsimTool" info petsc-outputs.afsim | grep -q "velocities  yes" || { "$bin/afsimTool" info petsc-outputs.afsim; exit 1; }
agree local-outputs.afsim petsc-outputs.afsim vtu-and-velocities 1e-9
# A local run does not take a PETSc checkpoint (nor the reverse): the integrator differs by name.
if "$bin/offlineSimulator" scene.json -q --resume -o resumed.afsim 2> err.txt; then exit 1; fi
grep -q 'integrator (backward-euler (PETSc) there, backward-euler here)' err.txt || { cat err.txt; exit 1; }
# Progress lines come from rank 0 only: the last frame's line once.
[ "$(grep -c 'offlineSimulator: frame 8/8 (100%)' progress.txt)" = 1 ] || { cat progress.txt; exit 1; }
# SIGINT sent to one rank (the last child of mpiexec) stops both ranks after the same frame,
# without a hang (ctest's timeout would catch one): exit status 130, the frames kept intact.
sed -i 's/"count": 8/"count": 100000/' scene.json
"$mpiexec" -n 2 "$bin/offlineSimulator" scene.json --backend petsc --petsc-solver mumps -o long.afsim \
  > /dev/null 2> interrupted.txt &
launcher=$!
for _ in $(seq 600); do  # until a frame is written (at most 60 s)
  [ -s long.afsim ] && "$bin/afsimTool" info long.afsim 2> /dev/null | grep -q "frames      [1-9]" && break
  sleep 0.1
done
rank=$(pgrep -P "$launcher" | tail -n 1)
kill -INT "$rank"
status=0
wait "$launcher" || status=$?
[ "$status" = 130 ] || { echo "exit status $status after SIGINT"; cat interrupted.txt; exit 1; }
grep -q "interrupted by SIGINT: [0-9]* of 100000 frames are complete in long.afsim" interrupted.txt ||
  { cat interrupted.txt; exit 1; }
"$bin/afsimTool" info long.afsim | grep -q "checksums   ok" || { "$bin/afsimTool" info long.afsim; exit 1; }
# The asynchronous integrator over MPI: every rank steps the replicated state, each fast
# region is computed by one rank, each rank evaluates its own elements' forces and tangent
# (summed over the ranks), L's system H^{LL*} is solved distributed. The antenna (rod and ring at ratio 30), corotational with
# the exact tangent, 8 frames on 2 ranks (CG + GAMG to a relative residual of 1e-10, the
# simulator's setting for L) equal the local run: kappa 1e-10 per step as in the Newton
# bound above, 1e-6 (observed 2e-14). Resumed from 4 frames on 3 ranks with MUMPS: the same
# bound against the 2-rank run.
models="$(cd "$(dirname "$0")/../../models" && pwd)"
python3 - "$models" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1] + "/antenna/antenna.json"))
scene["mesh"]["file"] = sys.argv[1] + "/antenna/antenna.veg"
scene["forceModel"] = {"type": "corotational", "tangent": "exact"}
scene["frames"]["count"] = 8
json.dump(scene, open("antenna.json", "w"))
PY
"$bin/offlineSimulator" antenna.json -q -o antenna-local.afsim
"$mpiexec" -n 2 "$bin/offlineSimulator" antenna.json --backend petsc -o antenna-petsc.afsim > antenna.txt 2> /dev/null
grep -q "PETSc       2 ranks solve L's system" antenna.txt || { cat antenna.txt; exit 1; }
grep -q "fast regions owned by one rank each: rank 0 computes [01] of 1" antenna.txt || { cat antenna.txt; exit 1; }
grep -q "element loops: each rank evaluates its elements' forces and tangent" antenna.txt || { cat antenna.txt; exit 1; }
agree antenna-local.afsim antenna-petsc.afsim async-on-2-ranks 1e-6 637 8
# The same with every rank computing the region and every element (--petsc-regions
# replicated --petsc-elements replicated): the same bound.
"$mpiexec" -n 2 "$bin/offlineSimulator" antenna.json --backend petsc --petsc-regions replicated \
  --petsc-elements replicated -o antenna-replicated.afsim > replicated.txt 2> /dev/null
grep -q "fast regions replicated: every rank computes every region" replicated.txt || { cat replicated.txt; exit 1; }
grep -q "element loops: every rank evaluates every element" replicated.txt || { cat replicated.txt; exit 1; }
agree antenna-local.afsim antenna-replicated.afsim async-replicated-on-2-ranks 1e-6 637 8
"$mpiexec" -n 2 "$bin/offlineSimulator" antenna.json --backend petsc --petsc-solver mumps -q --frames 4 \
  -o antenna-resumed.afsim
"$mpiexec" -n 3 "$bin/offlineSimulator" antenna.json --backend petsc --petsc-solver mumps -q --resume \
  -o antenna-resumed.afsim
agree antenna-petsc.afsim antenna-resumed.afsim async-resumed-on-3-ranks 1e-6 637 8
# What it cannot run is refused by name.
if "$bin/offlineSimulator" "$models/antenna/antenna-nested.json" --backend petsc -o x.afsim 2> err.txt; then exit 1; fi
grep -q 'option "largeSystemSolver": an external solver of L.s system (the PETSc backend) is not available with the hierarchy solve (the regions given touch or nest)' err.txt ||
  { cat err.txt; exit 1; }
if "$bin/offlineSimulator" scene.json --backend petsc --integrator trapezoidal -o x.afsim 2> err.txt; then exit 1; fi
grep -q 'Newton iterations run with backward-euler only on the PETSc backend' err.txt || { cat err.txt; exit 1; }
