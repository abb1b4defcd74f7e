// SPDX-License-Identifier: BSD-3-Clause
// ScopedBlasThreads against the BLAS this process loaded (CHOLMOD's, through sparseSolver).
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <asyncfem/core/threading.hpp>
#include <cstring>

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

}  // namespace
