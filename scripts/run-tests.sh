#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Quick-start command 2: install dependencies, build everything, run the whole test suite.
#
#   scripts/run-tests.sh              Release build in build/, every test; then the fast
#                                     library tests again under AddressSanitizer,
#                                     LeakSanitizer and UndefinedBehaviorSanitizer
#                                     (build-asan-fast/, -O1, a few minutes)
#   scripts/run-tests.sh --sanitize   the whole suite built with the sanitizers in
#                                     build-asan/ (docs/robustness.md: before each release)
set -euo pipefail
cd "$(dirname "$0")/.."
installing=$SECONDS
bash scripts/install-deps.sh
echo "run-tests: packages checked or installed in $((SECONDS - installing)) s"
jobs=$(nproc)

# The optional parts CI is meant to test (docs/robustness.md, "What CI tests"). The configure
# step lists the parts it builds and fails when one of these is missing (the CMake cache
# variable ASYNCFEM_REQUIRE_PARTS), so that no group of tests vanishes unnoticed.
# ASYNCFEM_ALLOW_MISSING=petsc,python (a comma-separated list of these names) leaves parts
# out on purpose, e.g. on a machine without PETSc. The benchmark drivers are compiled (not
# run) so that they cannot rot unnoticed: about 120 s of CPU, 1 minute on 2 cores.
ci_parts="petsc python render utilities docs benchmarks"
required_parts() {  # the semicolon list of $1 less ASYNCFEM_ALLOW_MISSING
  local missing="${ASYNCFEM_ALLOW_MISSING:-}"
  local allowed=" ${missing//,/ } " part required=""
  for part in ${missing//,/ }; do
    if [[ " $ci_parts " != *" $part "* ]]; then
      echo "ASYNCFEM_ALLOW_MISSING: unknown part '$part' (known: $ci_parts)" >&2
      return 1
    fi
  done
  for part in $1; do
    [[ $allowed == *" $part "* ]] || required+="${required:+;}$part"
  done
  echo "$required"
}

# The library tests of what reads untrusted bytes (users' .veg, TetGen and Gmsh files, the
# output file and checkpoints), built a second time with AddressSanitizer, LeakSanitizer
# and UndefinedBehaviorSanitizer at -O1 and without the utilities, rendering, PETSc and
# Python, so that CI checks memory and undefined behaviour on every change
# (docs/robustness.md, "Sanitizers"; about 2 minutes on 2 cores). The sparse solvers'
# tests left this list when a fresh-clone CI run reached 33 minutes; --sanitize runs them.
# fuzzFileCorpusTests replays the fuzz corpora of those readers (tests/fuzz; the scene
# corpus needs every library and is replayed sanitized by --sanitize). Any report fails the run.
sanitized_tests="volumetricMeshTests simulationIOTests fuzzFileCorpusTests"
run_sanitized_library_tests() {
  cmake -S . -B build-asan-fast -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS=-O1 \
    -DASYNCFEM_SANITIZE=ON -DASYNCFEM_BUILD_TESTS=ON -DASYNCFEM_BUILD_UTILITIES=OFF \
    -DASYNCFEM_WITH_RENDER=OFF -DASYNCFEM_WITH_PETSC=OFF -DASYNCFEM_WITH_PYTHON=OFF -DASYNCFEM_REQUIRE_PARTS= "${launcher[@]}"
  # shellcheck disable=SC2086
  cmake --build build-asan-fast --parallel "$jobs" --target $sanitized_tests
  local leaks=1 test log
  for test in $sanitized_tests; do
    log=$(mktemp)
    if ! ASAN_OPTIONS=detect_leaks=$leaks UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      OMP_WAIT_POLICY=passive "build-asan-fast/bin/$test" --gtest_brief=1 >"$log" 2>&1; then
      if [ "$leaks" = 1 ] && grep -q "LeakSanitizer has encountered a fatal error" "$log"; then
        # LeakSanitizer cannot run where ptrace is forbidden (some containers): say so and
        # keep AddressSanitizer and UndefinedBehaviorSanitizer.
        echo "sanitized tests: LeakSanitizer cannot run here; continuing without leak checks" >&2
        leaks=0
        ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
          OMP_WAIT_POLICY=passive "build-asan-fast/bin/$test" --gtest_brief=1 >"$log" 2>&1 || {
          cat "$log"; rm -f "$log"; echo "sanitized tests: $test failed" >&2; return 1; }
      else
        cat "$log"; rm -f "$log"; echo "sanitized tests: $test failed" >&2; return 1
      fi
    fi
    tail -n 1 "$log" | sed "s/^/sanitized $test: /"
    rm -f "$log"
  done
}
# ccache, when installed, makes a second run of this script rebuild only what changed
# (CCACHE_DISABLE=1 turns it off; CI's fresh machine has none, so nothing changes there).
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
case "${1:-}" in
  "")
    parts=$(required_parts "$ci_parts")
    started=$SECONDS
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DASYNCFEM_BUILD_TESTS=ON \
      -DASYNCFEM_BUILD_BENCHMARKS=ON -DASYNCFEM_UNITY_BUILD=ON "-DASYNCFEM_REQUIRE_PARTS=$parts" "${launcher[@]}"
    cmake --build build --parallel "$jobs"
    built=$SECONDS
    ctest --test-dir build --output-on-failure --parallel "$jobs"
    tested=$SECONDS
    run_sanitized_library_tests
    # Where the time went (packages before this script's build are not counted here).
    echo "run-tests: build $((built - started)) s, tests $((tested - built)) s," \
      "sanitized library tests $((SECONDS - tested)) s, total $((SECONDS - started)) s on $jobs cores"
    ;;
  --sanitize)
    # -O1: GCC takes several times longer on sanitized code at -O2 -g (test files 2-6
    # minutes each on 2 cores), while -O1 keeps the sanitizers' reports exact.
    # Python stays off: an instrumented module cannot load into the uninstrumented interpreter.
    parts=$(required_parts "petsc render utilities docs")
    cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS=-O1 -DASYNCFEM_SANITIZE=ON \
      -DASYNCFEM_BUILD_TESTS=ON "-DASYNCFEM_REQUIRE_PARTS=$parts"
    cmake --build build-asan --parallel "$jobs"
    ctest --test-dir build-asan --output-on-failure --parallel "$jobs"
    ;;
  *)
    echo "usage: scripts/run-tests.sh [--sanitize]" >&2
    exit 2
    ;;
esac
