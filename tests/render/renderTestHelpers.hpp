// SPDX-License-Identifier: BSD-3-Clause
// Shared meshes and pixel queries of the render tests.
#pragma once

#include <unistd.h>

#include <Eigen/Core>
#include <asyncfem/image/image.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "../hexElements/hexBar.hpp"

namespace asyncfem::renderTesting {

/// A 2 x 0.4 x 0.4 bar of 10 x 2 x 2 cubes along x, starting at the origin.
inline TetMesh renderTestBar() {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(2.0, 0.4, 0.4);
  spec.cells = Eigen::Vector3i(10, 2, 2);
  return makeBoxMesh(spec);
}

/// A 1.6 x 0.4 x 0.4 bar of 8 x 2 x 2 cubes of side 0.2 (test::hexBar scaled; Vega CUBIC
/// needs cubes). With `wobble` > 0 its interior vertices move by up to wobble along a smooth
/// non-affine field, so the elements become general hexahedra (non-planar faces) and the
/// trilinear map has to be inverted iteratively.
inline TetMesh renderTestCubeBar(double wobble = 0.0) {
  const TetMesh bar = test::hexBar(2);
  Eigen::Matrix3Xd x = 1.6 * bar.restPositions();
  for (int v = 0; v < bar.numVertices(); ++v) {
    const Eigen::Vector3d p = x.col(v);
    const bool interior = p.x() > 0.0 && p.x() < 1.6 && p.y() > 0.0 && p.y() < 0.4 && p.z() > 0.0 && p.z() < 0.4;
    if (interior)
      x.col(v) += wobble * Eigen::Vector3d(std::sin(7.0 * p.x()), std::cos(5.0 * p.x()), std::sin(9.0 * p.x()));
  }
  return {std::move(x), bar.hexahedra(), bar.materials(), bar.elementMaterials()};
}

/// The bar bent downwards: u_y = -0.15 x^2, u_x = 0.3 x (y - 0.2) (linear bending).
inline Eigen::VectorXd bentBar(const TetMesh& mesh) {
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    u.segment<3>(3 * v) = Eigen::Vector3d(0.3 * x.x() * (x.y() - 0.2), -0.15 * x.x() * x.x(), 0.0);
  }
  return u;
}

/// True if pixel (x, y) differs from the colour bg (components in [0, 255]) by more than
/// tolerance in some channel.
inline bool differsFrom(const Image& image, int x, int y, const Eigen::Vector3i& bg, int tolerance = 0) {
  const std::uint8_t* p = image.pixel(x, y);
  return std::abs(p[0] - bg.x()) > tolerance || std::abs(p[1] - bg.y()) > tolerance ||
         std::abs(p[2] - bg.z()) > tolerance;
}

/// A fresh temporary folder for one test, removed by the caller.
inline std::filesystem::path freshFolder(const std::string& name) {
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("asyncfem-render-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

}  // namespace asyncfem::renderTesting
