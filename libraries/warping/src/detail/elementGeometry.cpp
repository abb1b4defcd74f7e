// SPDX-License-Identifier: BSD-3-Clause
#include "detail/elementGeometry.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <cmath>
#include <string>

namespace asyncfem::detail {

namespace {

double longestEdge(const Eigen::Matrix3Xd& rest) {
  double longest = 0.0;
  for (Eigen::Index a = 0; a < rest.cols(); ++a) {
    for (Eigen::Index b = a + 1; b < rest.cols(); ++b) longest = std::max(longest, (rest.col(a) - rest.col(b)).norm());
  }
  return longest;
}

[[noreturn]] void throwDegenerate(int e, double volume) {
  throw ValidationError("warping: element " + std::to_string(e) + " is degenerate (volume " + std::to_string(volume) +
                        ")");
}

/// Centre and integrated gradients of hexahedron e; its |volume|.
double hexahedronGeometry(const TetMesh& mesh, int e, Eigen::Ref<Eigen::Matrix<double, 3, 8>> centre,
                          Eigen::Ref<Eigen::Matrix<double, 3, 8>> integrated) {
  const Eigen::Matrix<double, 3, 8> x = mesh.hexahedronRestPositions(e);
  const double l = longestEdge(x);
  // det J is a volume over the reference cube's volume 8.
  const double threshold = 1e-14 * l * l * l / 8.0;
  double determinant = 0.0;
  centre = hexShapeGradients(x, Eigen::Vector3d::Zero(), &determinant);
  if (!(std::abs(determinant) > threshold)) throwDegenerate(e, 8.0 * determinant);
  integrated.setZero();
  double volume = 0.0;
  for (int g = 0; g < 8; ++g) {
    const Eigen::Matrix<double, 3, 8> gradients = hexShapeGradients(x, hexahedron::gaussPoint(g), &determinant);
    if (!(std::abs(determinant) > threshold)) throwDegenerate(e, hexahedron::signedVolume(x));
    integrated += std::abs(determinant) * gradients;
    volume += determinant;
  }
  return std::abs(volume);
}

}  // namespace

ElementGeometry elementGeometry(const TetMesh& mesh) {
  ElementGeometry geometry;
  const int k = mesh.verticesPerElement();
  const int numElements = mesh.numElements();
  geometry.verticesPerElement = k;
  geometry.elements = mesh.connectivity();
  geometry.centreGradients.resize(3, static_cast<Eigen::Index>(k) * numElements);
  geometry.integratedGradients.resize(3, static_cast<Eigen::Index>(k) * numElements);
  geometry.volumes.resize(numElements);
  for (int e = 0; e < numElements; ++e) {
    if (mesh.isHexahedral()) {
      geometry.volumes[e] = hexahedronGeometry(mesh, e, geometry.centreGradients.middleCols<8>(8 * e),
                                               geometry.integratedGradients.middleCols<8>(8 * e));
      continue;
    }
    const Eigen::Matrix<double, 3, 4> rest = mesh.elementRestPositions(e);
    const double l = longestEdge(rest);
    double signedVolume = 0.0;
    const Eigen::Matrix<double, 3, 4> g = shapeFunctionGradients(rest, &signedVolume);
    // Same threshold as the stiffness assembly, so a mesh that simulates also warps.
    if (!(std::abs(signedVolume) > 1e-14 * l * l * l)) throwDegenerate(e, signedVolume);
    geometry.volumes[e] = std::abs(signedVolume);
    geometry.centreGradients.middleCols<4>(4 * e) = g;
    geometry.integratedGradients.middleCols<4>(4 * e) = geometry.volumes[e] * g;
  }
  return geometry;
}

Eigen::MatrixXd elementLaplacian(const TetMesh& mesh, const ElementGeometry& geometry, int e) {
  const int k = geometry.verticesPerElement;
  if (!mesh.isHexahedral()) {
    const auto g = geometry.centreGradients.middleCols(static_cast<Eigen::Index>(k) * e, k);
    return geometry.volumes[e] * (g.transpose() * g);
  }
  const Eigen::Matrix<double, 3, 8> x = mesh.hexahedronRestPositions(e);
  Eigen::MatrixXd laplacian = Eigen::MatrixXd::Zero(8, 8);
  for (int g = 0; g < 8; ++g) {
    double determinant = 0.0;
    const Eigen::Matrix<double, 3, 8> gradients = hexShapeGradients(x, hexahedron::gaussPoint(g), &determinant);
    laplacian += std::abs(determinant) * (gradients.transpose() * gradients);
  }
  return laplacian;
}

Eigen::Matrix3d rotationFromVector(const Eigen::Vector3d& w) {
  const double t2 = w.squaredNorm();
  const double t = std::sqrt(t2);
  double sinOverT = 0.0;
  double oneMinusCosOverT2 = 0.0;
  if (t < 0.05) {
    // Next terms t^8 / 362880 and t^8 / 3628800 are below 1e-15 relative here.
    sinOverT = 1.0 - t2 / 6.0 + t2 * t2 / 120.0 - t2 * t2 * t2 / 5040.0;
    oneMinusCosOverT2 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0 - t2 * t2 * t2 / 40320.0;
  } else {
    sinOverT = std::sin(t) / t;
    oneMinusCosOverT2 = (1.0 - std::cos(t)) / t2;
  }
  Eigen::Matrix3d cross;
  cross << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return Eigen::Matrix3d::Identity() + sinOverT * cross + oneMinusCosOverT2 * (cross * cross);
}

}  // namespace asyncfem::detail
