// SPDX-License-Identifier: BSD-3-Clause
// The fused element kernel of CorotationalLinearFEM against the textbook form of the
// model (Mueller & Gross 2004): R from the SVD polar decomposition, f_e = R K_e (R^T x -
// X), K_e^R = R K_e R^T with the dense 12x12 K_e, E_e = 1/2 v^T K_e v; and the cache that
// makes the energy of an evaluated displacement free.
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <cmath>
#include <random>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

struct Reference {
  Eigen::VectorXd forces;
  SparseMatrix tangent;
  double energy = 0.0;
};

// The model written element by element with dense matrices.
Reference textbook(const TetMesh& mesh, const CorotationalLinearFEM& model, const Eigen::VectorXd& u) {
  const MatrixAssembler& assembler = model.assembler();
  std::vector<Eigen::Matrix3d> rotations(static_cast<std::size_t>(mesh.numElements()));
  Reference result;
  result.forces = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int e = 0; e < mesh.numElements(); ++e) {
    const ElementPositions rest = mesh.elementRestPositions(e);
    ElementPositions x = rest;
    for (int a = 0; a < 4; ++a) x.col(a) += u.segment<3>(3 * mesh.elements()(a, e));
    double volume = 0.0;
    const Eigen::Matrix<double, 3, 4> g = shapeFunctionGradients(rest, &volume);
    const Eigen::Matrix3d r = polarDecomposition(x * g.transpose()).rotation;
    rotations[static_cast<std::size_t>(e)] = r;
    ElementPositions v = r.transpose() * x - rest;
    const ElementVector stacked = Eigen::Map<const ElementVector>(v.data());
    const ElementVector kv = model.elementStiffness(e) * stacked;
    result.energy += 0.5 * stacked.dot(kv);
    for (int a = 0; a < 4; ++a) result.forces.segment<3>(3 * mesh.elements()(a, e)) += r * kv.segment<3>(3 * a);
  }
  result.tangent = assembler.createMatrix();
  assembler.assemble(
      [&](int e, ElementMatrix& out) {
        Eigen::Matrix<double, 12, 12> blockRotation = Eigen::Matrix<double, 12, 12>::Zero();
        for (int a = 0; a < 4; ++a) blockRotation.block<3, 3>(3 * a, 3 * a) = rotations[static_cast<std::size_t>(e)];
        out = blockRotation * model.elementStiffness(e) * blockRotation.transpose();
      },
      result.tangent);
  return result;
}

Eigen::Map<const Eigen::VectorXd> values(const SparseMatrix& m) { return {m.valuePtr(), m.nonZeros()}; }

TEST(CorotationalKernel, EqualsTheTextbookModelToRounding) {
  const int cells = 4;
  const TetMesh mesh = test::smallBox(cells);
  std::mt19937 random(31);
  // From nearly rigid to inverted elements (amplitude 0.6 cells).
  for (const double amplitude : {0.0, 0.01, 0.1, 0.6}) {
    SCOPED_TRACE(amplitude);
    const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d(1, 2, 3),
                                                         amplitude * test::cellSize(cells), random);
    CorotationalLinearFEM model(mesh);
    Eigen::VectorXd f;
    SparseMatrix k = model.createStiffnessMatrix();
    model.forcesAndTangent(u, f, k);
    const double energy = model.elasticEnergy(u);
    const Reference reference = textbook(mesh, model, u);
    // Both sides cancel terms of size E h^2 |x| / h (positions of order 5 over cells of
    // 0.25) down to forces of size E h^2 times the strain: rounding is ~1e-16 * 20 of
    // the force scale E h^2; 1e-11 bounds it with margin and is far below any real error
    // (a wrong rotation or block is off by the strain times E h^2).
    const double forceScale = test::kYoungsModulus * test::cellSize(cells) * test::cellSize(cells);
    EXPECT_LE(test::maxAbsDifference(f, reference.forces), 1e-11 * forceScale);
    // Tangent entries are E h times rotation products of order 1: relative rounding.
    const double tangentScale = test::kYoungsModulus * test::cellSize(cells);
    EXPECT_LE((values(k) - values(reference.tangent)).cwiseAbs().maxCoeff(), 1e-12 * tangentScale);
    // Energy: a sum of positive terms E V strain^2, so relative rounding (1e-12), plus
    // the rounding of the textbook side: its v = R^T x - X holds the rigid translation
    // Q^T t (|t|^2 = 14), which K_e cancels only to rounding, eps |K_e| |t|^2 ~ 1e-16 E h
    // |t|^2 per element (the strain form computed by the model has no such term).
    const double translationRounding =
        1e-16 * test::kYoungsModulus * test::cellSize(cells) * 14.0 * static_cast<double>(mesh.numElements());
    EXPECT_LE(std::abs(energy - reference.energy), (1e-12 * reference.energy) + translationRounding);
    for (int e = 0; e < mesh.numElements(); ++e) {
      EXPECT_NEAR(model.rotations()[static_cast<std::size_t>(e)].determinant(), 1.0, 1e-12);
    }
  }
}

