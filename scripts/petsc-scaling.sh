#!/usr/bin/env bash
# Strong and weak scaling of the PETSc backend (docs/petsc-backend.md, "Scaling"):
# corotational (exact tangent) and neo-Hookean backward Euler on the petscScaling box
# meshes, CG + GAMG and MUMPS on 1 and 2 ranks (more with RANKS="1 2 4 8 16"), CHOLMOD
# on one process as the single-machine baseline. One Markdown row per run on stdout.
#   bash scripts/petsc-scaling.sh [build/bin] > scaling.md
set -euo pipefail
bin=${1:-build/bin}
ranks=${RANKS:-"1 2"}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMP_NUM_THREADS=1
header=--header
row() {  # ranks, then petscScaling's arguments
  local n=$1
  shift
  if [ "$n" = 0 ]; then
    timeout 1800 "$bin/petscScaling" "$@" $header || echo "| failed: $* |"
  else
    timeout 1800 mpiexec -n "$n" "$bin/petscScaling" "$@" $header || echo "| failed: -n $n $* |"
  fi
  header=
}
for model in "corotational --tangent exact" neo-hookean; do
  # Strong scaling: 105k and 395k tets with every solver, about 1M tets with CG + GAMG.
  for cells in 18 28; do
    steps=3
    [ "$cells" -ge 28 ] && steps=2
    row 0 --cells "$cells" --steps "$steps" --solver cholmod --model $model
    for solver in cg-gamg mumps; do
      for n in $ranks; do row "$n" --cells "$cells" --steps "$steps" --solver "$solver" --model $model; done
    done
  done
  for n in $ranks; do row "$n" --cells 38 --steps 3 --solver cg-gamg --model $model; done
  # Weak scaling: twice the tets on two ranks (18 -> 23 and 28 -> 35 cells: 2.09x, 1.95x).
  row 2 --cells 23 --steps 3 --solver cg-gamg --model $model
  row 2 --cells 23 --steps 3 --solver mumps --model $model
  row 2 --cells 35 --steps 3 --solver cg-gamg --model $model
done
