// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <unistd.h>

#include <cstdlib>

namespace asyncfem {

/// Makes idle OpenMP threads sleep instead of spinning, for command-line programs.
///
/// The element loops run on OpenMP threads and CHOLMOD's supernodal kernels on the BLAS's
/// own threads. With the OpenMP runtime's default policy, threads that just left a
/// parallel loop keep spinning and take the cores the BLAS threads need: on a 2-core
/// machine a numeric factorization was measured 25x slower. The policy can only be set
/// through the environment before the runtime starts, so when OMP_WAIT_POLICY is unset
/// this sets it to "passive" and re-executes the program once (same arguments). A user's
/// own OMP_WAIT_POLICY is respected. Call it first thing in main().
inline void preferPassiveThreadWaiting(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  ::setenv("OMP_WAIT_POLICY", "passive", 1);
  ::execv("/proc/self/exe", argv);
  // execv only returns on failure (no /proc): carry on with the default policy.
}

}  // namespace asyncfem
