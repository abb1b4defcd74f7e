#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Quick-start command 2: install dependencies, build everything, run the whole test suite.
#
#   scripts/run-tests.sh              Release build in build/, every test
#   scripts/run-tests.sh --sanitize   the same suite built with AddressSanitizer and
#                                     UndefinedBehaviorSanitizer in build-asan/
#                                     (docs/robustness.md: run it before each release)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc)
case "${1:-}" in
  "")
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DASYNCFEM_BUILD_TESTS=ON
    cmake --build build --parallel "$jobs"
    ctest --test-dir build --output-on-failure --parallel "$jobs"
    ;;
  --sanitize)
    cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DASYNCFEM_SANITIZE=ON \
      -DASYNCFEM_BUILD_TESTS=ON
    cmake --build build-asan --parallel "$jobs"
    ctest --test-dir build-asan --output-on-failure --parallel "$jobs"
    ;;
  *)
    echo "usage: scripts/run-tests.sh [--sanitize]" >&2
    exit 2
    ;;
esac
