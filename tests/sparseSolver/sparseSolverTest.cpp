// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "../common/gaussianMatrix.hpp"
#include "gridLaplacian.hpp"

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using test::gridLaplacian;

// Relative residual tolerance. A backward-stable factorization gives
// ||A x - b|| / ||b|| <= g * cond(A) * eps with a modest growth factor g. The test
// matrices have cond(A) <= 121 (grid Laplacians with shift >= 0.1: eigenvalues in
// [shift, 12 + shift]) or cond_inf(A) <= 79 (the unsymmetric ones, strictly diagonally
// dominant with margin 0.2), so cond * eps <= 3e-14; 1e-10 leaves room for g up to 3000.
constexpr double kResidualTolerance = 1e-10;

/// Structurally symmetric, numerically unsymmetric: the Laplacian with shift 2 (diagonal
/// 8) and each off-diagonal -1 perturbed by U(-0.3, 0.3), so every row is strictly
/// diagonally dominant by at least 8 - 6 * 1.3 = 0.2.
SparseMatrix unsymmetric(int k, unsigned seed) {
  SparseMatrix a = gridLaplacian(k, 2.0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> perturbation(-0.3, 0.3);
  for (int c = 0; c < a.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(a, c); it; ++it)
      if (it.row() != it.col()) it.valueRef() += perturbation(rng);
  return a;
}

double relativeResidual(const SparseMatrix& a, const Eigen::MatrixXd& x, const Eigen::MatrixXd& b) {
  return (a * x - b).norm() / b.norm();
}

long long lowerTriangleNonZeros(const SparseMatrix& a) {
  long long count = 0;
  for (int c = 0; c < a.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(a, c); it; ++it) count += it.row() >= it.col() ? 1 : 0;
  return count;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

const SolverKind kAllKinds[] = {SolverKind::cholmod, SolverKind::umfpack, SolverKind::eigenLDLT, SolverKind::eigenLU,
                                SolverKind::dense};
const SolverKind kUnsymmetricKinds[] = {SolverKind::umfpack, SolverKind::eigenLU};
bool isCholesky(SolverKind kind) {
  return kind == SolverKind::cholmod || kind == SolverKind::eigenLDLT || kind == SolverKind::dense;
}

TEST(SparseSolver, SolvesSpdSystems) {
  const SparseMatrix a = gridLaplacian(14, 0.5);  // 2744 unknowns
  const Eigen::MatrixXd b = test::gaussianMatrix(a.rows(), 1, 1);
  for (SolverKind kind : kAllKinds) {
    auto solver = makeSparseSolver(kind);
    EXPECT_EQ(solver->kind(), kind);
    solver->compute(a);
    Eigen::MatrixXd x;
    solver->solve(b, x);
    ASSERT_EQ(x.rows(), a.rows());
    ASSERT_EQ(x.cols(), 1);
    EXPECT_LT(relativeResidual(a, x, b), kResidualTolerance) << toString(kind);
    EXPECT_LT(relativeResidual(a, solver->solve(Eigen::VectorXd(b.col(0))), b), kResidualTolerance) << toString(kind);
  }
}

TEST(SparseSolver, SolvesUnsymmetricSystems) {
  const SparseMatrix a = unsymmetric(14, 3);
  const Eigen::MatrixXd b = test::gaussianMatrix(a.rows(), 1, 2);
  for (SolverKind kind : kUnsymmetricKinds) {
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    EXPECT_LT(relativeResidual(a, solver->solve(Eigen::VectorXd(b.col(0))), b), kResidualTolerance) << toString(kind);
  }
  // The Cholesky solvers read only the upper triangle, so they solve another (symmetric)
  // system; their residual on the unsymmetric matrix is visibly large.
  for (SolverKind kind : {SolverKind::cholmod, SolverKind::eigenLDLT}) {
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    EXPECT_GT(relativeResidual(a, solver->solve(Eigen::VectorXd(b.col(0))), b), 1e-6) << toString(kind);
  }
}

TEST(SparseSolver, CholeskyReadsOnlyTheUpperTriangle) {
  const SparseMatrix full = gridLaplacian(8, 0.3);
  const SparseMatrix upper = full.triangularView<Eigen::Upper>();
  const Eigen::MatrixXd b = test::gaussianMatrix(full.rows(), 1, 12);
  for (SolverKind kind : {SolverKind::cholmod, SolverKind::eigenLDLT, SolverKind::dense}) {
    auto solver = makeSparseSolver(kind);
    solver->compute(upper);
    EXPECT_LT(relativeResidual(full, solver->solve(Eigen::VectorXd(b.col(0))), b), kResidualTolerance)
        << toString(kind);
  }
}

TEST(SparseSolver, MultipleRightHandSidesMatchColumnByColumn) {
  const SparseMatrix spd = gridLaplacian(10, 0.1);
  const SparseMatrix lu = unsymmetric(10, 7);
  const Eigen::MatrixXd b = test::gaussianMatrix(spd.rows(), 5, 4);
  for (SolverKind kind : kAllKinds) {
    const SparseMatrix& a = isCholesky(kind) ? spd : lu;
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    Eigen::MatrixXd x;
    solver->solve(b, x);
    ASSERT_EQ(x.rows(), a.rows());
    ASSERT_EQ(x.cols(), 5);
    EXPECT_LT(relativeResidual(a, x, b), kResidualTolerance) << toString(kind);
    for (int c = 0; c < 5; ++c) {
      const Eigen::VectorXd xc = solver->solve(Eigen::VectorXd(b.col(c)));
      // Same factor, same substitutions: equal up to the summation order of blocked kernels.
      EXPECT_LE((x.col(c) - xc).norm(), 1e-12 * xc.norm()) << toString(kind) << " column " << c;
    }
    EXPECT_EQ(solver->stats().solvedRightHandSides, 10) << toString(kind);
    // A strided right-hand side (a block of a wider matrix) gives the same solution.
    Eigen::MatrixXd wide = Eigen::MatrixXd::Zero(a.rows() + 3, 8);
    wide.block(2, 1, a.rows(), 5) = b;
    Eigen::MatrixXd xStrided;
    solver->solve(wide.block(2, 1, a.rows(), 5), xStrided);
    EXPECT_LE((xStrided - x).norm(), 1e-12 * x.norm()) << toString(kind);
  }
}

TEST(SparseSolver, RefactorizationReusesTheAnalysis) {
  const SparseMatrix spd = gridLaplacian(10, 0.1);
  const SparseMatrix lu = unsymmetric(10, 5);
  const Eigen::MatrixXd b = test::gaussianMatrix(spd.rows(), 1, 5);
  for (SolverKind kind : kAllKinds) {
    const SparseMatrix& a = isCholesky(kind) ? spd : lu;
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    const Eigen::VectorXd before = solver->solve(Eigen::VectorXd(b.col(0)));
    // New values, same pattern: 3 A + I.
    SparseMatrix changed = a;
    changed.coeffs() *= 3.0;
    for (int k = 0; k < changed.outerSize(); ++k) changed.coeffRef(k, k) += 1.0;
    solver->factorize(changed);
    Eigen::MatrixXd x;
    solver->solve(b, x);
    EXPECT_LT(relativeResidual(changed, x, b), kResidualTolerance) << toString(kind);
    EXPECT_GT((x.col(0) - before).norm(), 0.1 * before.norm()) << toString(kind) << " kept the old factor";
    EXPECT_EQ(solver->stats().analyses, 1) << toString(kind);
    EXPECT_EQ(solver->stats().factorizations, 2) << toString(kind);
  }
}

TEST(SparseSolver, StatsAreConsistent) {
  const SparseMatrix spd = gridLaplacian(10, 0.2);
  const SparseMatrix lu = unsymmetric(10, 8);
  for (SolverKind kind : kAllKinds) {
    const SparseMatrix& a = isCholesky(kind) ? spd : lu;
    auto solver = makeSparseSolver(kind);
    solver->compute(a);
    solver->solve(test::gaussianMatrix(a.rows(), 3, 9).col(0).eval());
    const SolverStats& stats = solver->stats();
    // Fill only adds entries: L holds at least A's lower triangle (L + U at least A).
    EXPECT_GE(stats.factorNonZeros, isCholesky(kind) ? lowerTriangleNonZeros(a) : a.nonZeros()) << toString(kind);
    EXPECT_LE(stats.factorNonZeros, 2LL * a.rows() * a.rows()) << toString(kind);
    // Eliminating n columns costs at least n flops and the factor's entries bound it below.
    EXPECT_GE(stats.factorFlops, static_cast<double>(a.rows())) << toString(kind);
    EXPECT_DOUBLE_EQ(stats.solveFlopsPerRhs, (isCholesky(kind) ? 4.0 : 2.0) * static_cast<double>(stats.factorNonZeros))
        << toString(kind);
    EXPECT_EQ(stats.analyses, 1);
    EXPECT_EQ(stats.factorizations, 1);
    EXPECT_EQ(stats.solvedRightHandSides, 1);
    EXPECT_GE(stats.analyzeSeconds, 0.0);
    EXPECT_GE(stats.factorSeconds, 0.0);
    EXPECT_GE(stats.solveSeconds, 0.0);
    solver->resetStats();
    EXPECT_EQ(solver->stats().factorizations, 0);
  }
}

TEST(SparseSolver, CholeskyFactorSizesAgree) {
  // Both Cholesky backends factor the same matrix; their orderings differ, so their fill
  // differs, but each must at least hold the lower triangle and be of the same magnitude.
  const SparseMatrix a = gridLaplacian(12, 0.2);
  auto cholmod = makeSparseSolver(SolverKind::cholmod);
  auto ldlt = makeSparseSolver(SolverKind::eigenLDLT);
  cholmod->compute(a);
  ldlt->compute(a);
  const double ratio = static_cast<double>(cholmod->stats().factorNonZeros) / ldlt->stats().factorNonZeros;
  EXPECT_GT(ratio, 0.25);
  EXPECT_LT(ratio, 4.0);
}

TEST(SparseSolver, CholmodUsesMetisOrdering) {
  auto solver = makeSparseSolver(SolverKind::cholmod);
  EXPECT_EQ(solver->ordering(), "none");
  solver->compute(gridLaplacian(12, 0.1));
  EXPECT_EQ(solver->ordering(), "metis");
  EXPECT_GT(solver->stats().factorFlops, 0.0);
}

// FillOrdering::automatic: AMD up to kAmdMaxRows rows, METIS above; the solves are as
// exact either way (relative residual 1e-12 for these SPD Laplacians, cond <= 121).
TEST(SparseSolver, AutomaticOrderingTakesAmdForSmallMatrices) {
  for (const int k : {12, 24}) {  // 1,728 and 13,824 rows
    const SparseMatrix a = gridLaplacian(k, 0.1);
    auto solver = makeSparseSolver(SolverKind::cholmod, FillOrdering::automatic);
    solver->compute(a);
    EXPECT_EQ(solver->ordering(), a.rows() <= kAmdMaxRows ? "amd" : "metis") << a.rows() << " rows";
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
    const Eigen::VectorXd x = solver->solve(b);
    EXPECT_LE((a * x - b).norm(), 1e-12 * b.norm());
  }
  ASSERT_LT(12 * 12 * 12, kAmdMaxRows);
  ASSERT_GT(24 * 24 * 24, kAmdMaxRows);
}

TEST(SparseSolver, OtherBackendsReportTheirOrdering) {
  const SparseMatrix a = gridLaplacian(6, 0.5);
  auto umfpack = makeSparseSolver(SolverKind::umfpack);
  umfpack->analyzePattern(a);
  EXPECT_TRUE(umfpack->ordering() == "amd" || umfpack->ordering() == "colamd") << umfpack->ordering();
  auto ldlt = makeSparseSolver(SolverKind::eigenLDLT);
  ldlt->analyzePattern(a);
  EXPECT_EQ(ldlt->ordering(), "amd");
  auto lu = makeSparseSolver(SolverKind::eigenLU);
  lu->analyzePattern(a);
  EXPECT_EQ(lu->ordering(), "colamd");
  auto dense = makeSparseSolver(SolverKind::dense);
  dense->analyzePattern(a);
  EXPECT_EQ(dense->ordering(), "natural");
}

TEST(SparseSolver, DenseRefusesLargeSystems) {
  // 20^3 * 3 = 24000 unknowns would be 4.6 GB dense: refused before anything is allocated.
  SparseMatrix large(24000, 24000);
  large.setIdentity();
  large.makeCompressed();
  auto dense = makeSparseSolver(SolverKind::dense);
  try {
    dense->analyzePattern(large);
    ADD_FAILURE() << "a 24000-unknown dense factor was accepted";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "24000 unknowns")) << e.what();
  }
}

