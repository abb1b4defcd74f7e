// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sparseSolver/factorReusingSolver.hpp>
#include <random>
#include <string>
#include <vector>

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

// 3D 7-point Laplacian on a k^3 grid plus a diagonal: SPD, full storage; the diagonal
// entries vary with `variation` so that a sequence of matrices drifts away from the first.
SparseMatrix driftingMatrix(int k, double variation) {
  const int n = k * k * k;
  std::vector<Eigen::Triplet<double>> entries;
  const auto index = [k](int x, int y, int z) { return x + (k * (y + (k * z))); };
  for (int z = 0; z < k; ++z) {
    for (int y = 0; y < k; ++y) {
      for (int x = 0; x < k; ++x) {
        const int i = index(x, y, z);
        entries.emplace_back(i, i, 6.5 + (variation * ((i % 7) - 3)));
        if (x + 1 < k)
          entries.emplace_back(i, index(x + 1, y, z), -1.0), entries.emplace_back(index(x + 1, y, z), i, -1.0);
        if (y + 1 < k)
          entries.emplace_back(i, index(x, y + 1, z), -1.0), entries.emplace_back(index(x, y + 1, z), i, -1.0);
        if (z + 1 < k)
          entries.emplace_back(i, index(x, y, z + 1), -1.0), entries.emplace_back(index(x, y, z + 1), i, -1.0);
      }
    }
  }
  SparseMatrix a(n, n);
  a.setFromTriplets(entries.begin(), entries.end());
  a.makeCompressed();
  return a;
}

Eigen::VectorXd randomVector(Eigen::Index n, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = entry(random);
  return v;
}

TEST(FactorReusingSolver, FirstSolveIsExactAndLaterOnesMeetTheTolerance) {
  FactorReuseOptions options;
  options.relativeTolerance = 1e-10;
  options.amortize = false;  // keep the first factor throughout
  FactorReusingSolver solver(SolverKind::cholmod, options);
  SparseMatrix a = driftingMatrix(8, 0.0);
  solver.setMatrix(a);
  const Eigen::VectorXd b = randomVector(a.rows(), 1);
  Eigen::VectorXd x;
  solver.solve(b, x);
  // A direct Cholesky solve of this well-conditioned (cond < 10) matrix: rounding only.
  EXPECT_LE((a * x - b).norm(), 1e-13 * b.norm());
  EXPECT_EQ(solver.stats().exactSolves, 1);
  EXPECT_EQ(solver.stats().refactorizations, 1);
  // Drift the values by a few percent per step: PCG with the first factor.
  for (int step = 1; step <= 4; ++step) {
    a = driftingMatrix(8, 0.01 * step);
    solver.setMatrix(a);
    solver.solve(b, x);
    EXPECT_LE((a * x - b).norm(), options.relativeTolerance * b.norm()) << "step " << step;
    EXPECT_GT(solver.stats().lastIterations, 0);
  }
  EXPECT_EQ(solver.stats().refactorizations, 1);
  EXPECT_GT(solver.stats().pcgIterations, 4);
}

TEST(FactorReusingSolver, GrowingIterationCountsTriggerARefactorization) {
  FactorReuseOptions options;
  options.relativeTolerance = 1e-10;
  options.refactorAfterIterations = 4;
  FactorReusingSolver solver(SolverKind::cholmod, options);
  const Eigen::VectorXd b = randomVector(512, 2);
  Eigen::VectorXd x;
  long long refactorizationsSeen = 0;
  for (int step = 0; step < 12; ++step) {
    // The diagonal drifts by up to 0.45 (of 6.5) over the run, keeping A SPD (its
    // smallest eigenvalue is above 0.5 - 0.45): the first factor soon needs many iterations.
    const SparseMatrix a = driftingMatrix(8, 0.0125 * step);
    solver.setMatrix(a);
    solver.solve(b, x);
    EXPECT_LE((a * x - b).norm(), options.relativeTolerance * b.norm()) << "step " << step;
    EXPECT_LE(solver.stats().lastIterations, options.maxIterations);
    refactorizationsSeen = solver.stats().refactorizations;
  }
  EXPECT_GT(refactorizationsSeen, 1);   // it did refactor
  EXPECT_LT(refactorizationsSeen, 12);  // but not every step
}

