// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <thread>

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

// Residual tolerance: the test matrices below have condition numbers below ~1e3, so a
// backward-stable factorization leaves a relative residual of about cond * 1e-16 = 1e-13;
// 1e-10 leaves three orders of magnitude of margin.
constexpr double kResidualTolerance = 1e-10;

/// 3D grid Laplacian (7-point) plus shift * I: SPD, n = k^3.
SparseMatrix gridLaplacian(int k, double shift) {
  const int n = k * k * k;
  std::vector<Eigen::Triplet<double>> t;
  auto id = [k](int i, int j, int l) { return i + k * (j + k * l); };
  for (int l = 0; l < k; ++l)
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k; ++i) {
        const int row = id(i, j, l);
        t.emplace_back(row, row, 6.0 + shift);
        if (i > 0) t.emplace_back(row, id(i - 1, j, l), -1.0);
        if (i + 1 < k) t.emplace_back(row, id(i + 1, j, l), -1.0);
        if (j > 0) t.emplace_back(row, id(i, j - 1, l), -1.0);
        if (j + 1 < k) t.emplace_back(row, id(i, j + 1, l), -1.0);
        if (l > 0) t.emplace_back(row, id(i, j, l - 1), -1.0);
        if (l + 1 < k) t.emplace_back(row, id(i, j, l + 1), -1.0);
      }
  SparseMatrix a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  a.makeCompressed();
  return a;
}

/// Structurally symmetric, numerically unsymmetric: Laplacian with perturbed off-diagonals.
SparseMatrix unsymmetric(int k, unsigned seed) {
  SparseMatrix a = gridLaplacian(k, 1.0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int c = 0; c < a.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(a, c); it; ++it)
      if (it.row() != it.col()) it.valueRef() += u(rng);
  return a;
}

double relativeResidual(const SparseMatrix& a, const Eigen::MatrixXd& x, const Eigen::MatrixXd& b) {
  return (a * x - b).norm() / b.norm();
}

Eigen::MatrixXd randomRhs(Eigen::Index n, Eigen::Index k, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd b(n, k);
  for (Eigen::Index i = 0; i < b.size(); ++i) b.data()[i] = g(rng);
  return b;
}

const SolverKind kAllKinds[] = {SolverKind::cholmod, SolverKind::umfpack, SolverKind::eigenLDLT, SolverKind::eigenLU};
const SolverKind kUnsymmetricKinds[] = {SolverKind::umfpack, SolverKind::eigenLU};

TEST(SparseSolver, SolvesSpdSystems) {
  const SparseMatrix a = gridLaplacian(14, 0.5);  // 2744 unknowns
  const Eigen::MatrixXd b = randomRhs(a.rows(), 1, 1);
  for (SolverKind kind : kAllKinds) {
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    Eigen::MatrixXd x;
    solver->solve(b, x);
    EXPECT_LT(relativeResidual(a, x, b), kResidualTolerance) << toString(kind);
    EXPECT_EQ(solver->kind(), kind);
    EXPECT_GT(solver->stats().factorNonZeros, 0) << toString(kind);
    EXPECT_EQ(solver->stats().solvedRightHandSides, 1) << toString(kind);
  }
}

TEST(SparseSolver, SolvesUnsymmetricSystems) {
  const SparseMatrix a = unsymmetric(12, 3);
  const Eigen::MatrixXd b = randomRhs(a.rows(), 1, 2);
  for (SolverKind kind : kUnsymmetricKinds) {
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    EXPECT_LT(relativeResidual(a, solver->solve(Eigen::VectorXd(b.col(0))), b), kResidualTolerance) << toString(kind);
  }
  // The symmetric solvers read only the upper triangle, so they solve another system:
  // their residual on the unsymmetric matrix must be visibly large (the test can fail).
  auto cholmod = makeSparseSolver(SolverKind::cholmod);
  cholmod->compute(a);
  EXPECT_GT(relativeResidual(a, cholmod->solve(Eigen::VectorXd(b.col(0))), b), 1e-6);
}

TEST(SparseSolver, MultipleRightHandSidesMatchColumnByColumn) {
  const SparseMatrix a = gridLaplacian(10, 0.1);
  const Eigen::MatrixXd b = randomRhs(a.rows(), 5, 4);
  for (SolverKind kind : kAllKinds) {
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    Eigen::MatrixXd x;
    solver->solve(b, x);
    ASSERT_EQ(x.cols(), 5);
    for (int c = 0; c < 5; ++c) {
      const Eigen::VectorXd xc = solver->solve(Eigen::VectorXd(b.col(c)));
      EXPECT_LT((x.col(c) - xc).norm() / xc.norm(), 1e-12) << toString(kind);
    }
  }
}