TEST(SparseSolver, NotPositiveDefiniteIsANumericalErrorNamingTheColumn) {
  // Without the entry at column 10 the matrix is SPD, so every principal submatrix that
  // excludes it is too: elimination fails exactly at column 10, whatever the ordering.
  SparseMatrix a = gridLaplacian(6, 0.0);
  a.coeffRef(10, 10) = -50.0;
  for (SolverKind kind : {SolverKind::cholmod, SolverKind::eigenLDLT, SolverKind::dense}) {
    auto solver = makeSparseSolver(kind);
    solver->analyzePattern(a);
    try {
      solver->factorize(a);
      ADD_FAILURE() << toString(kind) << " accepted an indefinite matrix";
    } catch (const NumericalError& e) {
      EXPECT_TRUE(contains(e.what(), "not positive definite")) << e.what();
      EXPECT_TRUE(contains(e.what(), "column 10 ")) << e.what();
    }
    Eigen::MatrixXd x;
    EXPECT_THROW(solver->solve(Eigen::VectorXd::Ones(a.rows()), x), Error) << toString(kind);
    // The same solver recovers once the values are fixed (same pattern, no new analysis).
    SparseMatrix fixed = a;
    fixed.coeffRef(10, 10) = 6.0;
    solver->factorize(fixed);
    const Eigen::MatrixXd b = test::gaussianMatrix(a.rows(), 1, 10);
    solver->solve(b, x);
    EXPECT_LT(relativeResidual(fixed, x, b), kResidualTolerance) << toString(kind);
    EXPECT_EQ(solver->stats().analyses, 1);
  }
}

