// SPDX-License-Identifier: BSD-3-Clause
// ScopedBlasThreads against the BLAS this process loaded (CHOLMOD's, through sparseSolver).
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <asyncfem/core/threading.hpp>
#include <cstring>
#include <random>
#include <string>

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

// The supernodal factorization runs a large supernode's dtrsm and dsyrk on the BLAS's
// threads when the cores are free and on one thread when they are busy (coresAreBusy), so
// these must give the same bits on one thread and on two (were they to differ, a run's
// trajectory would depend on the machine's load, and a resumed run could differ from the
// uninterrupted one). OpenBLAS's dpotrf does not (its threaded blocking sums in another
// order: 7e-15 apart here, recorded as dpotrfDifference), so it always runs on one thread.
TEST(BlasResults, TrsmAndSyrkGiveTheSameBitsOnOneThreadAndTwo) {
  using Get = int();
  using Set = void(int);
  using Potrf = void(const char*, const int*, double*, const int*, int*);
  using Trsm = void(const char*, const char*, const char*, const char*, const int*, const int*, const double*,
                    const double*, const int*, double*, const int*);
  using Syrk = void(const char*, const char*, const int*, const int*, const double*, const double*, const int*,
                    const double*, double*, const int*);
  Get* get = lookUp<Get>("openblas_get_num_threads");
  Set* set = lookUp<Set>("openblas_set_num_threads");
  Potrf* potrf = lookUp<Potrf>("dpotrf_");
  Trsm* trsm = lookUp<Trsm>("dtrsm_");
  Syrk* syrk = lookUp<Syrk>("dsyrk_");
  if (get == nullptr || set == nullptr) GTEST_SKIP() << "the BLAS of this build is not OpenBLAS";
  ASSERT_TRUE(potrf != nullptr && trsm != nullptr && syrk != nullptr);
  const int original = get();
  // A supernode of 300 columns over 900 rows (work 2.7e7 > kThreadedBlasWork): an SPD
  // diagonal block and a random block below it.
  const int columns = 300, rows = 900, below = rows - columns;
  std::mt19937 generator(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::MatrixXd block(rows, columns);
  for (Eigen::Index i = 0; i < block.size(); ++i) block.data()[i] = unit(generator);
  const Eigen::MatrixXd square = block.topRows(columns);
  block.topRows(columns) = square * square.transpose() + columns * Eigen::MatrixXd::Identity(columns, columns);
  // Each call on the same input, on one thread and on two.
  const double one = 1.0, zero = 0.0;
  const auto onThreads = [&](int threads, Eigen::MatrixXd values, int call) {
    set(threads);
    Eigen::MatrixXd update = Eigen::MatrixXd::Zero(below, below);
    int info = 0;
    if (call == 0) potrf("L", &columns, values.data(), &rows, &info);
    if (call == 1)
      trsm("R", "L", "T", "N", &below, &columns, &one, values.data(), &rows, values.data() + columns, &rows);
    if (call == 2) syrk("L", "N", &below, &columns, &one, values.data() + columns, &rows, &zero, update.data(), &below);
    EXPECT_EQ(info, 0);
    return call == 2 ? Eigen::MatrixXd(update.triangularView<Eigen::Lower>()) : values;
  };
  Eigen::MatrixXd input = block;
  const char* names[] = {"dpotrf", "dtrsm", "dsyrk"};
  for (int call = 0; call < 3; ++call) {
    const Eigen::MatrixXd single = onThreads(1, input, call);
    const Eigen::MatrixXd threaded = onThreads(2, input, call);
    const double difference = (single - threaded).cwiseAbs().maxCoeff();
    if (call == 0) {
      ::testing::Test::RecordProperty("dpotrfDifference", std::to_string(difference));
    } else {
      EXPECT_EQ(difference, 0.0) << names[call];
    }
    EXPECT_GT(single.cwiseAbs().maxCoeff(), 0.0) << names[call];
    if (call < 2) input = single;  // the next call's input: this one's result
  }
  set(original);
}

}  // namespace
