// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>
#include <omp.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/hyperelasticFEM/stvkFEM.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <cstring>
#include <random>
#include <string>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

using test::allModelCases;
using test::ModelCase;

// Tolerances. Finite differences use the step t = 1e-6 (length units; the cells are 0.5
// long, so strains change by 2e-6): the central-difference truncation error is
// O(t^2) ~ 1e-12 relative and the rounding error eps |f| / t ~ 1e-10 relative, so 1e-6
// relative to the largest entry leaves four orders of margin while a wrong term (e.g. a
// dropped rotation block, which is O(stress / E) ~ 1e-2) fails.
constexpr double kStep = 1e-6;
constexpr double kFiniteDifferenceTolerance = 1e-6;

double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const double scale = std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff());
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

TEST(HyperelasticOptions, VegaLameParametersFollowEAndNu) {
  // Vega's ENuMaterial formulas, and the same numbers as linear FEM's lameParameters().
  const LameParameters lame = vegaLameParameters(1e6, 0.45);
  EXPECT_NEAR(lame.lambda, 0.45 * 1e6 / (1.45 * 0.1), 1e-9 * lame.lambda);
  EXPECT_NEAR(lame.mu, 1e6 / 2.9, 1e-9 * lame.mu);
  const Eigen::Vector2d linear = lameParameters(1e6, 0.45);
  EXPECT_DOUBLE_EQ(lame.lambda, linear[0]);
  EXPECT_DOUBLE_EQ(lame.mu, linear[1]);
}

TEST(HyperelasticOptions, MooneyRivlinSmallStrainModuliInvertTheMatching) {
  const MooneyRivlinParameters parameters = test::matchingMooneyRivlin(3e5, 0.3);
  const SmallStrainModuli moduli = mooneyRivlinSmallStrainModuli(parameters);
  EXPECT_NEAR(moduli.youngsModulus, 3e5, 1e-9 * 3e5);
  EXPECT_NEAR(moduli.poissonRatio, 0.3, 1e-12);
  EXPECT_THROW(mooneyRivlinSmallStrainModuli({1.0, -2.0, 5.0}), ValidationError);
  EXPECT_THROW(mooneyRivlinSmallStrainModuli({1.0, 2.0, 0.0}), ValidationError);
}

TEST(HyperelasticOptions, ParsesMaterialNamesAndRejectsOthers) {
  EXPECT_EQ(parseHyperelasticMaterialKind("stvk"), HyperelasticMaterialKind::stvk);
  EXPECT_EQ(parseHyperelasticMaterialKind("Neo-Hookean"), HyperelasticMaterialKind::neoHookean);
  EXPECT_EQ(parseHyperelasticMaterialKind("mooney-rivlin"), HyperelasticMaterialKind::mooneyRivlin);
  for (const auto kind :
       {HyperelasticMaterialKind::stvk, HyperelasticMaterialKind::neoHookean, HyperelasticMaterialKind::mooneyRivlin}) {
    EXPECT_EQ(parseHyperelasticMaterialKind(toString(kind)), kind);
  }
  try {
    parseHyperelasticMaterialKind("ogden");
    FAIL() << "expected a ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("'ogden'"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("neo-hookean"), std::string::npos) << error.what();
  }
}

TEST(HyperelasticFactory, RejectsBadOptionsWithClearMessages) {
  const TetMesh mesh = test::smallBox(1);
  HyperelasticOptions green;
  green.inversionThreshold = 0.3;
  EXPECT_THROW(makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::stvk, green), ValidationError);
  HyperelasticOptions badThreshold;
  badThreshold.inversionThreshold = 1.5;
  try {
    makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::neoHookean, badThreshold);
    FAIL() << "expected a ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("inversion threshold 1.5"), std::string::npos) << error.what();
  }
  // A Mooney-Rivlin model on an E, nu material names the element and the material.
  TetMesh plain = mesh;
  plain.addMaterial(Material{"m", 1000.0, 1e6, 0.4});
  try {
    makeHyperelasticForceModel(plain, HyperelasticMaterialKind::mooneyRivlin);
    FAIL() << "expected a ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("element 0 has material 'm'"), std::string::npos) << error.what();
  }
  // ... and the override makes it valid.
  HyperelasticOptions overridden;
  overridden.mooneyRivlin = test::matchingMooneyRivlin(1e6, 0.4);
  EXPECT_NO_THROW(makeHyperelasticForceModel(plain, HyperelasticMaterialKind::mooneyRivlin, overridden));
}

