// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/tetElementGeometry.hpp>
#include <cmath>
#include <sstream>

namespace asyncfem {

TetElementGeometry::TetElementGeometry(const TetMesh& mesh, const char* caller)
    : numDofs(mesh.numDofs()), elements(mesh.elements()) {
  const int count = mesh.numElements();
  const auto size = static_cast<std::size_t>(count);
  restPositions.resize(size);
  shapeGradients.resize(size);
  volumes.resize(size);
  std::vector<double> longestEdges(size);
  std::vector<double> signedVolumes(size);
#pragma omp parallel for schedule(static)
  for (int e = 0; e < count; ++e) {
    const auto i = static_cast<std::size_t>(e);
    const ElementPositions x = mesh.elementRestPositions(e);
    restPositions[i] = x;
    shapeGradients[i] = shapeFunctionGradients(x, &signedVolumes[i]);
    volumes[i] = std::abs(signedVolumes[i]);
    longestEdges[i] = longestEdge(x);
  }
  // Checked in element order so that the message names the lowest bad element.
  for (int e = 0; e < count; ++e) {
    const auto i = static_cast<std::size_t>(e);
    checkElementVolume(e, signedVolumes[i], longestEdges[i], caller);
  }
}

ElementPositions TetElementGeometry::currentPositions(int e, const Eigen::VectorXd& displacement) const {
  ElementPositions x = restPositions[static_cast<std::size_t>(e)];
  for (int a = 0; a < 4; ++a) x.col(a) += displacement.segment<3>(3 * static_cast<Eigen::Index>(elements(a, e)));
  return x;
}

Eigen::Matrix3d TetElementGeometry::deformationGradient(int e, const Eigen::VectorXd& displacement) const {
  return currentPositions(e, displacement) * shapeGradients[static_cast<std::size_t>(e)].transpose();
}

}  // namespace asyncfem