TEST(FactorReusingSolver, AmortisationRefactorsWhenFactorizationsAreCheap) {
  const Eigen::VectorXd b = randomVector(512, 4);
  Eigen::VectorXd x;
  std::vector<long long> refactorizations;
  // A factorization that costs as much as 1 PCG iteration is redone after every PCG
  // solve (any iteration count exceeds the average); one that costs 1e4 is never redone
  // over 8 small drifts (the iteration counts stay far below the average).
  for (const double cost : {1.0, 1e4}) {
    FactorReuseOptions options;
    options.relativeTolerance = 1e-10;
    options.factorCostInIterations = cost;
    FactorReusingSolver solver(SolverKind::cholmod, options);
    for (int step = 0; step < 8; ++step) {
      const SparseMatrix a = driftingMatrix(8, 0.005 * step);
      solver.setMatrix(a);
      solver.solve(b, x);
      EXPECT_LE((a * x - b).norm(), options.relativeTolerance * b.norm());
    }
    EXPECT_EQ(solver.stats().factorCostInIterations, cost);
    refactorizations.push_back(solver.stats().refactorizations);
  }
  EXPECT_EQ(refactorizations[0], 4);  // factor, PCG, factor, PCG, ...
  EXPECT_EQ(refactorizations[1], 1);
}

TEST(FactorReusingSolver, AGoodInitialGuessSavesIterationsAndABadOneIsIgnored) {
  FactorReuseOptions options;
  options.relativeTolerance = 1e-10;
  options.amortize = false;
  FactorReusingSolver solver(SolverKind::cholmod, options);
  const SparseMatrix first = driftingMatrix(8, 0.0);
  const Eigen::VectorXd b = randomVector(first.rows(), 5);
  Eigen::VectorXd exact;
  solver.setMatrix(first);
  solver.solve(b, exact);
  const SparseMatrix second = driftingMatrix(8, 0.02);
  solver.setMatrix(second);
  Eigen::VectorXd fromZero;
  solver.solve(b, fromZero);
  const int iterationsFromZero = solver.stats().lastIterations;
  // The first system's solution is close to the second's: fewer iterations, same tolerance.
  Eigen::VectorXd fromGuess = exact;
  solver.solve(b, fromGuess, fromGuess);
  EXPECT_LT(solver.stats().lastIterations, iterationsFromZero);
  EXPECT_LE((second * fromGuess - b).norm(), options.relativeTolerance * b.norm());
  // A guess worse than 0 (residual above |b|) is not used: the count is that from 0.
  const Eigen::VectorXd bad = -10.0 * exact;
  Eigen::VectorXd fromBad;
  solver.solve(b, bad, fromBad);
  EXPECT_EQ(solver.stats().lastIterations, iterationsFromZero);
  EXPECT_LE((second * fromBad - b).norm(), options.relativeTolerance * b.norm());
}

TEST(FactorReusingSolver, AnAbandonedSolveFallsBackToAnExactOne) {
  FactorReuseOptions options;
  options.relativeTolerance = 1e-14;
  options.maxIterations = 1;  // one iteration can never reach 1e-14 on a changed matrix
  FactorReusingSolver solver(SolverKind::cholmod, options);
  const SparseMatrix first = driftingMatrix(6, 0.0);
  solver.setMatrix(first);
  const Eigen::VectorXd b = randomVector(first.rows(), 3);
  Eigen::VectorXd x;
  solver.solve(b, x);
  const SparseMatrix second = driftingMatrix(6, 0.1);
  solver.setMatrix(second);
  solver.solve(b, x);
  EXPECT_EQ(solver.stats().abandonedSolves, 1);
  EXPECT_EQ(solver.stats().refactorizations, 2);
  EXPECT_LE((second * x - b).norm(), 1e-13 * b.norm());  // exact solve: rounding only
}

// PCG to 1e-10 with the first factor kept throughout, preconditioned in single or double precision.
FactorReuseOptions keepFirstFactor(bool singlePrecision) {
  FactorReuseOptions options;
  options.relativeTolerance = 1e-10;
  options.amortize = false;
  options.singlePrecisionPreconditioner = singlePrecision;
  return options;
}

// The single-precision copy of CHOLMOD's supernodal factor is A^-1 to about 1e-7: with the
// factor's own matrix (set again, so the next solve runs PCG) one PCG iteration brings the
// residual to about 1e-7 |b| and a second below 1e-10, where the double factor needs one.
// A copy with a wrong permutation, supernode layout or triangle would need many more.
TEST(FactorReusingSolver, SinglePrecisionCopyIsTheFactorToSinglePrecision) {
  const SparseMatrix a = driftingMatrix(8, 0.0);
  const Eigen::VectorXd b = randomVector(a.rows(), 5);
  std::vector<int> iterations;
  for (const bool single : {true, false}) {
    const FactorReuseOptions options = keepFirstFactor(single);
    FactorReusingSolver solver(SolverKind::cholmod, options);
    Eigen::VectorXd x;
    solver.setMatrix(a);
    solver.solve(b, x);  // exact, the double factor
    solver.setMatrix(a);
    solver.solve(b, x);
    EXPECT_EQ(solver.stats().singlePrecisionPreconditioner, single);
    EXPECT_EQ(solver.stats().refactorizations, 1);
    EXPECT_LE((a * x - b).norm(), options.relativeTolerance * b.norm());
    iterations.push_back(solver.stats().lastIterations);
  }
  EXPECT_EQ(iterations[0], 2);  // single precision
  EXPECT_EQ(iterations[1], 1);  // double
}

