#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Quick-start command 1: install what the demo needs, build the two programs it runs, simulate
# the default scene, render its frames (and a video when ffmpeg is present), and print where
# the time went. Its own build folder, build-demo/, has PETSc, Python and the tests off; the
# whole toolkit (build/) is what scripts/run-tests.sh builds.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s.%N)
now() { date +%s.%N; }
seconds() { awk -v a="$1" -v b="$2" 'BEGIN{printf "%.1f", b - a}'; }

t0=$(now)
bash scripts/install-deps.sh --demo
t1=$(now)
jobs=$(nproc)
build=build-demo
# -O1: the build is nearly all of the demo's time, and at -O1 it took 28% less CPU than at
# -O3 while the simulation took 1.2-1.4 s either way (docs/benchmarks.md, "The demo, timed");
# build/ of scripts/run-tests.sh is the optimized one. Unity build (ASYNCFEM_UNITY_BUILD):
# 102 s instead of 192 s to build the two programs from a fresh clone on two idle cores,
# the same frames (the test command builds the libraries this way too, so CI checks it).
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -DNDEBUG" \
  -DASYNCFEM_WITH_PETSC=OFF -DASYNCFEM_WITH_PYTHON=OFF -DASYNCFEM_BUILD_TESTS=OFF \
  -DASYNCFEM_BUILD_BENCHMARKS=OFF -DASYNCFEM_UNITY_BUILD=ON
cmake --build "$build" --parallel "$jobs" --target offlineSimulator frameRenderer
t2=$(now)

# The main job: the default scene (cantilever pulled at its tip, released, swinging), with the
# asynchronous integrator (the tip takes 8 substeps per large step). Frames go to
# out/beam.afsim (format: docs/simulation-output.md).
mkdir -p out
"$build/bin/offlineSimulator" models/beam/beam.json --output out/beam.afsim
t3=$(now)
# Draw the frames at 640 x 360 with the stiff tip tinted, rotation-strain warping and a ground
# plane (docs/rendering.md): frame 0 first, so that a picture is there at once, then the rest.
render=(--output out/frames --width 640 --height 360 --warp rotation-strain --tint-set tip --ground)
"$build/bin/frameRenderer" out/beam.afsim "${render[@]}" --frames 0 --quiet
t4=$(now)
"$build/bin/frameRenderer" out/beam.afsim "${render[@]}" --frames 1:
t5=$(now)
frames=$(ls out/frames/frame_*.png | wc -l)
video="no ffmpeg: for a video, apt-get install ffmpeg and run"
video+=" ffmpeg -framerate 30 -i out/frames/frame_%05d.png -pix_fmt yuv420p out/beam.mp4"
if command -v ffmpeg >/dev/null; then
  rm -f out/beam.mp4
  ffmpeg -loglevel error -y -framerate 30 -i out/frames/frame_%05d.png -pix_fmt yuv420p out/beam.mp4
  video="out/beam.mp4"
fi
t6=$(now)

echo
echo "run-demo: timing (seconds, $jobs cores)"
echo "  packages      $(seconds "$t0" "$t1")   (scripts/install-deps.sh --demo)"
echo "  build         $(seconds "$t1" "$t2")   (configure $build/, offlineSimulator and frameRenderer)"
echo "  simulate      $(seconds "$t2" "$t3")   (offlineSimulator models/beam/beam.json)"
echo "  render        $(seconds "$t3" "$t5")   ($frames frames; frame 0 in $(seconds "$t3" "$t4"))"
echo "  video         $(seconds "$t5" "$t6")"
echo "  first frame   $(seconds "$start" "$t4")   after the start"
echo "  total         $(seconds "$start" "$t6")"
echo "run-demo: frames are in out/frames/frame_00000.png ... frame_$(printf %05d $((frames - 1))).png"
echo "run-demo: video: $video"