TEST(SparseSolver, RefactorizationReusesTheAnalysis) {
  SparseMatrix a = gridLaplacian(10, 0.1);
  const Eigen::MatrixXd b = randomRhs(a.rows(), 1, 5);
  for (SolverKind kind : kAllKinds) {
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    SparseMatrix scaled = a;
    scaled.coeffs() *= 3.0;
    for (int k = 0; k < scaled.outerSize(); ++k) scaled.coeffRef(k, k) += 1.0;
    solver->factorize(scaled);
    Eigen::MatrixXd x;
    solver->solve(b, x);
    EXPECT_LT(relativeResidual(scaled, x, b), kResidualTolerance) << toString(kind);
    EXPECT_EQ(solver->stats().analyses, 1) << toString(kind);
    EXPECT_EQ(solver->stats().factorizations, 2) << toString(kind);
  }
}

TEST(SparseSolver, CholmodUsesMetisOrdering) {
  auto solver = makeSparseSolver(SolverKind::cholmod);
  solver->compute(gridLaplacian(12, 0.1));
  EXPECT_EQ(solver->ordering(), "metis");
  EXPECT_GT(solver->stats().factorFlops, 0.0);
}

TEST(SparseSolver, NotPositiveDefiniteIsANumericalError) {
  SparseMatrix a = gridLaplacian(6, 0.0);
  a.coeffRef(10, 10) = -50.0;
  for (SolverKind kind : {SolverKind::cholmod, SolverKind::eigenLDLT}) {
    auto solver = makeSparseSolver(kind);
    solver->analyzePattern(a);
    try {
      solver->factorize(a);
      ADD_FAILURE() << toString(kind) << " accepted an indefinite matrix";
    } catch (const NumericalError& e) {
      EXPECT_NE(std::string(e.what()).find("not positive definite"), std::string::npos) << e.what();
    }
    Eigen::MatrixXd x;
    EXPECT_THROW(solver->solve(Eigen::VectorXd::Ones(a.rows()), x), Error) << toString(kind);
  }
}

TEST(SparseSolver, SingularIsANumericalError) {
  SparseMatrix a = unsymmetric(5, 9);
  // Make column 7 zero (structurally present, numerically zero).
  for (SparseMatrix::InnerIterator it(a, 7); it; ++it) it.valueRef() = 0.0;
  for (SolverKind kind : kUnsymmetricKinds) {
    auto solver = makeSparseSolver(kind);
    solver->analyzePattern(a);
    EXPECT_THROW(solver->factorize(a), NumericalError) << toString(kind);
  }
}

TEST(SparseSolver, MisuseGivesClearErrors) {
  const SparseMatrix a = gridLaplacian(5, 1.0);
  const SparseMatrix other = gridLaplacian(6, 1.0);
  for (SolverKind kind : kAllKinds) {
    auto solver = makeSparseSolver(kind);
    Eigen::MatrixXd x;
    EXPECT_THROW(solver->factorize(a), Error) << toString(kind);
    solver->analyzePattern(a);
    EXPECT_THROW(solver->solve(Eigen::VectorXd::Ones(a.rows()), x), Error) << toString(kind);
    try {
      solver->factorize(other);
      ADD_FAILURE() << "pattern mismatch accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("analyzePattern"), std::string::npos) << e.what();
    }
    solver->factorize(a);
    try {
      solver->solve(Eigen::VectorXd::Ones(a.rows() + 1), x);
      ADD_FAILURE() << "wrong rhs size accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("rows"), std::string::npos) << e.what();
    }
  }
}

TEST(SparseSolver, KindNamesRoundTrip) {
  for (SolverKind kind : kAllKinds) EXPECT_EQ(parseSolverKind(toString(kind)), kind);
  try {
    parseSolverKind("superlu");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("superlu"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("cholmod"), std::string::npos);
  }
}

TEST(SparseSolver, IndependentSolversRunConcurrently) {
  const SparseMatrix a = gridLaplacian(12, 0.2);
  const SparseMatrix c = unsymmetric(12, 11);
  const Eigen::MatrixXd b = randomRhs(a.rows(), 2, 6);
  double residualA = 1, residualC = 1;
  std::thread t1([&] {
    auto s = makeSparseSolver(SolverKind::cholmod);
    for (int k = 0; k < 5; ++k) s->compute(a);
    Eigen::MatrixXd x;
    s->solve(b, x);
    residualA = relativeResidual(a, x, b);
  });
  std::thread t2([&] {
    auto s = makeSparseSolver(SolverKind::umfpack);
    for (int k = 0; k < 5; ++k) s->compute(c);
    Eigen::MatrixXd x;
    s->solve(b, x);
    residualC = relativeResidual(c, x, b);
  });
  t1.join();
  t2.join();
  EXPECT_LT(residualA, kResidualTolerance);
  EXPECT_LT(residualC, kResidualTolerance);
}

}  // namespace
}  // namespace asyncfem
