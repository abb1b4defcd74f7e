// SPDX-License-Identifier: BSD-3-Clause
// The hyperelastic materials assembled over a hexahedral mesh (HexHyperelasticForceModel):
// forces and tangent against central differences, the rest tangent against the assembled
// linear stiffness, the factory's choice, and the refusals (options, missing Mooney-Rivlin
// parameters, tetrahedra, a flat element without inversion handling).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/hexElements/hexHyperelasticForceModel.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <memory>
#include <random>
#include <string>

#include "../hyperelasticFEM/testHelpers.hpp"
#include "hexBar.hpp"

namespace asyncfem {
namespace {

constexpr HyperelasticMaterialKind kKinds[] = {HyperelasticMaterialKind::stvk, HyperelasticMaterialKind::neoHookean,
                                               HyperelasticMaterialKind::mooneyRivlin};

/// Options for kind on hexBar's material (E 1e6, nu 0.3): stvk through principal stretches,
/// Mooney-Rivlin with parameters of the same small-strain moduli.
HyperelasticOptions barOptions(HyperelasticMaterialKind kind) {
  HyperelasticOptions options;
  options.stvkFormulation = StVKFormulation::principalStretches;
  if (kind == HyperelasticMaterialKind::mooneyRivlin) options.mooneyRivlin = test::matchingMooneyRivlin(1e6, 0.3);
  return options;
}

TEST(HexHyperelasticForceModel, AssembledForcesAndTangentAreTheEnergyDerivatives) {
  const TetMesh mesh = test::hexBar(1);
  std::mt19937 random(3);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, -2, 1).normalized()).toRotationMatrix();
  // Vertex perturbations of 0.03 on cells of 0.25: strains about 0.1, then a rigid motion.
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, rotation, 0.03, random);
  for (const HyperelasticMaterialKind kind : kKinds) {
    SCOPED_TRACE(toString(kind));
    HyperelasticOptions options = barOptions(kind);
    options.inversionThreshold = 0.2;  // on, but no stretch comes near it
    HexHyperelasticForceModel model(mesh, kind, options);
    EXPECT_FALSE(model.isLinear());
    Eigen::VectorXd forces;
    Eigen::SparseMatrix<double> tangent = model.createStiffnessMatrix();
    const Eigen::Index pattern = tangent.nonZeros();
    model.forcesAndTangent(u, forces, tangent);
    EXPECT_EQ(tangent.nonZeros(), pattern);
    // Step 1e-7 on displacements of order 0.1 and forces of order 1e4: truncation ~ step^2,
    // cancellation ~ 1e-16 |E| / step ~ 1e-9 relative; 1e-6 of the largest entry separates
    // round-off from a wrong or missing assembled block.
    EXPECT_LE(test::relativeEntryDifference(forces, test::finiteDifferenceForces(model, u, 1e-7)), 1e-6);
    const Eigen::MatrixXd numeric = test::finiteDifferenceTangent(model, u, 1e-7);
    EXPECT_LE((Eigen::MatrixXd(tangent) - numeric).cwiseAbs().maxCoeff(), 1e-6 * numeric.cwiseAbs().maxCoeff());
  }
}

TEST(HexHyperelasticForceModel, AtRestTheTangentIsTheLinearStiffness) {
  const TetMesh mesh = test::hexBar(1);
  const Eigen::MatrixXd linear(hexLinearStiffnessMatrix(mesh));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.numDofs());
  for (const HyperelasticMaterialKind kind : kKinds) {
    SCOPED_TRACE(toString(kind));
    HexHyperelasticForceModel model(mesh, kind, barOptions(kind));
    // The same 2 x 2 x 2 rule and the same small-strain C: equal to the rounding of |K|.
    EXPECT_LE((test::tangent(model, zero) - linear).cwiseAbs().maxCoeff(), 1e-10 * linear.cwiseAbs().maxCoeff());
    EXPECT_LE(test::forces(model, zero).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LE(std::abs(model.elasticEnergy(zero)), 1e-12);
  }
}

TEST(HexHyperelasticForceModel, FactoryPicksTheModelAndRefusesWhatItCannotRun) {
  const TetMesh mesh = test::hexBar(1);
  EXPECT_NE(dynamic_cast<HexStvkForceModel*>(makeHexHyperelasticForceModel(mesh, HyperelasticMaterialKind::stvk).get()),
            nullptr);
  for (const HyperelasticMaterialKind kind : kKinds) {
    const std::unique_ptr<ForceModel> model = makeHexHyperelasticForceModel(mesh, kind, barOptions(kind));
    EXPECT_NE(dynamic_cast<HexHyperelasticForceModel*>(model.get()), nullptr) << toString(kind);
  }
  HyperelasticOptions greenStrain;
  greenStrain.inversionThreshold = 0.3;
  EXPECT_THROW(makeHexHyperelasticForceModel(mesh, HyperelasticMaterialKind::stvk, greenStrain), ValidationError);
  try {
    HexHyperelasticForceModel model(mesh, HyperelasticMaterialKind::mooneyRivlin);
    ADD_FAILURE() << "Mooney-Rivlin accepted without parameters";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("element 0"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("Mooney-Rivlin"), std::string::npos) << error.what();
  }
  EXPECT_THROW(HexHyperelasticForceModel(test::unitTet(), HyperelasticMaterialKind::neoHookean), ValidationError);
}

TEST(HexHyperelasticForceModel, AFlatElementNeedsInversionHandling) {
  const TetMesh mesh = test::hexBar(1);
  Eigen::VectorXd flat = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) flat[(3 * v) + 2] = -mesh.restPosition(v).z();  // J = 0 everywhere
  HexHyperelasticForceModel plain(mesh, HyperelasticMaterialKind::neoHookean);
  Eigen::VectorXd forces;
  try {
    plain.internalForces(flat, forces);
    ADD_FAILURE() << "a flat neo-Hookean element gave finite forces";
  } catch (const NumericalError& error) {
    EXPECT_NE(std::string(error.what()).find("element 0"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("inversion threshold"), std::string::npos) << error.what();
  }
  HyperelasticOptions options;
  options.inversionThreshold = 0.2;
  HexHyperelasticForceModel invertible(mesh, HyperelasticMaterialKind::neoHookean, options);
  invertible.internalForces(flat, forces);
  EXPECT_TRUE(forces.allFinite());
  EXPECT_GT(forces.norm(), 0.0);
}

}  // namespace
}  // namespace asyncfem
