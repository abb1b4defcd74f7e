// SPDX-License-Identifier: BSD-3-Clause
// The trilinear hexahedron's element matrices against an independent dense quadrature, the
// patch test, mass totals and the rigid-body null space.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <cmath>
#include <vector>

namespace asyncfem {
namespace {

constexpr double kYoung = 2.0e6;
constexpr double kPoisson = 0.3;

/// A parallelepiped: the unit cube under a fixed affine map (so 2 x 2 x 2 Gauss is exact).
HexElementPositions parallelepiped() {
  Eigen::Matrix3d map;
  map << 1.2, 0.3, 0.1,  //
      0.0, 0.9, 0.2,     //
      0.1, 0.0, 0.7;
  const std::array<Eigen::Vector3d, 8> unit{
      Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 1, 0),
      Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(0, 1, 1)};
  HexElementPositions x;
  for (int a = 0; a < 8; ++a) x.col(a) = map * unit[static_cast<std::size_t>(a)] + Eigen::Vector3d(0.5, -0.2, 0.3);
  return x;
}

/// A general (non-affine) hexahedron: the parallelepiped with vertices moved.
HexElementPositions distorted() {
  HexElementPositions x = parallelepiped();
  x.col(6) += Eigen::Vector3d(0.15, -0.1, 0.2);
  x.col(2) += Eigen::Vector3d(-0.1, 0.05, 0.0);
  x.col(4) += Eigen::Vector3d(0.05, 0.1, -0.05);
  return x;
}

/// Independent oracle: Gauss-Legendre rule with `points` points per axis and the stiffness
/// in index form K_(a i)(b j) = int dN_a/dX_k C_ikjl dN_b/dX_l dV with the isotropic tensor
/// C_ikjl = lambda d_ik d_jl + mu (d_ij d_kl + d_il d_kj), shape functions written here
/// from their tensor-product definition (node coordinates in {0, 1}^3 on [0, 1]^3).
Eigen::Matrix<double, 24, 24> denseGaussStiffness(const HexElementPositions& x, int points) {
  std::vector<double> nodes, weights;
  if (points == 2) {
    nodes = {-1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0)};
    weights = {1.0, 1.0};
  } else {  // 4 points
    const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
    const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
    const double wa = (18.0 + std::sqrt(30.0)) / 36.0;
    const double wb = (18.0 - std::sqrt(30.0)) / 36.0;
    nodes = {-b, -a, a, b};
    weights = {wb, wa, wa, wb};
  }
  const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const double lambda = kYoung * kPoisson / ((1 + kPoisson) * (1 - 2 * kPoisson));
  const double mu = kYoung / (2 * (1 + kPoisson));
  const auto delta = [](int i, int j) { return i == j ? 1.0 : 0.0; };
  Eigen::Matrix<double, 24, 24> k = Eigen::Matrix<double, 24, 24>::Zero();
  for (std::size_t p = 0; p < nodes.size(); ++p)
    for (std::size_t q = 0; q < nodes.size(); ++q)
      for (std::size_t r = 0; r < nodes.size(); ++r) {
        // Reference point in [0, 1]^3 (weights scale by 1/8 for the map from [-1, 1]^3).
        const double s[3] = {(nodes[p] + 1) / 2, (nodes[q] + 1) / 2, (nodes[r] + 1) / 2};
        const double weight = weights[p] * weights[q] * weights[r] / 8.0;
        Eigen::Matrix<double, 8, 3> dN;  // dN_a / ds_j
        for (int a = 0; a < 8; ++a) {
          double f[3], df[3];
          for (int j = 0; j < 3; ++j) {
            f[j] = corner[a][j] == 1 ? s[j] : 1 - s[j];
            df[j] = corner[a][j] == 1 ? 1.0 : -1.0;
          }
          dN(a, 0) = df[0] * f[1] * f[2];
          dN(a, 1) = f[0] * df[1] * f[2];
          dN(a, 2) = f[0] * f[1] * df[2];
        }
        const Eigen::Matrix3d jacobian = x * dN;
        const Eigen::Matrix<double, 8, 3> grad = dN * jacobian.inverse();  // dN_a / dX_k
        const double dV = jacobian.determinant() * weight;
        for (int a = 0; a < 8; ++a)
          for (int b = 0; b < 8; ++b)
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) {
                double sum = 0.0;
                for (int kk = 0; kk < 3; ++kk)
                  for (int l = 0; l < 3; ++l) {
                    const double c = lambda * delta(i, kk) * delta(j, l) +
                                     mu * (delta(i, j) * delta(kk, l) + delta(i, l) * delta(kk, j));
                    sum += grad(a, kk) * c * grad(b, l);
                  }
                k(3 * a + i, 3 * b + j) += sum * dV;
              }
      }
  return k;
}

// Entries are of order E * length (1e6); the quadrature sums 8 to 64 products of such
// numbers, so 1e-12 relative to the largest entry is a few hundred roundings.
constexpr double kRelative = 1e-12;

