// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <asyncfem/core/error.hpp>
#include <asyncfem/warping/modalWarping.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "detail/elementGeometry.hpp"

namespace asyncfem {

ModalWarping::ModalWarping(const TetMesh& mesh) : numVertices_(mesh.numVertices()) {
  const detail::ElementGeometry geometry = detail::elementGeometry(mesh);
  const int k = geometry.verticesPerElement;
  Eigen::VectorXd vertexVolume = Eigen::VectorXd::Zero(numVertices_);
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (int a = 0; a < k; ++a) {
      vertexVolume[geometry.elements(a, e)] += geometry.volumes[e];
    }
  }
  // Row block of vertex i: sum over its elements e of (V_e / sum V) (1/2) [grad N_a]x (at the
  // element's centre), placed in the column block of the element's vertex a.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(mesh.numElements()) * k * k * 6);
  for (int e = 0; e < mesh.numElements(); ++e) {
    const auto g = geometry.centreGradients.middleCols(static_cast<Eigen::Index>(k) * e, k);
    for (int p = 0; p < k; ++p) {
      const int row = 3 * geometry.elements(p, e);
      const double weight = 0.5 * geometry.volumes[e] / vertexVolume[geometry.elements(p, e)];
      for (int a = 0; a < k; ++a) {
        const int column = 3 * geometry.elements(a, e);
        const Eigen::Vector3d w = weight * g.col(a);
        // [w]x = [[0, -wz, wy], [wz, 0, -wx], [-wy, wx, 0]]
        triplets.emplace_back(row + 0, column + 1, -w.z());
        triplets.emplace_back(row + 0, column + 2, w.y());
        triplets.emplace_back(row + 1, column + 0, w.z());
        triplets.emplace_back(row + 1, column + 2, -w.x());
        triplets.emplace_back(row + 2, column + 0, -w.y());
        triplets.emplace_back(row + 2, column + 1, w.x());
      }
    }
  }
  curl_.resize(3 * static_cast<Eigen::Index>(numVertices_), 3 * static_cast<Eigen::Index>(numVertices_));
  curl_.setFromTriplets(triplets.begin(), triplets.end());
  curl_.makeCompressed();
}

Eigen::VectorXd ModalWarping::rotationVectors(const Eigen::Ref<const Eigen::VectorXd>& displacement) const {
  if (displacement.size() != 3 * static_cast<Eigen::Index>(numVertices_)) {
    throw Error("modal warping: displacement has " + std::to_string(displacement.size()) + " entries, expected 3 x " +
                std::to_string(numVertices_));
  }
  Eigen::VectorXd rotations = curl_ * displacement;
  return rotations;
}

Eigen::VectorXd ModalWarping::warp(const Eigen::Ref<const Eigen::VectorXd>& displacement) {
  const Eigen::VectorXd rotations = rotationVectors(displacement);
  Eigen::VectorXd warped(displacement.size());
  // Threads pay off only for large meshes (the loop body is a few dozen flops).
#pragma omp parallel for schedule(static) if (numVertices_ >= 16384)
  for (int i = 0; i < numVertices_; ++i) {
    const Eigen::Vector3d w = rotations.segment<3>(3 * static_cast<Eigen::Index>(i));
    const Eigen::Vector3d u = displacement.segment<3>(3 * static_cast<Eigen::Index>(i));
    const double t2 = w.squaredNorm();
    const double t = std::sqrt(t2);
    double c1 = 0.0;
    double c2 = 0.0;
    if (t < 0.05) {
      c1 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0 - t2 * t2 * t2 / 40320.0;
      c2 = 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0 - t2 * t2 * t2 / 362880.0;
    } else {
      c1 = (1.0 - std::cos(t)) / t2;
      c2 = (t - std::sin(t)) / (t2 * t);
    }
    const Eigen::Vector3d wxu = w.cross(u);
    warped.segment<3>(3 * static_cast<Eigen::Index>(i)) = u + c1 * wxu + c2 * w.cross(wxu);
  }
  return warped;
}

}  // namespace asyncfem
