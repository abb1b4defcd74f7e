#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Runs the libFuzzer targets of tests/fuzz (docs/robustness.md).
#
#   scripts/run-fuzz.sh TARGET|all SECONDS [BUILD_DIR]
#
# TARGET is veg, tetgen, gmsh, simulationFile or scene (or fuzz_<name>); all runs each
# for SECONDS in turn. BUILD_DIR (default build-fuzz) is configured with clang++ and
# ASYNCFEM_FUZZ=ON and built if needed. Each target keeps a growing working corpus in
# BUILD_DIR/fuzz/corpus/TARGET (seeded from tests/fuzz/corpus/TARGET, which it never
# changes) and writes crashing, hanging or over-allocating inputs to a folder of this run,
# BUILD_DIR/fuzz/artifacts/TARGET/RUN (RUN: the UTC start time), so that the findings
# counted are this run's only and earlier ones stay for inspection. The last lines print
# executions, coverage, corpus units, peak RSS and findings per target; the exit status is
# 1 if any target found something in this run.
set -euo pipefail

usage() {
  echo "usage: $0 veg|tetgen|gmsh|simulationFile|scene|all SECONDS [BUILD_DIR]" >&2
  exit 2
}
[[ $# -ge 2 && $# -le 3 ]] || usage
target=${1#fuzz_}
seconds=$2
[[ $seconds =~ ^[0-9]+$ && $seconds -gt 0 ]] || usage

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${3:-$root/build-fuzz}
all_targets=(veg tetgen gmsh simulationFile scene)
if [[ $target == all ]]; then
  targets=("${all_targets[@]}")
else
  [[ " ${all_targets[*]} " == *" $target "* ]] || usage
  targets=("$target")
fi

if [[ ! -f $build/CMakeCache.txt ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DASYNCFEM_FUZZ=ON -DASYNCFEM_WITH_RENDER=OFF -DASYNCFEM_WITH_ASSIMP=OFF -DASYNCFEM_BUILD_UTILITIES=OFF
fi
cmake --build "$build" --target "${targets[@]/#/fuzz_}"

# Leaks are reported by the unit tests' sanitizer build; here they would only stop a run
# at the first one instead of finding crashes.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}

run=$(date -u +%Y%m%dT%H%M%SZ)
status=0
summary=()
for name in "${targets[@]}"; do
  corpus=$build/fuzz/corpus/$name
  artifacts=$build/fuzz/artifacts/$name/$run
  log=$build/fuzz/$name.log
  mkdir -p "$corpus" "$artifacts"
  options=(-max_total_time="$seconds" -max_len=65536 -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024
           -print_final_stats=1 -artifact_prefix="$artifacts/")
  if [[ -f $root/tests/fuzz/dictionaries/$name.dict ]]; then
    options+=(-dict="$root/tests/fuzz/dictionaries/$name.dict")
  fi
  echo "== fuzz_$name for $seconds s (log: $log)"
  set +e
  "$build/bin/fuzz_$name" "${options[@]}" "$corpus" "$root/tests/fuzz/corpus/$name" > "$log" 2>&1
  rc=$?
  set -e
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
  rss=$(grep -o 'stat::peak_rss_mb: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
  last=$(grep -E '^#[0-9]+' "$log" | tail -n 1 || true)
  cov=$(grep -o 'cov: [0-9]*' <<< "$last" | grep -o '[0-9]*' || true)
  ft=$(grep -o 'ft: [0-9]*' <<< "$last" | grep -o '[0-9]*' || true)
  units=$(find "$corpus" -type f | wc -l)
  findings=$(find "$artifacts" -type f | wc -l)
  summary+=("fuzz_$name: ${seconds} s, ${execs:-?} executions, cov ${cov:-?}, ft ${ft:-?}, corpus $units, peak RSS ${rss:-?} MB, findings $findings (exit $rc)")
  if [[ $rc -ne 0 || $findings -gt 0 ]]; then
    status=1
    grep -E 'ERROR|SUMMARY|Test unit written' "$log" | head -n 5 || true
  fi
done
printf '%s\n' "${summary[@]}"
exit $status