TEST(HexElement, StiffnessMatchesIndependentDenseGaussQuadrature) {
  const HexElementPositions box = parallelepiped();
  const HexElementMatrix k = hexLinearStiffness(box, kYoung, kPoisson);
  // Exact on a parallelepiped: a 4-point rule gives the same matrix.
  EXPECT_LE((k - denseGaussStiffness(box, 4)).cwiseAbs().maxCoeff(), kRelative * k.cwiseAbs().maxCoeff());
  // On a general hexahedron 2 x 2 x 2 is the rule itself (not exact): same rule, other code.
  const HexElementPositions general = distorted();
  const HexElementMatrix kg = hexLinearStiffness(general, kYoung, kPoisson);
  EXPECT_LE((kg - denseGaussStiffness(general, 2)).cwiseAbs().maxCoeff(), kRelative * kg.cwiseAbs().maxCoeff());
  // ...and the 4-point rule differs from it by more than rounding (so the check above could fail).
  EXPECT_GT((kg - denseGaussStiffness(general, 4)).cwiseAbs().maxCoeff(), 1e-6 * kg.cwiseAbs().maxCoeff());
  EXPECT_EQ(kg, kg.transpose());
}

/// The six rigid-body modes (3 translations, 3 infinitesimal rotations) at positions x.
Eigen::Matrix<double, 24, 6> rigidModes(const HexElementPositions& x) {
  Eigen::Matrix<double, 24, 6> modes = Eigen::Matrix<double, 24, 6>::Zero();
  for (int a = 0; a < 8; ++a) {
    modes.block<3, 3>(3 * a, 0).setIdentity();
    const Eigen::Vector3d p = x.col(a);
    for (int axis = 0; axis < 3; ++axis) modes.block<3, 1>(3 * a, 3 + axis) = Eigen::Vector3d::Unit(axis).cross(p);
  }
  return modes;
}

TEST(HexElement, RigidBodyModesSpanTheNullSpace) {
  for (const HexElementPositions& x : {parallelepiped(), distorted()}) {
    const HexElementMatrix k = hexLinearStiffness(x, kYoung, kPoisson);
    // |K r| is rounding of entries of order |K| times coordinates of order 1.
    EXPECT_LE((k * rigidModes(x)).cwiseAbs().maxCoeff(), kRelative * k.cwiseAbs().maxCoeff());
    // Exactly six zero eigenvalues: the 7th smallest is far from rounding.
    const Eigen::SelfAdjointEigenSolver<HexElementMatrix> eigen(k);
    const double largest = eigen.eigenvalues()[23];
    EXPECT_LE(std::abs(eigen.eigenvalues()[5]), kRelative * largest);
    EXPECT_GT(eigen.eigenvalues()[6], 1e-3 * largest);
  }
}

TEST(HexElement, MassTotalsAndTheCubeClosedForm) {
  const double density = 1200.0;
  for (const HexElementPositions& x : {parallelepiped(), distorted()}) {
    const double volume = hexahedron::signedVolume(x);
    const HexElementMatrix consistent = hexConsistentMass(x, density);
    const HexElementMatrix lumped = hexLumpedMass(x, density);
    // Per coordinate the entries sum to rho V (det J is integrated exactly); 1e-13 relative
    // is a few roundings of the 64 entries.
    for (int c = 0; c < 3; ++c) {
      double consistentSum = 0.0, lumpedSum = 0.0;
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) {
          consistentSum += consistent(3 * a + c, 3 * b + c);
          lumpedSum += lumped(3 * a + c, 3 * b + c);
        }
      EXPECT_NEAR(consistentSum, density * volume, 1e-13 * density * volume);
      EXPECT_NEAR(lumpedSum, density * volume, 1e-13 * density * volume);
    }
    EXPECT_EQ(consistent(0, 1), 0.0);  // coordinates do not couple
  }
  // A cube of side s: rho s^3 {8, 4, 2, 1} / 216 for a vertex with itself, an edge
  // neighbour, a face-diagonal neighbour, the opposite vertex.
  HexElementPositions cube;
  const double side = 0.3;
  for (int a = 0; a < 8; ++a) {
    const auto& c = hexahedron::kCorners[static_cast<std::size_t>(a)];
    cube.col(a) = side * Eigen::Vector3d((c[0] + 1) / 2, (c[1] + 1) / 2, (c[2] + 1) / 2);
  }
  const HexElementMatrix m = hexConsistentMass(cube, density);
  const double unit = density * side * side * side / 216.0;
  EXPECT_NEAR(m(0, 0), 8 * unit, 1e-14 * unit);
  EXPECT_NEAR(m(0, 3 * 1), 4 * unit, 1e-14 * unit);
  EXPECT_NEAR(m(0, 3 * 2), 2 * unit, 1e-14 * unit);
  EXPECT_NEAR(m(0, 3 * 6), 1 * unit, 1e-14 * unit);
  EXPECT_NEAR(hexLumpedMass(cube, density)(5, 5), 27 * unit, 1e-14 * unit);  // rho V / 8
}