// On a drifting sequence both preconditioners reach the tolerance in about as many
// iterations, and the solutions agree to the tolerance times cond(A) (< 10 here).
TEST(FactorReusingSolver, SinglePrecisionPreconditionerConvergesLikeTheDoubleFactor) {
  const Eigen::VectorXd b = randomVector(512, 6);
  std::vector<Eigen::VectorXd> solutions[2];
  long long totalIterations[2] = {0, 0};
  for (const bool single : {true, false}) {
    const FactorReuseOptions options = keepFirstFactor(single);
    FactorReusingSolver solver(SolverKind::cholmod, options);
    Eigen::VectorXd x;
    for (int step = 0; step < 6; ++step) {
      const SparseMatrix a = driftingMatrix(8, 0.01 * step);
      solver.setMatrix(a);
      solver.solve(b, x);
      EXPECT_LE((a * x - b).norm(), options.relativeTolerance * b.norm()) << "step " << step;
      solutions[single ? 0 : 1].push_back(x);
    }
    EXPECT_EQ(solver.stats().abandonedSolves, 0);
    totalIterations[single ? 0 : 1] = solver.stats().pcgIterations;
  }
  // Five PCG solves: at most one extra iteration each.
  EXPECT_LE(totalIterations[0], totalIterations[1] + 5);
  for (std::size_t step = 0; step < solutions[0].size(); ++step) {
    EXPECT_LE((solutions[0][step] - solutions[1][step]).norm(), 1e-8 * solutions[1][step].norm()) << "step " << step;
  }
}

// A system whose factor's entries are far beyond float's range (A scaled by 1e80: L's
// entries near 1e40, above float's 3.4e38) cannot be copied to single precision: the copy's
// solve is not finite, so it is dropped and PCG runs with the double factor. (The check
// compares the copy's solve of a fixed vector with the double factor's: a tridiagonal
// chain with cond(A) = 6e6 still agreed to 2.4e-7, so conditioning alone rarely drops it.)
TEST(FactorReusingSolver, SinglePrecisionCopyIsDroppedWhereFloatCannotHoldTheFactor) {
  const SparseMatrix a = 1e80 * driftingMatrix(6, 0.0);
  FactorReusingSolver solver(SolverKind::cholmod, keepFirstFactor(true));
  solver.setMatrix(a);
  EXPECT_FALSE(solver.stats().singlePrecisionPreconditioner);
  const Eigen::VectorXd b = 1e80 * randomVector(a.rows(), 7);
  Eigen::VectorXd x;
  solver.solve(b, x);
  solver.setMatrix(a);
  solver.solve(b, x);
  EXPECT_EQ(solver.stats().lastIterations, 1);  // the double factor of A itself
  EXPECT_EQ(solver.stats().abandonedSolves, 0);
  EXPECT_LE((a * x - b).norm(), 1e-10 * b.norm());
  // The same system at its natural scale keeps the copy.
  FactorReusingSolver natural(SolverKind::cholmod, keepFirstFactor(true));
  natural.setMatrix(driftingMatrix(6, 0.0));
  EXPECT_TRUE(natural.stats().singlePrecisionPreconditioner);
}

// The default price of a factorization: max(30, factorFlops / (6 solveFlopsPerRhs)) in PCG
// iterations with the single-precision copy, max(20, ...) with the double factor or a
// solver without a supernodal factor (Eigen's LDLT). Oracles independent of the solver's
// flop counts: the 512-unknown grid's factor costs a few solves, so each floor is the price;
// a dense n x n factor costs n^3/3 flops and the two triangular solves 2 n^2, so its price
// is n/36 to leading order (n = 1440: 40, above both floors).
TEST(FactorReusingSolver, DefaultFactorCostHasAFloorPerPreconditioner) {
  const SparseMatrix a = driftingMatrix(8, 0.0);
  struct Case {
    SolverKind kind;
    bool single;
    bool expectSingle;
    double floor;
  };
  for (const Case& c : {Case{SolverKind::cholmod, true, true, 30.0}, Case{SolverKind::cholmod, false, false, 20.0},
                        Case{SolverKind::eigenLDLT, true, false, 20.0}}) {
    FactorReuseOptions options;
    options.singlePrecisionPreconditioner = c.single;
    FactorReusingSolver solver(c.kind, options);
    solver.setMatrix(a);
    EXPECT_EQ(solver.stats().singlePrecisionPreconditioner, c.expectSingle) << toString(c.kind);
    EXPECT_EQ(solver.stats().factorCostInIterations, c.floor) << toString(c.kind);
  }
}