TEST(SparseSolver, SingularIsANumericalError) {
  SparseMatrix a = unsymmetric(5, 9);
  // Column 7 structurally present but numerically zero.
  for (SparseMatrix::InnerIterator it(a, 7); it; ++it) it.valueRef() = 0.0;
  for (SolverKind kind : kUnsymmetricKinds) {
    auto solver = makeSparseSolver(kind);
    solver->analyzePattern(a);
    try {
      solver->factorize(a);
      ADD_FAILURE() << toString(kind) << " accepted a singular matrix";
    } catch (const NumericalError& e) {
      EXPECT_TRUE(contains(e.what(), "singular")) << e.what();
    }
    Eigen::MatrixXd x;
    EXPECT_THROW(solver->solve(Eigen::VectorXd::Ones(a.rows()), x), Error) << toString(kind);
  }
}

TEST(SparseSolver, MisuseGivesClearErrors) {
  const SparseMatrix a = gridLaplacian(5, 1.0);
  const SparseMatrix larger = gridLaplacian(6, 1.0);
  // Same size and non-zero count as `a`, other indices: one off-diagonal moved.
  SparseMatrix moved = a;
  moved.coeffRef(0, 1) = 0.0;
  moved.prune([](int row, int col, double) { return !(row == 0 && col == 1); });
  moved.insert(0, 3) = 0.5;
  moved.makeCompressed();
  ASSERT_EQ(moved.nonZeros(), a.nonZeros());
  for (SolverKind kind : kAllKinds) {
    const std::string name = toString(kind);
    auto solver = makeSparseSolver(kind);
    Eigen::MatrixXd x;
    try {
      solver->factorize(a);
      ADD_FAILURE() << name << ": factorize before analyzePattern accepted";
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "before analyzePattern")) << e.what();
    }
    solver->analyzePattern(a);
    try {
      solver->solve(Eigen::VectorXd::Ones(a.rows()), x);
      ADD_FAILURE() << name << ": solve before factorize accepted";
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "before a successful factorize")) << e.what();
    }
    const SparseMatrix* otherPatterns[] = {&larger, &moved};
    for (const SparseMatrix* other : otherPatterns) {
      try {
        solver->factorize(*other);
        ADD_FAILURE() << name << ": pattern mismatch accepted";
      } catch (const Error& e) {
        EXPECT_TRUE(contains(e.what(), "call analyzePattern() again")) << e.what();
        EXPECT_TRUE(contains(e.what(), name)) << e.what();
      }
    }
    solver->factorize(a);
    try {
      solver->solve(Eigen::VectorXd::Ones(a.rows() + 1), x);
      ADD_FAILURE() << name << ": wrong rhs size accepted";
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), std::to_string(a.rows() + 1) + " rows")) << e.what();
    }
    // Analysing the other pattern makes it usable.
    solver->compute(larger);
    EXPECT_EQ(solver->stats().analyses, 2);
  }
}

