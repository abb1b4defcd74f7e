// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace asyncfem {

/// Makes idle OpenMP threads sleep instead of spinning, for command-line programs.
///
/// The element loops run on OpenMP threads and CHOLMOD's supernodal kernels on the BLAS's
/// own threads. With the OpenMP runtime's default policy, threads that just left a
/// parallel loop keep spinning and take the cores the BLAS threads need: on a 2-core
/// machine a numeric factorization was measured 25x slower. The policy can only be set
/// through the environment before the runtime starts, so when OMP_WAIT_POLICY is unset
/// this sets it to "passive" and re-executes the program once (same arguments). A user's
/// own OMP_WAIT_POLICY is respected. Call it first thing in main().
inline void preferPassiveThreadWaiting(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  ::setenv("OMP_WAIT_POLICY", "passive", 1);
  ::execv("/proc/self/exe", argv);
  // execv only returns on failure (no /proc): carry on with the default policy.
}

/// Whether fewer than `wanted` cores are free now besides the calling thread: the tasks
/// the kernel counts as running or ready to run (/proc/loadavg's fourth field, "R/T",
/// which counts the caller) against the online cores. An instant's reading, for choosing a
/// thread count just before a large computation; false where /proc/loadavg is not there.
inline bool coresAreBusy(int wanted) {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen, tasks;
  if (!(in >> one >> five >> fifteen >> tasks)) return false;
  const long running = std::strtol(tasks.c_str(), nullptr, 10);
  const long cores = ::sysconf(_SC_NPROCESSORS_ONLN);
  if (running < 1 || cores < 1) return false;
  return cores - (running - 1) < wanted;
}

/// While alive, the BLAS runs each of its calls on at most `threads` threads of its own, then
/// its previous count returns. For code that calls the BLAS (CHOLMOD's supernodal solves
/// and factorizations) from several OpenMP threads at once: each call would otherwise start
/// a team of the BLAS's threads on the same cores, which then compete with the OpenMP
/// threads (on 2 cores the corotational dinosaur's asynchronous large step took 44 to 48 ms
/// on average, 29 ms with the BLAS held to one thread; docs/benchmarks.md). It acts on OpenBLAS,
/// found in the process at run time (openblas_set_num_threads); with another BLAS it does
/// nothing. The count is process-wide: create it in the thread that starts the parallel
/// region, not inside it.
class ScopedBlasThreads {
 public:
  explicit ScopedBlasThreads(int threads) : threads_(threads) {
    int (*get)() = nullptr;
    symbol("openblas_get_num_threads", get);
    symbol("openblas_set_num_threads", set_);
    if (get == nullptr || set_ == nullptr) {
      set_ = nullptr;
      return;
    }
    previous_ = get();
    hold(true);
  }
  ~ScopedBlasThreads() { hold(false); }
  /// The BLAS's thread count before this guard (0 where the BLAS is not OpenBLAS).
  int previousCount() const { return previous_; }
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

  /// true: the BLAS runs on at most the constructor's count (as after construction);
  /// false: on its previous count again, until the next hold(true). For a sequence of calls
  /// of which only the largest gain from the BLAS's threads (a supernodal factorization).
  void hold(bool held) {
    if (set_ == nullptr || previous_ <= threads_ || held == held_) return;  // nothing to change
    set_(held ? threads_ : previous_);
    held_ = held;
  }

 private:
  // A function of the process's libraries by name, or null (copied from dlsym's object
  // pointer, which ISO C++ does not convert to a function pointer directly).
  template <class Function>
  static void symbol(const char* name, Function& function) {
    void* address = ::dlsym(RTLD_DEFAULT, name);
    function = nullptr;
    if (address != nullptr) std::memcpy(&function, &address, sizeof(function));
  }

  void (*set_)(int) = nullptr;
  int threads_ = 1;
  int previous_ = 0;
  bool held_ = false;
};

}  // namespace asyncfem
