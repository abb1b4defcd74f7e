// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace asyncfem {

/// The displacements of a run, one full (3n) vector per frame.
using Trajectory = std::vector<Eigen::VectorXd>;

/// A named set of vertices the error is reported on (a fast region, L, everything).
struct VertexGroup {
  std::string name;
  std::vector<int> vertices;  ///< 0-based; empty means every vertex
};

/// Relative L2 error over the frames on the DOFs of a vertex group:
///
///     sqrt( sum_k sum_{v in group} |u_k(v) - r_k(v)|^2 ) / sqrt( sum_k sum_{v in group} |r_k(v)|^2 )
///
/// over frames k = 0 .. min(run, reference) - 1 (a run that stopped early is compared on the
/// frames it has; the caller reports that it stopped). When the reference is identically
/// zero on the group the absolute norm of the difference is returned. Throws
/// asyncfem::Error when the frame vectors differ in size.
double relativeL2Error(const Trajectory& run, const Trajectory& reference, const VertexGroup& group);

/// |u_k(vertex)| for every frame k: the displacement magnitude of one vertex over time
/// (the quantity plotted in Figures 4 and 7 of Zhao, Li & Barbič 2016).
std::vector<double> vertexDisplacementNorms(const Trajectory& run, int vertex);

}  // namespace asyncfem
