// SPDX-License-Identifier: BSD-3-Clause
// ScopedBlasThreads against the BLAS this process loaded (CHOLMOD's, through sparseSolver).
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <cstring>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "gridLaplacian.hpp"

namespace {

template <class Function>
Function* lookUp(const char* name) {
  void* address = ::dlsym(RTLD_DEFAULT, name);
  Function* function = nullptr;
  if (address != nullptr) std::memcpy(&function, &address, sizeof(function));
  return function;
}

// With OpenBLAS in the process: the count is held at the requested one while the guard
// lives and the earlier count returns after it; a guard asking for more than the current
// count changes nothing. With another BLAS, or OpenBLAS on one core, there is nothing to
// hold (reported as skipped).
TEST(ScopedBlasThreads, HoldsOpenBlasToTheCountWhileAlive) {
  using Get = int();
  using Set = void(int);
  Get* get = lookUp<Get>("openblas_get_num_threads");
  Set* set = lookUp<Set>("openblas_set_num_threads");
  if (get == nullptr || set == nullptr) GTEST_SKIP() << "the BLAS of this build is not OpenBLAS";
  const int original = get();
  set(2);
  if (get() < 2) {  // OpenBLAS started with one thread (one core): no count to hold down
    set(original);
    GTEST_SKIP() << "OpenBLAS runs one thread here";
  }
  {
    const asyncfem::ScopedBlasThreads one(1);
    EXPECT_EQ(get(), 1);
    {
      const asyncfem::ScopedBlasThreads more(4);  // above the count: left as it is
      EXPECT_EQ(get(), 1);
    }
    EXPECT_EQ(get(), 1);
  }
  EXPECT_EQ(get(), 2);
  {
    // hold(false) gives the earlier count back for the large calls, hold(true) takes it
    // again; the destructor restores it whichever state the guard was left in.
    asyncfem::ScopedBlasThreads toggled(1);
    EXPECT_EQ(get(), 1);
    toggled.hold(false);
    EXPECT_EQ(get(), 2);
    toggled.hold(false);
    EXPECT_EQ(get(), 2);
    toggled.hold(true);
    EXPECT_EQ(get(), 1);
  }
  EXPECT_EQ(get(), 2);
  set(original);
}

// What OpenBLAS's thread count changes in the last bits of the calls a factorization and
// its solves make: recorded as test properties (dpotrfDifference, dgemmDifference, ...; on
// the 2-core machine dpotrf 7e-15, dgemm 1.4e-14, dtrsm and dsyrk 0), so that a reader of
// the XML output sees why factorBlasThreads() is a setting and not a reading of the load.
// Each call must have done something (a non-zero result).
TEST(BlasResults, TheThreadCountsDifferencesAreRecorded) {
  using Get = int();
  using Set = void(int);
  using Potrf = void(const char*, const int*, double*, const int*, int*);
  using Trsm = void(const char*, const char*, const char*, const char*, const int*, const int*, const double*,
                    const double*, const int*, double*, const int*);
  using Syrk = void(const char*, const char*, const int*, const int*, const double*, const double*, const int*,
                    const double*, double*, const int*);
  using Gemm = void(const char*, const char*, const int*, const int*, const int*, const double*, const double*,
                    const int*, const double*, const int*, const double*, double*, const int*);
  Get* get = lookUp<Get>("openblas_get_num_threads");
  Set* set = lookUp<Set>("openblas_set_num_threads");
  Potrf* potrf = lookUp<Potrf>("dpotrf_");
  Trsm* trsm = lookUp<Trsm>("dtrsm_");
  Syrk* syrk = lookUp<Syrk>("dsyrk_");
  Gemm* gemm = lookUp<Gemm>("dgemm_");
  if (get == nullptr || set == nullptr) GTEST_SKIP() << "the BLAS of this build is not OpenBLAS";
  ASSERT_TRUE(potrf != nullptr && trsm != nullptr && syrk != nullptr && gemm != nullptr);
  const int original = get();
  // A supernode of 300 columns over 900 rows: an SPD diagonal block and a random block
  // below it; 48 right-hand sides for the solve's update (dgemm).
  const int columns = 300, rows = 900, below = rows - columns, k = 48;
  std::mt19937 generator(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::MatrixXd block(rows, columns), solution(columns, k);
  for (Eigen::Index i = 0; i < block.size(); ++i) block.data()[i] = unit(generator);
  for (Eigen::Index i = 0; i < solution.size(); ++i) solution.data()[i] = unit(generator);
  const Eigen::MatrixXd square = block.topRows(columns);
  block.topRows(columns) = square * square.transpose() + columns * Eigen::MatrixXd::Identity(columns, columns);
  const double one = 1.0, zero = 0.0, minusOne = -1.0;
  const auto onThreads = [&](int threads, Eigen::MatrixXd values, int call) {
    set(threads);
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(call == 3 ? below : below, call == 3 ? k : below);
    int info = 0;
    if (call == 0) potrf("L", &columns, values.data(), &rows, &info);
    if (call == 1)
      trsm("R", "L", "T", "N", &below, &columns, &one, values.data(), &rows, values.data() + columns, &rows);
    if (call == 2) syrk("L", "N", &below, &columns, &one, values.data() + columns, &rows, &zero, out.data(), &below);
    if (call == 3)
      gemm("N", "N", &below, &k, &columns, &minusOne, values.data() + columns, &rows, solution.data(), &columns, &one,
           out.data(), &below);
    EXPECT_EQ(info, 0);
    return call == 2 ? Eigen::MatrixXd(out.triangularView<Eigen::Lower>()) : call == 3 ? out : values;
  };
  Eigen::MatrixXd input = block;
  const char* names[] = {"dpotrf", "dtrsm", "dsyrk", "dgemm"};
  for (int call = 0; call < 4; ++call) {
    const Eigen::MatrixXd single = onThreads(1, input, call);
    const Eigen::MatrixXd threaded = onThreads(2, input, call);
    ::testing::Test::RecordProperty(std::string(names[call]) + "Difference",
                                    std::to_string((single - threaded).cwiseAbs().maxCoeff()));
    EXPECT_GT(single.cwiseAbs().maxCoeff(), 0.0) << names[call];
    if (call < 2) input = single;  // the next call's input: this one's result
  }
  set(original);
}

// Whatever thread count the BLAS has when a factorization or a solve starts (the machine's
// cores, or one), CHOLMOD and the supernodal factorization give the same bits: they run the
// BLAS on factorBlasThreads() (1 here). A 24^3 grid Laplacian (13,824 unknowns; its top
// separators are supernodes of about 600 columns, above kThreadedBlasWork) with 32
// right-hand sides and with one.
TEST(BlasResults, FactorAndSolveDoNotDependOnTheBlasCountTheyFind) {
  using Get = int();
  using Set = void(int);
  Get* get = lookUp<Get>("openblas_get_num_threads");
  Set* set = lookUp<Set>("openblas_set_num_threads");
  if (get == nullptr || set == nullptr) GTEST_SKIP() << "the BLAS of this build is not OpenBLAS";
  ASSERT_EQ(asyncfem::factorBlasThreads(), 1) << "run without ASYNCFEM_BLAS_THREADS";
  const int original = get();
  const int size = 24 * 24 * 24;
  const Eigen::SparseMatrix<double> matrix = asyncfem::test::gridLaplacian(24, 0.5);
  std::mt19937 generator(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::MatrixXd rhs(size, 32);
  for (Eigen::Index i = 0; i < rhs.size(); ++i) rhs.data()[i] = unit(generator);
  const auto solveOn = [&](int threads) {
    set(threads);
    auto solver = asyncfem::makeSparseSolver(asyncfem::SolverKind::cholmod);
    solver->compute(matrix);
    Eigen::MatrixXd many, one;
    solver->solve(rhs, many);
    solver->solve(rhs.col(0), one);
    return std::make_pair(many, one);
  };
  const auto onTwo = solveOn(2);
  const auto onOne = solveOn(1);
  set(original);
  EXPECT_GT(onOne.first.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((onTwo.first - onOne.first).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((onTwo.second - onOne.second).cwiseAbs().maxCoeff(), 0.0);
}

// ASYNCFEM_BLAS_THREADS: 1 when unset or empty, its value when a positive integer, an error
// naming it otherwise.
TEST(BlasResults, TheThreadSettingIsReadAndChecked) {
  const char* saved = std::getenv("ASYNCFEM_BLAS_THREADS");
  const std::string previous = saved != nullptr ? saved : "";
  ::unsetenv("ASYNCFEM_BLAS_THREADS");
  EXPECT_EQ(asyncfem::factorBlasThreads(), 1);
  ::setenv("ASYNCFEM_BLAS_THREADS", "3", 1);
  EXPECT_EQ(asyncfem::factorBlasThreads(), 3);
  for (const char* bad : {"0", "-2", "two", "2x", "100000"}) {
    ::setenv("ASYNCFEM_BLAS_THREADS", bad, 1);
    try {
      (void)asyncfem::factorBlasThreads();
      ADD_FAILURE() << bad << " accepted";
    } catch (const asyncfem::Error& error) {
      EXPECT_NE(std::string(error.what()).find("ASYNCFEM_BLAS_THREADS: expected a positive integer"), std::string::npos)
          << error.what();
    }
  }
  if (saved != nullptr) {
    ::setenv("ASYNCFEM_BLAS_THREADS", previous.c_str(), 1);
  } else {
    ::unsetenv("ASYNCFEM_BLAS_THREADS");
  }
}

}  // namespace
