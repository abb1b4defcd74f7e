#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Quick-start command 2: install dependencies, build everything, run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DASYNCFEM_BUILD_TESTS=ON
cmake --build build --parallel "$jobs"
ctest --test-dir build --output-on-failure --parallel "$jobs"