TEST(CorotationalKernel, EnergyOfAnEvaluatedDisplacementIsReusedAndExact) {
  const TetMesh mesh = test::smallBox(3);
  std::mt19937 random(37);
  const Eigen::VectorXd u =
      test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d::Zero(), 0.05, random);
  CorotationalLinearFEM model(mesh);
  EXPECT_FALSE(model.hasLastEvaluation());
  EXPECT_THROW(static_cast<void>(model.energyOfLastEvaluation()), Error);
  Eigen::VectorXd f;
  SparseMatrix k = model.createStiffnessMatrix();
  model.forcesAndTangent(u, f, k);
  const long long extractions = model.rotationStats().extractions;
  const double reused = model.elasticEnergy(u);
  // No element rotation was computed again, and the value is the one a fresh model
  // computes from scratch, bit for bit.
  EXPECT_EQ(model.rotationStats().extractions, extractions);
  EXPECT_EQ(model.rotationStats().reusedEvaluations, 1);
  CorotationalLinearFEM fresh(mesh);
  EXPECT_EQ(reused, fresh.elasticEnergy(u));
  EXPECT_EQ(model.energyOfLastEvaluation(), reused);
  EXPECT_TRUE(model.displacementOfLastEvaluation() == u);

  // Energy first, then forces at the same displacement: the forces reuse the rotations
  // and equal a fresh evaluation.
  Eigen::VectorXd other = u;
  other[5] += 1e-3;
  CorotationalLinearFEM energyFirst(mesh);
  const double otherEnergy = energyFirst.elasticEnergy(other);
  Eigen::VectorXd fReused;
  energyFirst.internalForces(other, fReused);
  EXPECT_EQ(energyFirst.rotationStats().extractions, mesh.numElements());
  Eigen::VectorXd fFresh;
  fresh.internalForces(other, fFresh);
  EXPECT_TRUE(fReused == fFresh);
  // A displacement that differs in one bit is evaluated again.
  EXPECT_NE(model.elasticEnergy(other), reused);
  EXPECT_EQ(model.elasticEnergy(other), otherEnergy);
}

TEST(CorotationalKernel, WarmStartGivesTheSameResultsWithFewerNewtonSteps) {
  const int cells = 3;
  const TetMesh mesh = test::smallBox(cells);
  std::mt19937 random(41);
  const Eigen::Matrix3d rotation = test::randomRotation(random);
  const Eigen::VectorXd base =
      test::deformedDisplacement(mesh, rotation, Eigen::Vector3d::Zero(), 0.1 * test::cellSize(cells), random);
  CorotationalLinearFEM cold(mesh);
  CorotationalLinearFEM warm(mesh);
  warm.setRotationStart(RotationStart::previousEvaluation);
  // A smooth motion: small increments of a deformation, evaluated step by step.
  std::uniform_real_distribution<double> jitter(-1e-3, 1e-3);
  Eigen::VectorXd u = base;
  for (int step = 0; step < 10; ++step) {
    for (Eigen::Index i = 0; i < u.size(); ++i) u[i] += jitter(random) * test::cellSize(cells);
    Eigen::VectorXd fCold;
    Eigen::VectorXd fWarm;
    cold.internalForces(u, fCold);
    warm.internalForces(u, fWarm);
    // Same rotations to rounding (see the polar rotation tests), hence forces to
    // rounding of the force scale.
    EXPECT_LE(test::maxAbsDifference(fCold, fWarm),
              1e-11 * test::kYoungsModulus * test::cellSize(cells) * test::cellSize(cells));
  }
  EXPECT_LT(warm.rotationStats().newtonSteps, cold.rotationStats().newtonSteps);
  EXPECT_EQ(warm.rotationStats().decompositionFallbacks, 0);
}

TEST(CorotationalKernel, MatrixWithAnotherPatternIsRejected) {
  const TetMesh mesh = test::smallBox(2);
  CorotationalLinearFEM model(mesh);
  SparseMatrix k = model.createStiffnessMatrix();
  // Same size and entry count, other column starts.
  k.outerIndexPtr()[1] += 1;
  EXPECT_THROW(model.tangentStiffness(Eigen::VectorXd::Zero(mesh.numDofs()), k), Error);
}

}  // namespace
}  // namespace asyncfem
