// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <asyncfem/core/error.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cstring>
#include <random>
#include <string>

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

SparseMatrix boxStiffness() {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i(2, 2, 1);
  spec.material = Material{"m", 1000.0, 3e6, 0.35};
  const TetMesh mesh = makeBoxMesh(spec);
  const MatrixAssembler assembler(mesh);
  return linearStiffnessMatrix(mesh, assembler);
}

Eigen::VectorXd randomVector(Eigen::Index size, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> value(-0.01, 0.01);
  Eigen::VectorXd v(size);
  for (Eigen::Index i = 0; i < size; ++i) v[i] = value(random);
  return v;
}

bool sameValues(const SparseMatrix& a, const SparseMatrix& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && a.nonZeros() == b.nonZeros() &&
         std::memcmp(a.valuePtr(), b.valuePtr(), sizeof(double) * static_cast<std::size_t>(a.nonZeros())) == 0 &&
         std::memcmp(a.innerIndexPtr(), b.innerIndexPtr(), sizeof(int) * static_cast<std::size_t>(a.nonZeros())) == 0;
}

TEST(LinearForceModel, ForcesAreStiffnessTimesDisplacement) {
  const SparseMatrix k = boxStiffness();
  LinearForceModel model(k);
  EXPECT_TRUE(model.isLinear());
  EXPECT_EQ(model.numDofs(), k.rows());
  const Eigen::VectorXd u = randomVector(k.rows(), 1);
  Eigen::VectorXd f;
  model.internalForces(u, f);
  // Reference through a dense product: the summation order differs, so only rounding
  // (a few ulps of |K| |u| per entry) separates the two.
  const Eigen::VectorXd reference = Eigen::MatrixXd(k) * u;
  const double scale = (Eigen::MatrixXd(k).cwiseAbs() * u.cwiseAbs()).maxCoeff();
  EXPECT_LE((f - reference).cwiseAbs().maxCoeff(), 1e-13 * scale);
}

TEST(LinearForceModel, EnergyIsHalfDisplacementTimesForce) {
  const SparseMatrix k = boxStiffness();
  LinearForceModel model(k);
  const Eigen::VectorXd u = randomVector(k.rows(), 2);
  const double reference = 0.5 * u.dot(Eigen::MatrixXd(k) * u);
  // K is positive semi-definite, so the energy is a sum with little cancellation;
  // 1e-12 relative is rounding with margin.
  EXPECT_NEAR(model.elasticEnergy(u), reference, 1e-12 * std::abs(reference));
  EXPECT_GT(reference, 0.0);
  EXPECT_EQ(model.elasticEnergy(Eigen::VectorXd::Zero(k.rows())), 0.0);
  // Forces are the energy gradient: central differences of a quadratic are exact up to
  // rounding (step 1e-6, 1e-4 of |u| ~ 1e-2: rounding eps E / step ~ 1e-12 of |f|).
  Eigen::VectorXd f;
  model.internalForces(u, f);
  const double step = 1e-6;
  for (Eigen::Index j = 0; j < u.size(); j += 7) {
    Eigen::VectorXd plus = u;
    Eigen::VectorXd minus = u;
    plus[j] += step;
    minus[j] -= step;
    const double derivative = (model.elasticEnergy(plus) - model.elasticEnergy(minus)) / (2.0 * step);
    EXPECT_NEAR(derivative, f[j], 1e-6 * f.cwiseAbs().maxCoeff()) << "dof " << j;
  }
}

TEST(LinearForceModel, TangentCopiesTheStiffness) {
  const SparseMatrix k = boxStiffness();
  LinearForceModel model(k);
  const Eigen::VectorXd u = randomVector(k.rows(), 3);

  SparseMatrix patterned = model.createStiffnessMatrix();
  ASSERT_EQ(patterned.nonZeros(), k.nonZeros());
  for (Eigen::Index i = 0; i < patterned.nonZeros(); ++i) EXPECT_EQ(patterned.valuePtr()[i], 0.0);
  model.tangentStiffness(u, patterned);
  EXPECT_TRUE(sameValues(patterned, k));

  SparseMatrix empty;  // no pattern yet: replaced by a copy
  model.tangentStiffness(u, empty);
  EXPECT_TRUE(sameValues(empty, k));

  Eigen::VectorXd f;
  SparseMatrix both = model.createStiffnessMatrix();
  model.forcesAndTangent(u, f, both);
  EXPECT_TRUE(sameValues(both, k));
  EXPECT_LE((f - k * u).cwiseAbs().maxCoeff(), 0.0);  // the same product, bit for bit
}

TEST(LinearForceModel, RejectsNonSquareStiffnessAndWrongDisplacementSize) {
  EXPECT_THROW(LinearForceModel(SparseMatrix(6, 3)), Error);
  const SparseMatrix k = boxStiffness();
  LinearForceModel model(k);
  Eigen::VectorXd f;
  try {
    model.internalForces(Eigen::VectorXd::Zero(4), f);
    FAIL() << "no exception";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("displacement has size 4"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace asyncfem
