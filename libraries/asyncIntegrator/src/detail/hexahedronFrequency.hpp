// SPDX-License-Identifier: BSD-3-Clause
// The region proposal's element measures on hexahedra (hexahedronFrequency.cpp). Private to
// the library.
#pragma once

#include <Eigen/Core>

namespace asyncfem::detail {

/// The unit cube [0, 1]^3 as a hexahedron (vertices in hexahedron.hpp's order).
Eigen::Matrix<double, 3, 8> unitCube();
/// RMS length of a hexahedron's 12 edges.
double rmsEdgeLength(const Eigen::Matrix<double, 3, 8>& restPositions);

}  // namespace asyncfem::detail
