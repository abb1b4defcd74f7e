// SPDX-License-Identifier: BSD-3-Clause
// Meshes, deformations and finite differences shared by the hyperelasticFEM tests.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <random>
#include <string>
#include <vector>

#include "../common/forceModelTestHelpers.hpp"

namespace asyncfem::test {

inline constexpr double kYoungsModulus = 2e6;
inline constexpr double kPoissonRatio = 0.4;

/// Mooney-Rivlin parameters with the small-strain moduli of (E, nu): G = E / (2 (1 + nu))
/// split 30/70 between mu01 and mu10, K = E / (3 (1 - 2 nu)) = 2 v1.
inline MooneyRivlinParameters matchingMooneyRivlin(double youngsModulus, double poissonRatio) {
  const double shear = youngsModulus / (2.0 * (1.0 + poissonRatio));
  const double bulk = youngsModulus / (3.0 * (1.0 - (2.0 * poissonRatio)));
  return {0.3 * shear / 2.0, 0.7 * shear / 2.0, bulk / 2.0};
}

/// A box of cells^3 cubes (6 tets each), 1 x 0.8 x 0.6, E = kYoungsModulus, nu = 0.4,
/// with matching Mooney-Rivlin parameters on its material.
inline TetMesh smallBox(int cells) {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(1.0, 0.8, 0.6);
  spec.cells = Eigen::Vector3i::Constant(cells);
  spec.material =
      Material{"m", 1000.0, kYoungsModulus, kPoissonRatio, matchingMooneyRivlin(kYoungsModulus, kPoissonRatio)};
  return makeBoxMesh(spec);
}

/// The unit corner tetrahedron (0, e_x, e_y, e_z), same material as smallBox().
inline TetMesh unitTet() {
  Eigen::Matrix3Xd x(3, 4);
  x << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  Eigen::Matrix4Xi elements(4, 1);
  elements << 0, 1, 2, 3;
  return TetMesh(
      x, elements,
      {Material{"m", 1000.0, kYoungsModulus, kPoissonRatio, matchingMooneyRivlin(kYoungsModulus, kPoissonRatio)}}, {0});
}

/// Displacement that gives every element the deformation gradient f: u = (F - I) X.
inline Eigen::VectorXd homogeneousDisplacement(const TetMesh& mesh, const Eigen::Matrix3d& f) {
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v)
    u.segment<3>(3 * v) = (f - Eigen::Matrix3d::Identity()) * mesh.restPosition(v);
  return u;
}

/// deformedDisplacement with the translation t = (0.1, -0.2, 0.3) these tests use.
inline Eigen::VectorXd deformedDisplacement(const TetMesh& mesh, const Eigen::Matrix3d& rotation, double amplitude,
                                            std::mt19937& random) {
  return deformedDisplacement(mesh, rotation, Eigen::Vector3d(0.1, -0.2, 0.3), amplitude, random);
}

/// Central differences of the energy, component j = (E(u + t e_j) - E(u - t e_j)) / 2t.
inline Eigen::VectorXd finiteDifferenceForces(ForceModel& model, const Eigen::VectorXd& u, double step) {
  Eigen::VectorXd result(u.size());
  for (Eigen::Index j = 0; j < u.size(); ++j) {
    Eigen::VectorXd plus = u;
    Eigen::VectorXd minus = u;
    plus[j] += step;
    minus[j] -= step;
    result[j] = (model.elasticEnergy(plus) - model.elasticEnergy(minus)) / (2.0 * step);
  }
  return result;
}

/// A labelled configuration of a model for parameterised loops.
struct ModelCase {
  std::string label;
  HyperelasticMaterialKind kind;
  HyperelasticOptions options;
};

/// Every material, each with inversion handling off and with the consistent extension
/// at threshold 0.2, plus the Green-strain StVK.
inline std::vector<ModelCase> allModelCases() {
  std::vector<ModelCase> cases;
  HyperelasticOptions green;
  cases.push_back({"stvk green strain", HyperelasticMaterialKind::stvk, green});
  for (const HyperelasticMaterialKind kind :
       {HyperelasticMaterialKind::stvk, HyperelasticMaterialKind::neoHookean, HyperelasticMaterialKind::mooneyRivlin}) {
    HyperelasticOptions plain;
    plain.stvkFormulation = StVKFormulation::principalStretches;
    cases.push_back({toString(kind), kind, plain});
    HyperelasticOptions handled = plain;
    handled.inversionThreshold = 0.2;
    handled.enableCompressionResistance = true;
    cases.push_back({toString(kind) + " threshold 0.2 + compression resistance", kind, handled});
  }
  return cases;
}

}  // namespace asyncfem::test