TEST(SparseSolver, RejectsNonSquareAndUncompressedMatrices) {
  SparseMatrix rectangular(4, 5);
  rectangular.insert(0, 0) = 1.0;
  rectangular.makeCompressed();
  SparseMatrix uncompressed = gridLaplacian(3, 1.0);
  uncompressed.insert(0, 26) = 0.1;  // insertion leaves the matrix uncompressed
  ASSERT_FALSE(uncompressed.isCompressed());
  for (SolverKind kind : kAllKinds) {
    auto solver = makeSparseSolver(kind);
    try {
      solver->analyzePattern(rectangular);
      ADD_FAILURE() << toString(kind);
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "not square")) << e.what();
    }
    try {
      solver->analyzePattern(uncompressed);
      ADD_FAILURE() << toString(kind);
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "makeCompressed")) << e.what();
    }
  }
}

TEST(SparseSolver, KindNamesRoundTrip) {
  for (SolverKind kind : kAllKinds) EXPECT_EQ(parseSolverKind(toString(kind)), kind);
  EXPECT_EQ(toString(SolverKind::eigenLDLT), "eigen-ldlt");
  EXPECT_EQ(toString(SolverKind::eigenLU), "eigen-lu");
  EXPECT_EQ(toString(SolverKind::dense), "dense");
  try {
    parseSolverKind("superlu");
    ADD_FAILURE() << "unknown name accepted";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "'superlu'")) << e.what();
    for (SolverKind kind : kAllKinds) EXPECT_TRUE(contains(e.what(), toString(kind))) << e.what();
  }
}

