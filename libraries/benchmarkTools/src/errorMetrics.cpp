// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>

namespace asyncfem {

double relativeL2Error(const Trajectory& run, const Trajectory& reference, const VertexGroup& group) {
  const std::size_t frames = std::min(run.size(), reference.size());
  double difference = 0.0, norm = 0.0;
  for (std::size_t k = 0; k < frames; ++k) {
    const Eigen::VectorXd& u = run[k];
    const Eigen::VectorXd& r = reference[k];
    if (u.size() != r.size()) {
      throw Error("relativeL2Error: frame " + std::to_string(k) + " has " + std::to_string(u.size()) +
                  " entries in the run and " + std::to_string(r.size()) + " in the reference");
    }
    if (group.vertices.empty()) {
      difference += (u - r).squaredNorm();
      norm += r.squaredNorm();
      continue;
    }
    for (const int v : group.vertices) {
      const Eigen::Index dof = 3 * static_cast<Eigen::Index>(v);
      difference += (u.segment<3>(dof) - r.segment<3>(dof)).squaredNorm();
      norm += r.segment<3>(dof).squaredNorm();
    }
  }
  return norm > 0.0 ? std::sqrt(difference / norm) : std::sqrt(difference);
}

std::vector<double> vertexDisplacementNorms(const Trajectory& run, int vertex) {
  std::vector<double> out;
  out.reserve(run.size());
  for (const Eigen::VectorXd& u : run) out.push_back(u.segment<3>(3 * static_cast<Eigen::Index>(vertex)).norm());
  return out;
}

}  // namespace asyncfem
