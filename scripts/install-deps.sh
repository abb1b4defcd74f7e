#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs the Debian packages AsyncFEM needs, skipping those already present.
# Usage: scripts/install-deps.sh [--no-render | --demo]
#   (none)       everything: the libraries, rendering, tests, benchmarks, PETSc/MPI, Python,
#                ffmpeg
#   --no-render  the same without OSMesa, assimp, libpng and assimp's test models
#   --demo       only what scripts/run-demo.sh builds: the compiler, CMake, Ninja and the
#                libraries of a configure with PETSc, Python and the tests off (no PETSc,
#                MPI, pybind11, GoogleTest, matplotlib or ffmpeg)
set -euo pipefail

mode="${1:-}"
case "$mode" in
  "" | --no-render | --demo) ;;
  *) echo "install-deps: unknown option '$mode' (usage: $0 [--no-render | --demo])" >&2; exit 2 ;;
esac

if [[ "$mode" == "--demo" ]]; then
  # What the top-level CMakeLists.txt requires with ASYNCFEM_WITH_PETSC=OFF,
  # ASYNCFEM_WITH_PYTHON=OFF and ASYNCFEM_BUILD_TESTS=OFF, rendering on: Eigen, SuiteSparse,
  # METIS, LAPACK/BLAS, OpenMP (with the compiler), zlib, nlohmann-json, Spectra, Bullet,
  # CLI11 (utilities), OSMesa, libpng, assimp.
  packages=(
    build-essential cmake ninja-build
    libeigen3-dev libsuitesparse-dev libmetis-dev libopenblas-dev zlib1g-dev
    nlohmann-json3-dev libcli11-dev libspectra-dev libbullet-dev
    libosmesa6-dev libpng-dev libassimp-dev
  )
else
  packages=(
    build-essential cmake ninja-build pkg-config git
    libeigen3-dev libsuitesparse-dev libmetis-dev libopenblas-dev zlib1g-dev
    nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev libbullet-dev
    libgtest-dev libgmock-dev libbenchmark-dev libspectra-dev clang-format-14
    libpetsc-real-dev openmpi-bin ffmpeg
    python3-dev python3-pybind11 pybind11-dev python3-numpy python3-scipy python3-pytest python3-matplotlib
    python3-pip python3-venv python3-setuptools python3-wheel  # pip install . (pyproject.toml, setup.py)
  )
  if [[ "$mode" != "--no-render" ]]; then
    # assimp-testmodels: real surfaces for the mesher's property test
    # (StuffingProperties.RealSurfacesFromAssimpTestModels), which skips without them.
    packages+=(libosmesa6-dev libassimp-dev libpng-dev assimp-testmodels)
  fi
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}" >&2
  sudo_cmd=()
  if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "install-deps: all ${#packages[@]} packages present" >&2
fi