/// An SPD matrix of n unknowns whose Cholesky factor is one dense supernode (every
/// unknown coupled to every other): B B^T / n + I with B Gaussian, eigenvalues in [1, ~5].
SparseMatrix denseSpd(int n, unsigned seed) {
  const Eigen::MatrixXd b = test::gaussianMatrix(n, n, seed);
  const Eigen::MatrixXd dense = b * b.transpose() / n + Eigen::MatrixXd::Identity(n, n);
  SparseMatrix a = dense.sparseView();
  a.makeCompressed();
  return a;
}

TEST(SparseSolver, CholmodFactorsSmallAndLargeSupernodesToTheDenseSolution) {
  // A grid Laplacian's factor has many small supernodes, a dense matrix's one large
  // supernode (no update to scatter). Each solution is
  // compared with a dense Cholesky solve: both are backward stable and cond <= 121
  // (Laplacian) or about 5 (dense), so they agree to about cond * eps = 3e-14; 1e-12.
  const SparseMatrix matrices[] = {gridLaplacian(10, 0.1), denseSpd(400, 21)};
  for (const SparseMatrix& a : matrices) {
    const Eigen::MatrixXd b = test::gaussianMatrix(a.rows(), 2, 22);
    const Eigen::MatrixXd expected = Eigen::MatrixXd(a).llt().solve(b);
    auto solver = makeSparseSolver(SolverKind::cholmod);
    solver->analyzePattern(a);
    for (int round = 0; round < 2; ++round) {  // the first factorization and a refactorization
      SparseMatrix scaled = a * (1.0 + round);
      solver->factorize(scaled);
      Eigen::MatrixXd x;
      solver->solve(b, x);
      EXPECT_LE((x * (1.0 + round) - expected).norm(), 1e-12 * expected.norm()) << a.rows() << " round " << round;
      for (int c = 0; c < 2; ++c) {
        const Eigen::VectorXd column = solver->solve(Eigen::VectorXd(b.col(c)));  // one-column substitution
        EXPECT_LE((column * (1.0 + round) - expected.col(c)).norm(), 1e-12 * expected.col(c).norm());
      }
    }
  }
}