/// A 2 x 2 x 2 block of distorted hexahedra around one interior vertex (13), moved off centre.
TetMesh distortedBlock() {
  Eigen::Matrix3Xd x(3, 27);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        // Smooth non-affine distortion of the lattice, plus the interior vertex pushed.
        const double u = i * 0.5, v = j * 0.5, w = k * 0.5;
        x.col(i + 3 * j + 9 * k) = Eigen::Vector3d(u + 0.05 * v * w, v + 0.04 * u * u, w + 0.03 * u * v);
      }
  x.col(13) += Eigen::Vector3d(0.07, -0.05, 0.04);
  HexElements h(8, 8);
  int e = 0;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const auto id = [&](int di, int dj, int dk) { return (i + di) + 3 * (j + dj) + 9 * (k + dk); };
        h.col(e++) << id(0, 0, 0), id(1, 0, 0), id(1, 1, 0), id(0, 1, 0), id(0, 0, 1), id(1, 0, 1), id(1, 1, 1),
            id(0, 1, 1);
      }
  return TetMesh(x, h, {Material{"m", 1000.0, kYoung, kPoisson}}, std::vector<int>(8, 0));
}

TEST(HexElement, PatchTestLinearFieldGivesConstantStrainAndNoInteriorForce) {
  const TetMesh mesh = distortedBlock();
  Eigen::Matrix3d gradient;
  gradient << 1e-3, 2e-4, -5e-4,  //
      3e-4, -2e-3, 1e-4,          //
      -1e-4, 4e-4, 5e-4;
  const Eigen::Vector3d shift(1e-3, -2e-3, 3e-3);
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) u.segment<3>(3 * v) = gradient * mesh.restPosition(v) + shift;
  // Constant strain at every Gauss point of every element: sym(gradient) in Voigt form.
  const Eigen::Matrix3d strain = 0.5 * (gradient + gradient.transpose());
  Eigen::Matrix<double, 6, 1> voigt;
  voigt << strain(0, 0), strain(1, 1), strain(2, 2), 2 * strain(1, 2), 2 * strain(0, 2), 2 * strain(0, 1);
  for (int e = 0; e < mesh.numElements(); ++e) {
    HexElementVector ue;
    for (int a = 0; a < 8; ++a) ue.segment<3>(3 * a) = u.segment<3>(3 * mesh.hexahedron(e)[a]);
    for (int g = 0; g < 8; ++g) {
      const Eigen::Matrix<double, 6, 24> b =
          hexStrainDisplacement(hexShapeGradients(mesh.hexahedronRestPositions(e), hexahedron::gaussPoint(g), nullptr));
      // Strains of order 1e-3 from gradients of order 1 times displacements of order 1e-3.
      EXPECT_LE((b * ue - voigt).cwiseAbs().maxCoeff(), 1e-15) << "element " << e << " point " << g;
    }
  }
  // Zero force on the interior vertex: forces there are sums of terms of order
  // |K| |u| ~ 1e6 * 1e-3 that cancel, so 1e-12 of that scale is rounding.
  const Eigen::VectorXd force = hexLinearStiffnessMatrix(mesh) * u;
  const double scale = hexLinearStiffnessMatrix(mesh).coeffs().cwiseAbs().maxCoeff() * u.cwiseAbs().maxCoeff();
  EXPECT_LE(force.segment<3>(3 * 13).cwiseAbs().maxCoeff(), 1e-12 * scale);
  // Boundary vertices carry the traction of the constant stress, which is not zero.
  EXPECT_GT(force.segment<3>(0).norm(), 1e-3 * scale);
}

TEST(HexElement, MeshMatricesSumElementsAndRefuseTetrahedra) {
  const TetMesh mesh = distortedBlock();
  const Eigen::SparseMatrix<double> mass = hexMassMatrix(mesh, MassType::consistent);
  Eigen::VectorXd ones = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) ones[3 * v] = 1.0;
  double volume = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e) volume += hexahedron::signedVolume(mesh.hexahedronRestPositions(e));
  EXPECT_NEAR(ones.dot(mass * ones), 1000.0 * volume, 1e-12 * 1000.0 * volume);
  EXPECT_NEAR(ones.dot(hexMassMatrix(mesh, MassType::lumped) * ones), 1000.0 * volume, 1e-12 * 1000.0 * volume);
  const TetMesh tet(Eigen::Matrix3Xd::Identity(3, 4), Eigen::Matrix4Xi(Eigen::Vector4i(0, 1, 2, 3)),
                    {Material{"m", 1000.0, kYoung, kPoisson}}, {0});
  EXPECT_THROW((void)hexLinearStiffnessMatrix(tet), ValidationError);
}

TEST(HexElement, InvertedElementIsRefused) {
  HexElementPositions x = parallelepiped();
  x.col(0).swap(x.col(4));
  x.col(1).swap(x.col(5));
  x.col(2).swap(x.col(6));
  x.col(3).swap(x.col(7));
  EXPECT_THROW((void)hexLinearStiffness(x, kYoung, kPoisson), ValidationError);
}

}  // namespace
}  // namespace asyncfem
