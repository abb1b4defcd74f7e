// SPDX-License-Identifier: BSD-3-Clause
// Shared helpers of the stiffnessMatrix benchmarks: cached box meshes and memory counters.
#pragma once

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <fstream>
#include <map>
#include <memory>

namespace asyncfem::bench {

/// Unit box of cells^3 cubes (6 cells^3 tets), built once per size and kept.
inline const TetMesh& boxMesh(int cells) {
  static std::map<int, std::unique_ptr<TetMesh>> cache;
  auto& mesh = cache[cells];
  if (!mesh) {
    BoxMeshSpec spec;
    spec.cells = Eigen::Vector3i::Constant(cells);
    spec.material = Material{"rubber", 1100.0, 1e6, 0.45};
    mesh = std::make_unique<TetMesh>(makeBoxMesh(spec));
  }
  return *mesh;
}

/// Resets the kernel's peak-RSS mark (Linux /proc/self/clear_refs, value 5) so that the
/// next peakResidentMegabytes() reports the peak of what follows, not of earlier runs.
/// Where the kernel refuses, the reading stays the process-wide peak.
inline void resetPeakResident() {
  std::ofstream clear("/proc/self/clear_refs");
  if (clear) clear << "5";
}

/// Peak resident set size of the process in MiB (getrusage ru_maxrss).
inline double peakResidentMegabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

/// Sizes: about 10k, 100k and 1M tets.
inline void meshSizes(benchmark::internal::Benchmark* b) {
  for (int cells : {12, 26, 55}) b->Arg(cells);
}

}  // namespace asyncfem::bench