TEST(HyperelasticFEM, RestStateAndRigidMotionsHaveNoForceOrEnergy) {
  const TetMesh mesh = test::smallBox(2);
  std::mt19937 random(7);
  for (const ModelCase& c : allModelCases()) {
    SCOPED_TRACE(c.label);
    auto model = makeHyperelasticForceModel(mesh, c.kind, c.options);
    const Eigen::VectorXd rest = Eigen::VectorXd::Zero(mesh.numDofs());
    // Force scale E h^2 (h = 0.5): rounding leaves about 1e-16 of it.
    const double forceScale = test::kYoungsModulus * 0.25;
    EXPECT_LE(test::forces(*model, rest).cwiseAbs().maxCoeff(), 1e-10 * forceScale);
    EXPECT_NEAR(model->elasticEnergy(rest), 0.0, 1e-12 * test::kYoungsModulus);
    const Eigen::VectorXd rigid = test::deformedDisplacement(mesh, test::randomRotation(random), 0.0, random);
    EXPECT_LE(test::forces(*model, rigid).cwiseAbs().maxCoeff(), 1e-9 * forceScale);
    EXPECT_NEAR(model->elasticEnergy(rigid), 0.0, 1e-9 * test::kYoungsModulus);
  }
}

TEST(HyperelasticFEM, ForcesAreTheEnergyGradientAndTangentsTheirJacobian) {
  const TetMesh mesh = test::smallBox(2);
  std::mt19937 random(11);
  for (const ModelCase& c : allModelCases()) {
    SCOPED_TRACE(c.label);
    auto model = makeHyperelasticForceModel(mesh, c.kind, c.options);
    // Strains of about 0.1 / 0.5 = 20 %, rotated: far from the small-strain regime.
    const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), 0.1, random);
    const Eigen::VectorXd f = test::forces(*model, u);
    EXPECT_LE(relativeDifference(f, test::finiteDifferenceForces(*model, u, kStep)), kFiniteDifferenceTolerance);
    const Eigen::MatrixXd k = test::tangent(*model, u);
    EXPECT_LE(relativeDifference(k, test::finiteDifferenceTangent(*model, u, kStep)), kFiniteDifferenceTolerance);
    // forcesAndTangent gives the same numbers as the separate calls.
    Eigen::VectorXd fBoth;
    Eigen::SparseMatrix<double> kBoth = model->createStiffnessMatrix();
    model->forcesAndTangent(u, fBoth, kBoth);
    EXPECT_EQ((fBoth - f).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((Eigen::MatrixXd(kBoth) - k).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(HyperelasticFEM, InvariantPathEqualsPrincipalStretchPath) {
  // The invariant path (no SVD) and the principal-stretch path are the same derivatives of
  // the same energy wherever no stretch is clamped, so they differ by rounding only: a few
  // hundred flops each, entries of size E, relative rounding about 1e-15 per operation
  // chain; 1e-11 of the largest entry leaves margin while any wrong term (size stress / E
  // ~ 1e-2 relative) fails. Elements at or below the threshold take the principal-stretch
  // path in both models, so equality must hold for them exactly as well.
  const TetMesh mesh = test::smallBox(2);
  std::mt19937 random(29);
  for (const ModelCase& c : allModelCases()) {
    if (c.kind == HyperelasticMaterialKind::stvk && c.options.stvkFormulation == StVKFormulation::greenStrain) continue;
    SCOPED_TRACE(c.label);
    HyperelasticOptions principal = c.options;
    principal.invariantPath = false;
    auto fast = makeHyperelasticForceModel(mesh, c.kind, c.options);
    auto reference = makeHyperelasticForceModel(mesh, c.kind, principal);
    Eigen::Matrix3d squeezed = Eigen::Matrix3d::Identity();
    squeezed(2, 2) = 0.15;  // below the 0.2 threshold: the principal-stretch path in both
    for (const Eigen::VectorXd& u : {test::deformedDisplacement(mesh, test::randomRotation(random), 0.1, random),
                                     test::deformedDisplacement(mesh, test::randomRotation(random), 0.25, random),
                                     test::homogeneousDisplacement(mesh, Eigen::Vector3d(0.7, 0.8, 0.9).asDiagonal()),
                                     test::homogeneousDisplacement(mesh, squeezed)}) {
      EXPECT_LE(relativeDifference(test::forces(*fast, u), test::forces(*reference, u)), 1e-11);
      EXPECT_LE(relativeDifference(test::tangent(*fast, u), test::tangent(*reference, u)), 1e-11);
      EXPECT_NEAR(fast->elasticEnergy(u), reference->elasticEnergy(u),
                  1e-11 * std::max(1.0, std::abs(reference->elasticEnergy(u))));
    }
  }
}

TEST(HyperelasticFEM, SmallStrainTangentEqualsLinearFEM) {
  const TetMesh mesh = test::smallBox(2);
  const MatrixAssembler assembler(mesh);
  const Eigen::MatrixXd linear(linearStiffnessMatrix(mesh, assembler));
  for (const ModelCase& c : allModelCases()) {
    SCOPED_TRACE(c.label);
    auto model = makeHyperelasticForceModel(mesh, c.kind, c.options);
    // At rest the hyperelastic tangents are exactly the linear elasticity tensor with the
    // same Lame parameters; only rounding (1e-16 of K, accumulated over a few products)
    // separates them.
    EXPECT_LE(relativeDifference(test::tangent(*model, Eigen::VectorXd::Zero(mesh.numDofs())), linear), 1e-10);
  }
}

TEST(HyperelasticFEM, EnergyAndForcesAreRotationInvariant) {
  const TetMesh mesh = test::smallBox(2);
  std::mt19937 random(5);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  for (const ModelCase& c : allModelCases()) {
    SCOPED_TRACE(c.label);
    auto model = makeHyperelasticForceModel(mesh, c.kind, c.options);
    std::mt19937 sameOffsets(99);
    const Eigen::VectorXd unrotated = test::deformedDisplacement(mesh, identity, 0.08, sameOffsets);
    const Eigen::Matrix3d q = test::randomRotation(random);
    std::mt19937 sameOffsetsAgain(99);
    const Eigen::VectorXd rotated = test::deformedDisplacement(mesh, q, 0.08, sameOffsetsAgain);
    const double energy = model->elasticEnergy(unrotated);
    EXPECT_NEAR(model->elasticEnergy(rotated), energy, 1e-10 * energy);
    const Eigen::VectorXd f0 = test::forces(*model, unrotated);
    const Eigen::VectorXd f1 = test::forces(*model, rotated);
    Eigen::VectorXd rotatedBack(f1.size());
    for (int v = 0; v < mesh.numVertices(); ++v) rotatedBack.segment<3>(3 * v) = q.transpose() * f1.segment<3>(3 * v);
    EXPECT_LE(relativeDifference(rotatedBack, f0), 1e-10);
  }
}

TEST(HyperelasticFEM, ElementTangentMatchesAssembledContribution) {
  const TetMesh mesh = test::unitTet();
  std::mt19937 random(3);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), 0.2, random);
  for (const ModelCase& c : allModelCases()) {
    SCOPED_TRACE(c.label);
    auto model = makeHyperelasticForceModel(mesh, c.kind, c.options);
    ElementMatrix element;
    ASSERT_TRUE(model->elementTangent(u, 0, element));
    // One element, vertices 0..3 in order: the assembled matrix is the element matrix.
    EXPECT_EQ((test::tangent(*model, u) - Eigen::MatrixXd(element)).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(HyperelasticFEM, ResultsAreBitIdenticalForAnyThreadCount) {
  const TetMesh mesh = test::smallBox(3);
  std::mt19937 random(17);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), 0.05, random);
  HyperelasticOptions options;
  options.inversionThreshold = 0.3;
  IsotropicHyperelasticFEM model(mesh, HyperelasticMaterialKind::neoHookean, options);
  const int saved = omp_get_max_threads();
  Eigen::VectorXd f1;
  Eigen::VectorXd f2;
  Eigen::SparseMatrix<double> k1 = model.createStiffnessMatrix();
  Eigen::SparseMatrix<double> k2 = model.createStiffnessMatrix();
  omp_set_num_threads(1);
  model.forcesAndTangent(u, f1, k1);
  const double e1 = model.elasticEnergy(u);
  omp_set_num_threads(3);
  model.forcesAndTangent(u, f2, k2);
  const double e2 = model.elasticEnergy(u);
  omp_set_num_threads(saved);
  EXPECT_EQ(std::memcmp(f1.data(), f2.data(), sizeof(double) * static_cast<std::size_t>(f1.size())), 0);
  EXPECT_EQ(std::memcmp(k1.valuePtr(), k2.valuePtr(), sizeof(double) * static_cast<std::size_t>(k1.nonZeros())), 0);
  EXPECT_EQ(e1, e2);
}

TEST(HyperelasticFEM, WrongSizesAndElementsAreReported) {
  const TetMesh mesh = test::unitTet();
  StVKFEM model(mesh);
  Eigen::VectorXd f;
  EXPECT_THROW(model.internalForces(Eigen::VectorXd::Zero(5), f), Error);
  ElementMatrix k;
  EXPECT_THROW(model.elementTangent(Eigen::VectorXd::Zero(12), 1, k), Error);
}

}  // namespace
}  // namespace asyncfem
