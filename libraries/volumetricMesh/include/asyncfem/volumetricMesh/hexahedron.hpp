// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>

namespace asyncfem::hexahedron {

/// Reference geometry of the trilinear 8-node hexahedron on the cube [-1, 1]^3 with
/// coordinates xi = (xi, eta, zeta).
///
/// Vertex order (VTK_HEXAHEDRON = Gmsh's 8-node hexahedron = Vega's CUBIC elements): the
/// bottom face 0 1 2 3 counter-clockwise seen from above, then the top face 4 5 6 7 above
/// it. For a cube of side s with its minimum corner at the origin: 0 (0,0,0), 1 (s,0,0),
/// 2 (s,s,0), 3 (0,s,0), 4 (0,0,s), 5 (s,0,s), 6 (s,s,s), 7 (0,s,s). kCorners gives
/// each vertex's reference coordinates (-1 for 0 above, +1 for s).
inline constexpr std::array<std::array<int, 3>, 8> kCorners{
    {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}}};

/// The six quadrilateral faces, each counter-clockwise seen from outside (so the
/// normal (b - a) x (c - a) of a positively oriented element points out): -z, +z, -y, +x,
/// +y, -x.
inline constexpr std::array<std::array<int, 4>, 6> kFaces{
    {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}};

/// The vertex whose reference corner is that of vertex a with the signs of the axes in
/// mask flipped (bit 0: xi, bit 1: eta, bit 2: zeta); e.g. opposite(0, 7) = 6.
int flippedCorner(int a, int mask);

/// The eight shape functions N_a(xi) = (1 + xi xi_a)(1 + eta eta_a)(1 + zeta zeta_a) / 8.
Eigen::Matrix<double, 8, 1> shapeFunctions(const Eigen::Vector3d& xi);
/// Their derivatives dN_a / dxi_j (8 x 3, row a).
Eigen::Matrix<double, 8, 3> shapeFunctionDerivatives(const Eigen::Vector3d& xi);
/// Jacobian dx/dxi (3 x 3) at xi of the element with vertex positions x (3 x 8).
Eigen::Matrix3d jacobian(const Eigen::Matrix<double, 3, 8>& x, const Eigen::Vector3d& xi);

/// The reference coordinates xi with x(xi) = p, the inverse of the trilinear map, by Newton's
/// method from the centre xi = 0: at most `iterations` steps, fewer once a step moves xi by less
/// than 1e-13. Exact after one step for a parallelepiped (an affine map). Points outside the
/// element get coordinates outside [-1, 1]^3 (the map extended); for a strongly distorted element
/// and a point far outside, the last iterate is returned.
Eigen::Vector3d referenceCoordinates(const Eigen::Matrix<double, 3, 8>& x, const Eigen::Vector3d& p,
                                     int iterations = 20);

/// The 2 x 2 x 2 Gauss points (+-1/sqrt 3 on each axis, weight 1 each), point g at the
/// signs of corner g. Exact for the volume (det J has degree <= 2 in each coordinate) and
/// for the linear stiffness and consistent mass of a parallelepiped.
Eigen::Vector3d gaussPoint(int g);

/// Signed volume: the integral of det J over the reference cube (2 x 2 x 2 Gauss, exact).
/// Positive for the vertex order above.
double signedVolume(const Eigen::Matrix<double, 3, 8>& x);

/// At each vertex a, det[e_xi, e_eta, e_zeta] of the three edges leaving it, each pointing
/// along +xi, +eta, +zeta of the reference cube (8 det J at that corner, a volume):
/// positive at every corner of a valid, positively oriented element.
Eigen::Matrix<double, 8, 1> cornerJacobians(const Eigen::Matrix<double, 3, 8>& x);
/// The scaled Jacobian at each corner: det of J with normalized columns, in [-1, 1]; 1 at
/// every corner of a parallelepiped with right angles (a box), <= 0 where the element is
/// inverted or flat at that corner; NaN where an edge at the corner has zero length.
Eigen::Matrix<double, 8, 1> cornerScaledJacobians(const Eigen::Matrix<double, 3, 8>& x);

}  // namespace asyncfem::hexahedron