TEST(FactorReusingSolver, DefaultFactorCostOfADenseFactorIsNOver36) {
  // (n + 1) I + ones: symmetric positive definite with every entry non-zero.
  const int n = 1440;
  const Eigen::MatrixXd dense = Eigen::MatrixXd::Constant(n, n, 1.0) + (n + 1.0) * Eigen::MatrixXd::Identity(n, n);
  const SparseMatrix a = dense.sparseView();
  ASSERT_EQ(a.nonZeros(), static_cast<Eigen::Index>(n) * n);
  for (const bool single : {true, false}) {
    FactorReuseOptions options;
    options.singlePrecisionPreconditioner = single;
    FactorReusingSolver solver(SolverKind::cholmod, options);
    solver.setMatrix(a);
    // The terms of lower order in n (n^2/2 flops in the factor, 2 n in the solves) move
    // the price by about 1.5/n relative (0.1%); 2% leaves room for how a library counts them.
    EXPECT_NEAR(solver.stats().factorCostInIterations, n / 36.0, 0.02 * n / 36.0) << "single " << single;
  }
}

// A solver restored from another's rule state and the matrix of its kept factor continues
// exactly as that one does: the same solutions bit for bit, the same refactorizations.
TEST(FactorReusingSolver, RestoredRuleStateContinuesBitForBit) {
  std::vector<SparseMatrix> matrices;
  for (int k = 0; k < 24; ++k) matrices.push_back(driftingMatrix(6, 0.02 * k));
  FactorReusingSolver whole;
  std::vector<FactorReuseRuleState> states;
  std::vector<int> factored;  // the matrix of the factor kept after each solve
  std::vector<Eigen::VectorXd> solutions;
  int lastFactored = -1;
  for (int k = 0; k < 24; ++k) {
    const long long before = whole.stats().refactorizations;
    whole.setMatrix(matrices[static_cast<std::size_t>(k)]);
    Eigen::VectorXd x;
    whole.solve(randomVector(matrices[0].rows(), static_cast<unsigned>(k)), x);
    if (whole.stats().refactorizations != before) lastFactored = k;
    states.push_back(whole.ruleState());
    factored.push_back(lastFactored);
    solutions.push_back(x);
  }
  EXPECT_GT(whole.stats().pcgIterations, 0);
  EXPECT_GT(whole.stats().refactorizations, 1);
  for (int k = 0; k + 1 < 24; ++k) {
    const FactorReuseRuleState& state = states[static_cast<std::size_t>(k)];
    FactorReusingSolver resumed;
    const bool needsMatrix = state.hasFactor && !state.refactorPending;
    SparseMatrix kept = matrices[static_cast<std::size_t>(factored[static_cast<std::size_t>(k)])];
    resumed.restoreRuleState(state, needsMatrix ? &kept : nullptr);
    EXPECT_EQ(resumed.stats().refactorizations, needsMatrix ? 1 : 0);
    for (int j = k + 1; j < 24; ++j) {
      resumed.setMatrix(matrices[static_cast<std::size_t>(j)]);
      Eigen::VectorXd x;
      resumed.solve(randomVector(matrices[0].rows(), static_cast<unsigned>(j)), x);
      ASSERT_TRUE(x == solutions[static_cast<std::size_t>(j)]) << "restored after solve " << k << ", solve " << j;
    }
  }
  FactorReusingSolver refused;
  FactorReuseRuleState state = states.back();
  state.refactorPending = false;
  EXPECT_THROW(refused.restoreRuleState(state, nullptr), Error);
  state.cycleSolves = -1;
  EXPECT_THROW(refused.restoreRuleState(state, &matrices[0]), Error);
}

TEST(FactorReusingSolver, MisuseIsReportedClearly) {
  EXPECT_THROW(FactorReusingSolver(SolverKind::cholmod, FactorReuseOptions{1.5, 10, 8, 3.0, 0.0, true}), Error);
  EXPECT_THROW(FactorReusingSolver(SolverKind::cholmod, FactorReuseOptions{1e-8, 0, 8, 3.0, 0.0, true}), Error);
  FactorReusingSolver solver;
  Eigen::VectorXd x;
  try {
    solver.solve(Eigen::VectorXd::Ones(3), x);
    FAIL() << "no exception";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("before setMatrix"), std::string::npos) << error.what();
  }
  const SparseMatrix a = driftingMatrix(3, 0.0);
  solver.setMatrix(a);
  EXPECT_THROW(solver.solve(Eigen::VectorXd::Ones(5), x), Error);
}

}  // namespace
}  // namespace asyncfem
