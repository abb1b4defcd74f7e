// SPDX-License-Identifier: BSD-3-Clause
// The checks every hexahedron of a file passes (hexahedra are read from Vega CUBIC files
// and Gmsh element type 5); see docs/file-formats.md.
#include <algorithm>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <string>
#include <utility>

#include "detail/rawMesh.hpp"

namespace asyncfem::detail {

namespace {

/// Largest distance between a cube corner and where it should be, relative to the side:
/// Vega's voxelizer writes its grid to about 15 digits, and a vertex off by more than
/// this is a different shape, not rounding.
constexpr double kCubeTolerance = 1e-6;

std::string point(const Eigen::Vector3d& x) {
  std::string text(1, '(');
  for (int c = 0; c < 3; ++c) {
    text += formatDouble(x[c]);
    text += c < 2 ? ", " : ")";
  }
  return text;
}

/// Vertex a of element e as the file names it: "vertex 3 (file vertex 17)".
std::string cornerName(const RawMesh& raw, const std::array<int, 8>& h, int a) {
  return "vertex " + std::to_string(a) + " (file vertex " +
         std::to_string(raw.vertexFileIds[static_cast<std::size_t>(h[static_cast<std::size_t>(a)])]) + ")";
}

void checkDistinctPositions(const RawMesh& raw, std::size_t e, const Eigen::Matrix<double, 3, 8>& x,
                            const LineCursor& cursor) {
  const std::array<int, 8>& h = raw.hexahedra[e];
  for (int a = 0; a < 8; ++a) {
    for (int b = a + 1; b < 8; ++b) {
      if (x.col(a) == x.col(b)) {
        cursor.failAt(raw.elementLocations[e], "element " + std::to_string(raw.elementFileIds[e]) +
                                                   " is collapsed: its " + cornerName(raw, h, a) + " and " +
                                                   cornerName(raw, h, b) + " are both at " + point(x.col(a)));
      }
    }
  }
}

/// Vega takes the side of every cube from element 0's first edge; the element must be that
/// cube, axis-aligned, in Vega's vertex order.
void checkVegaCube(const RawMesh& raw, std::size_t e, const Eigen::Matrix<double, 3, 8>& x, double side,
                   const LineCursor& cursor) {
  for (int a = 1; a < 8; ++a) {
    const auto& c = hexahedron::kCorners[static_cast<std::size_t>(a)];
    const Eigen::Vector3d expected = x.col(0) + side * Eigen::Vector3d((c[0] + 1) / 2, (c[1] + 1) / 2, (c[2] + 1) / 2);
    if ((x.col(a) - expected).cwiseAbs().maxCoeff() > kCubeTolerance * side) {
      cursor.failAt(raw.elementLocations[e],
                    "element " + std::to_string(raw.elementFileIds[e]) + " is not an axis-aligned cube of side " +
                        formatDouble(side) +
                        " in Vega's vertex order (CUBIC elements must be: Vega takes every cube's side from element "
                        "1's first edge): its " +
                        cornerName(raw, raw.hexahedra[e], a) + " is at " + point(x.col(a)) + ", expected " +
                        point(expected) +
                        " (order: 0 (0,0,0), 1 (s,0,0), 2 (s,s,0), 3 (0,s,0), 4 (0,0,s), 5 (s,0,s), 6 (s,s,s), "
                        "7 (0,s,s) from the minimum corner)");
    }
  }
}

}  // namespace

HexElements checkedHexahedra(const RawMesh& raw, const Eigen::Matrix3Xd& positions, const LineCursor& cursor,
                             const MeshReadOptions& options, MeshReadReport& report) {
  const std::size_t numElements = raw.hexahedra.size();
  HexElements hexahedra(8, static_cast<Eigen::Index>(numElements));
  double side = 0.0;
  for (std::size_t e = 0; e < numElements; ++e) {
    std::array<int, 8> h = raw.hexahedra[e];
    Eigen::Matrix<double, 3, 8> x;
    for (int a = 0; a < 8; ++a) x.col(a) = positions.col(h[static_cast<std::size_t>(a)]);
    checkDistinctPositions(raw, e, x, cursor);
    if (raw.vegaCubes) {
      if (e == 0) side = (x.col(1) - x.col(0)).norm();
      checkVegaCube(raw, e, x, side, cursor);
    }
    const Eigen::Matrix<double, 8, 1> scaled = hexahedron::cornerScaledJacobians(x);
    const std::string name = "element " + std::to_string(raw.elementFileIds[e]);
    if ((scaled.array() < -options.degenerateVolumeTolerance).all()) {
      if (!options.reorientInvertedElements) {
        cursor.failAt(raw.elementLocations[e], name +
                                                   " is inverted (negative Jacobian at every corner); swap its "
                                                   "bottom face (vertices 0-3) and top face (4-7) or allow "
                                                   "reorientation");
      }
      for (std::size_t a = 0; a < 4; ++a) std::swap(h[a], h[a + 4]);
      ++report.reorientedElements;
    } else {
      for (int a = 0; a < 8; ++a) {
        if (!(scaled[a] > options.degenerateVolumeTolerance)) {
          cursor.failAt(raw.elementLocations[e],
                        name + " has a non-positive Jacobian at its " + cornerName(raw, h, a) + " (scaled Jacobian " +
                            formatDouble(scaled[a]) +
                            "): it is inverted, flat or wrongly ordered there (expected order: the bottom face "
                            "0 1 2 3 counter-clockwise seen from above, then the top face 4 5 6 7 above it)");
        }
      }
    }
    for (int a = 0; a < 8; ++a) hexahedra(a, static_cast<Eigen::Index>(e)) = h[static_cast<std::size_t>(a)];
  }
  return hexahedra;
}

}  // namespace asyncfem::detail