TEST(SparseSolver, CholmodRefactorizationsAndFreshSolversAgreeBitForBit) {
  // A run resumed from a checkpoint builds a fresh solver where the uninterrupted run
  // refactors its own: both must compute the same factor, bit for bit.
  const SparseMatrix matrices[] = {gridLaplacian(9, 0.3), denseSpd(300, 23)};
  for (const SparseMatrix& a : matrices) {
    const Eigen::VectorXd b = test::gaussianMatrix(a.rows(), 1, 24);
    const SparseMatrix other = a * 3.0;
    auto running = makeSparseSolver(SolverKind::cholmod);
    running->compute(other);
    running->factorize(a);
    auto fresh = makeSparseSolver(SolverKind::cholmod);
    fresh->compute(a);
    const Eigen::VectorXd x = running->solve(b), y = fresh->solve(b);
    EXPECT_EQ((x - y).cwiseAbs().maxCoeff(), 0.0) << a.rows();
  }
}

TEST(SparseSolver, CholmodApproximateSolvesUseASinglePrecisionFactor) {
  // One column: a single-precision copy of the factor. Rounding L to float (6e-8) moves
  // the solution by about cond * 6e-8 <= 121 * 6e-8 = 7e-6; 1e-4. It must differ from the
  // exact solve (else the copy is not in use); several columns solve exactly.
  const SparseMatrix a = gridLaplacian(10, 0.1);
  auto solver = makeSparseSolver(SolverKind::cholmod);
  solver->compute(a);
  const Eigen::MatrixXd b = test::gaussianMatrix(a.rows(), 2, 25);
  Eigen::MatrixXd exact, approximate;
  solver->solve(b.col(0), exact);
  solver->solveApproximately(b.col(0), approximate);
  const double difference = (approximate - exact).norm() / exact.norm();
  EXPECT_LE(difference, 1e-4);
  EXPECT_GT(difference, 1e-12);
  solver->solve(b, exact);
  solver->solveApproximately(b, approximate);
  EXPECT_EQ((approximate - exact).cwiseAbs().maxCoeff(), 0.0);
  // Entries beyond float's range (the matrix scaled by 1e80): the copy would overflow, so
  // approximate solves are exact ones.
  const SparseMatrix huge = a * 1e80;
  solver->factorize(huge);
  solver->solve(b.col(1), exact);
  solver->solveApproximately(b.col(1), approximate);
  EXPECT_EQ((approximate - exact).cwiseAbs().maxCoeff(), 0.0);
}

TEST(SparseSolver, IndependentSolversRunConcurrently) {
  // Two solvers of each SuiteSparse backend on their own threads, each refactorizing
  // repeatedly: any state shared through CHOLMOD or UMFPACK would corrupt a result.
  const SparseMatrix spd[] = {gridLaplacian(12, 0.2), gridLaplacian(11, 0.7)};
  const SparseMatrix lu[] = {unsymmetric(12, 11), unsymmetric(11, 13)};
  struct Job {
    SolverKind kind;
    const SparseMatrix* matrix;
    double residual = 1.0;
  };
  std::vector<Job> jobs = {{SolverKind::cholmod, &spd[0]},
                           {SolverKind::cholmod, &spd[1]},
                           {SolverKind::umfpack, &lu[0]},
                           {SolverKind::umfpack, &lu[1]}};
  std::vector<std::thread> threads;
  for (Job& job : jobs) {
    threads.emplace_back([&job] {
      auto solver = makeSparseSolver(job.kind);
      const Eigen::MatrixXd b = test::gaussianMatrix(job.matrix->rows(), 3, 6);
      Eigen::MatrixXd x;
      job.residual = 0.0;
      for (int round = 0; round < 4; ++round) {
        solver->compute(*job.matrix);
        solver->solve(b, x);
        job.residual = std::max(job.residual, relativeResidual(*job.matrix, x, b));
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (const Job& job : jobs) EXPECT_LT(job.residual, kResidualTolerance) << toString(job.kind);
}

}  // namespace
}  // namespace asyncfem
