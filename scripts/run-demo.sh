#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Quick-start command 1: install dependencies, build, and run the main job on the default scene.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build --parallel "$jobs"
./build/bin/meshInfo models/beam/beam.veg
# The main job: the default scene (cantilever pulled at its tip, released, swinging).
# Frames go to out/beam.afsim (format: docs/simulation-output.md).
mkdir -p out
./build/bin/offlineSimulator models/beam/beam.json --output out/beam.afsim
